"""The ``piezobearing`` console script.

``piezobearing diagnose MEASUREMENT.csv --out DIR [--config FILE]``
    Hold the configured model against a calibration record: fit, residual
    tests, effect ranking, stepwise selection, verdict; writes
    DIR/diagnosis.json, DIR/report.md, DIR/figures/ and DIR/diagnosis.npz.

``piezobearing validate FILE [--config FILE]``
    Check a calibration CSV (time_s, force_N, voltage_V) as the workflow
    does before any job runs (file checks, at least two impulses, voltage
    polarity); prints ``OK`` and a summary, or the one-line problem (exit
    status 1).

A user error (bad file, bad config, unknown effect) prints one line and
exits with status 1, without a traceback.
"""

from __future__ import annotations

import argparse
import sys


def _fail(msg: str) -> int:
    print(f"piezobearing: {msg}", file=sys.stderr)
    return 1


def _validate(args) -> int:
    from . import config as cfg
    from .io import MeasurementError
    from .stages.calibration import load_record

    try:
        config = cfg.load(args.config) if args.config else cfg.load()
    except (cfg.ConfigError, OSError) as e:
        return _fail(str(e))
    if args.resample_to_uniform:
        config["calibration"]["resample_to_uniform"] = True
    try:  # the same checks as the workflow's, so that OK here means the workflow accepts the file
        m, imps = load_record(args.file, config)
    except MeasurementError as e:
        return _fail(str(e))
    print(
        f"OK: {args.file}: {m.time_s.size} rows, {m.sample_rate_Hz:.6g} Hz, "
        f"{m.time_s[-1] - m.time_s[0]:.6g} s, {len(imps)} impulses"
    )
    return 0


def _diagnose(args) -> int:
    from tqdm import tqdm

    from . import config as cfg
    from .diagnosis.calibration.effects import CATALOGUE, EffectError
    from .io import MeasurementError
    from .stages.diagnostics import diagnose

    try:
        config = cfg.load(args.config) if args.config else cfg.load()
    except (cfg.ConfigError, OSError) as e:
        return _fail(str(e))
    config["calibration"]["measurement"] = args.measurement
    n = (
        2
        + len(config["model"]["effects"])
        + sum(
            len(CATALOGUE) - len(config["model"]["effects"]) - k
            for k in range(config["diagnostics"]["max_steps"])
        )
    )
    bar = tqdm(total=n, desc="diagnose", unit="fit", file=sys.stderr, disable=args.quiet)

    def progress(msg: str) -> None:
        bar.set_postfix_str(msg[-40:])
        bar.update(1)

    try:
        d = diagnose(args.measurement, args.out, config, progress)
    except (MeasurementError, EffectError) as e:
        bar.close()
        return _fail(str(e))
    bar.update(bar.total - bar.n)
    bar.close()
    base, final = d["baseline"], d["final"]
    print(f"baseline NRMSE {100 * base['nrmse']:.2f}% (noise floor {100 * base['noise_floor_nrmse']:.2f}%)")
    conf = d["configured"]
    if conf["effects"]:
        print(
            f"configured model (baseline + {' + '.join(conf['effects'])}) NRMSE {100 * conf['nrmse']:.2f}% "
            f"(noise floor {100 * conf['noise_floor_nrmse']:.2f}%)"
        )
    if d["winner"]:
        print(f"most likely missing: {d['winner']['effect']} ({d['winner']['summary']})")
    print(
        f"selected: {', '.join(d['selected']) or 'nothing'}; final NRMSE {100 * final['nrmse']:.2f}% "
        f"(floor {100 * final['noise_floor_nrmse']:.2f}%)"
    )
    print(f"verdict: {d['verdict']}")
    for f in d["unexplained"][:5]:
        print(f"  - {f['where']}")
    print(f"report: {args.out}/report.md")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="piezobearing", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("diagnose", help="hold the model against a calibration record and write a report")
    d.add_argument("measurement", help="calibration CSV with time_s, force_N, voltage_V (s, N, V)")
    d.add_argument("--out", required=True, help="output folder (diagnosis.json, report.md, figures/)")
    d.add_argument(
        "--config", help="config file merged over config/config.yaml (model.effects, diagnostics, ...)"
    )
    d.add_argument("--quiet", action="store_true", help="no progress bar")
    d.set_defaults(func=_diagnose)
    v = sub.add_parser("validate", help="check a calibration CSV")
    v.add_argument("file")
    v.add_argument("--resample-to-uniform", action="store_true", help="accept an uneven clock (resampled)")
    v.add_argument("--config", help="config file merged over config/config.yaml (calibration.* settings)")
    v.set_defaults(func=_validate)
    args = p.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
