"""The ``piezobearing`` console script.

``piezobearing diagnose MEASUREMENT.csv --out DIR [--config FILE]``
    Hold the configured model against a calibration record: fit, residual
    tests, effect ranking, stepwise selection, verdict; writes
    DIR/diagnosis.json, DIR/report.md, DIR/figures/ and DIR/diagnosis.npz.

``piezobearing diagnose-bearing RECORD --out DIR [--config FILE] [--influence CSV] [--sensor-response CSV] [--rpm R]``
    Hold the bearing model against a running-bearing record (time_s,
    voltage_V[, speed_rpm]): baseline, bearing views, catalogue ranking,
    stepwise selection, verdict and the fault (type, size, position with
    95% intervals); writes DIR/diagnosis.json, DIR/report.md, DIR/figures/.

``piezobearing validate FILE [--config FILE]``
    Check a calibration record (time_s, force_N, voltage_V in any supported
    format: .csv, .mat, .uff/.unv, .tdms, .wav) as the workflow does before
    any job runs (file checks, at least two impulses, voltage polarity);
    prints ``OK`` and a summary, or the one-line problem (exit status 1).

``piezobearing hide-and-find EFFECT [--param NAME=VALUE ...] [--seed N] [--config FILE]``
    Hide a catalogue effect (a new one, while it is being written) in the
    configured synthetic calibration record (at its ``example`` size, the
    ``--param`` values over it) and diagnose it with the whole
    catalogue: prints what came first, what was selected, the fitted
    parameters with their 95% intervals and the verdict; exit status 0 when
    the effect (or one it is declared exactly equivalent to) is ranked and
    selected first with the verdict ``explained``, else 1.

``piezobearing detect RECORD [RECORD ...] --out DIR [--config RIG.yaml] [--bearing DESIGNATION] [--rpm R] [--fs HZ] [--channel NAME]``
    Detect a rolling-bearing fault in a recording (accelerometer or this
    sensor; .mat v5/v7.3 with structs and cells read by their paths, .csv,
    .wav, .uff, .tdms) with the envelope detector: writes DIR/detection.json
    (the call, per family its evidence, the band, the shaft speed found, the
    false-alarm probability), DIR/report.md and DIR/detection.png; prints
    the call in one line. Several records or a folder: each record's outputs
    in DIR/<name>/, a table DIR/detections.csv and a trend DIR/trend.png
    (exit status 1 where some record could not be read). ``--list`` prints
    what a record holds (channels, scalar and text fields by their paths).

Exit status: 0 done; 1 a user error (bad file, bad config, unknown effect,
unusable --out), one line naming the file or key and the fix, never a
traceback; 2 a usage error (unknown option, missing argument); 3 an internal
error (a bug: one line asking to report it; PIEZOBEARING_DEBUG=1 shows the
traceback). Run inside a checkout, the defaults come from its
config/config.yaml; elsewhere from the default config installed with the package.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .config import ConfigError, default_config_dir, find_checkout, load, read_yaml

# Each command imports what it runs inside its own function: all of them together take about 2-3 s of CPU to
# import (SciPy, sfepy, matplotlib, pandas; measured with resource.getrusage), which `piezobearing --help` and
# every other command would pay.

#: Exit statuses (see the module docstring).
EXIT_USER, EXIT_USAGE, EXIT_INTERNAL = 1, 2, 3


class UserError(Exception):
    """A problem with what the user asked for (one line, exit status 1)."""


def _fail(msg: str) -> int:
    print(f"piezobearing: {msg}", file=sys.stderr)
    return EXIT_USER


def _load_config(args) -> tuple[dict, str]:
    """The config the command uses and a line saying where it came from; a bad or unreadable config file is a
    :class:`UserError` (its one line)."""
    d = default_config_dir()
    overrides = [args.config] if args.config is not None else []
    try:
        config = load(*overrides, config_dir=d)
    except (ConfigError, OSError) as e:
        raise UserError(str(e)) from None
    return config, " + ".join([str(d / "config.yaml"), *map(str, overrides)])


#: The record formats the readers take (piezobearing.io.record_formats.RECORD_FORMATS; a test holds the two equal),
#: written out here so that ``--help`` does not import the readers.
FORMATS = ".csv, .mat (MATLAB v5 or v7.3), .uff/.unv (UFF58), .tdms (NI TDMS), .wav"

#: What ``piezobearing --help`` says first.
DESCRIPTION = (
    "Hold the embedded PZT force sensor's models against your measurements, and look for a fault in a "
    "recording. 'validate' checks a calibration record as the workflow does; 'diagnose' fits the sensor's "
    "circuit model to a calibration record and names the physical effect it misses; 'diagnose-bearing' holds "
    "the bearing, housing and sensor chain against a running-bearing record and names the fault; "
    "'hide-and-find' checks that the diagnosis finds an effect hidden in a synthetic record; 'detect' says "
    "whether a vibration or sensor recording of any rolling bearing shows an outer-race, inner-race or "
    "rolling-element fault. 'validate', 'diagnose', 'diagnose-bearing' and 'hide-and-find' read the "
    "checkout's config/config.yaml with --config merged over it; 'detect' reads no model config: its --config "
    "is a rig file (the bearing, the shaft speed, the sampling rate, the channel). The four model commands "
    "print which config and which model they used; every command stops on a bad input with one line naming "
    "the file or key and the fix. The paper's figures and numbers come from the Snakemake workflow (snakemake --cores 2), not from "
    "this script."
)


def _calibration_model(config: dict) -> str:
    """The calibration model a command used, in one line: the sensor, its circuit and the effects switched on."""
    s = config["sensor"]
    effects = ", ".join(config["model"]["effects"]) or "none"
    return (
        f"model: RC circuit of Eq. 6 (R fitted) on the {s['material']} disk {s['pzt_diameter_m'] * 1e3:g} x "
        f"{s['pzt_height_m'] * 1e3:g} mm, {s['cable_length_m']:g} m cable at "
        f"{s['cable_capacitance_F_per_m'] * 1e12:g} pF/m; effects switched on: {effects}"
    )


def _bearing_model(config: dict, influence: str | None) -> str:
    """The running-bearing model a command used, in one line: bearing, operating point, housing, sensor."""
    b, s, bd = config["bearing"], config["sensor"], config["bearing_diagnosis"]
    effects = ", ".join(bd["effects"]) or "none"
    housing = f"influence line from {influence}" if influence else "influence line solved from the config"
    return (
        f"model: {b['n_rollers']}-roller bearing (D_r {b['roller_diameter_m'] * 1e3:g} mm, D_p "
        f"{b['pitch_diameter_m'] * 1e3:g} mm) at {b['shaft_speed_rpm']:g} rpm and {b['radial_load_N']:g} N, "
        f"quasi-static surrogate, {housing}; sensor {s['material']} {s['pzt_diameter_m'] * 1e3:g} x "
        f"{s['pzt_height_m'] * 1e3:g} mm through R = {bd['resistance_ohm'] / 1e6:g} MOhm; effects switched on: "
        f"{effects}"
    )


def _data_dirs() -> list[Path]:
    """The data/ folders that hold users' measurements and are never written."""
    # the checkout around the current folder, and the one holding the package (an editable install)
    roots = {r.resolve() for r in (find_checkout(), find_checkout(Path(__file__).parent)) if r}
    return [r / "data" for r in sorted(roots)]


def _prepare_out(out: str) -> list[Path]:
    """Check ``--out`` before any work; create it and return the folders created (to remove on failure)."""
    if not out.strip():
        raise UserError("--out is empty; give the folder for the report, e.g. --out results/diagnosis")
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise UserError(f"--out {out}: is a file, not a folder; give a new or existing folder")
    full = p.resolve()
    for data in _data_dirs():
        if full == data or data in full.parents:
            raise UserError(
                f"--out {out}: inside {data}, which holds measurements and is never written; "
                "give a folder outside it, e.g. --out results/diagnosis"
            )
    missing = [d for d in (full, *full.parents) if not d.exists()][::-1]
    parent = missing[0].parent if missing else full
    if not parent.is_dir():
        raise UserError(
            f"--out {out}: {parent} is a file, so no folder can be made under it; give another folder"
        )
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UserError(f"--out {out}: no permission to write in {parent}; give a folder you can write to")
    try:
        for d in missing:
            d.mkdir()
    except OSError as e:
        _remove_empty(missing)
        raise UserError(
            f"--out {out}: cannot create {e.filename or full} ({e.strerror or type(e).__name__}); "
            "give a folder you can write to"
        ) from None
    return missing


def _remove_empty(created: list[Path]) -> None:
    """Remove the folders this run created, deepest first, where they are still empty."""
    for d in reversed(created):
        try:
            d.rmdir()
        except OSError:
            pass


def _validate(args) -> int:
    from .io import MeasurementError
    from .stages.calibration import load_record

    config, used = _load_config(args)
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
    print(f"config: {used}")
    from .diagnosis.describe import stuck_runs

    stuck = stuck_runs(m.voltage_V, time_s=m.time_s)
    if stuck["n_runs"]:  # readable, but no model can fit these samples
        levels = ", ".join(f"{v:.6g} V" for v in stuck["levels"])
        print(
            f"WARNING: {args.file}: column voltage_V is stuck at {levels} in {stuck['n_runs']} run(s) "
            f"({stuck['n_samples']} samples, the first at t = {stuck['runs'][0]['start_s']:.3f} s): "
            "clipped; widen the DAQ's input range or lower the gain"
        )
    if m.filled is not None:  # resampled across gaps: those samples are the interpolation's
        from .diagnosis.record import Record

        g = Record(m.time_s, filled=m.filled).filled_gaps()
        first = g["gaps"][0]
        print(
            f"WARNING: {args.file}: column time_s: {g['n_samples']} samples lost in {len(g['gaps'])} gap(s) "
            f"(the first {first['duration_s'] * 1e3:.3g} ms at t = {first['start_s']:.4g} s) were filled by "
            "resample_to_uniform; the diagnosis leaves them out of its fit"
        )
    return 0


def _diagnose(args) -> int:
    from tqdm import tqdm

    from .diagnosis.calibration.effects import CATALOGUE, EffectError
    from .io import MeasurementError
    from .stages.diagnostics import diagnose

    config, used = _load_config(args)
    try:
        created = _prepare_out(args.out)
    except UserError as e:
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
        _remove_empty(created)
        return _fail(str(e))
    except OSError as e:
        bar.close()
        return _fail(
            f"--out {args.out}: writing {e.filename or 'the report'} failed ({e.strerror or type(e).__name__}); "
            "free space or give another folder"
        )
    except BaseException:
        bar.close()
        _remove_empty(created)
        raise
    bar.update(bar.total - bar.n)
    bar.close()
    print(f"config: {used}")
    print(_calibration_model(config))
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
    stuck = (d.get("outside_catalogue") or {}).get("stuck") or {}
    if stuck.get("where"):
        print(f"WARNING: {stuck['where']}")
    if (d.get("filled_gaps") or {}).get("n_samples"):
        from .diagnosis.report.sections import filled_gaps_line

        print(f"WARNING: {filled_gaps_line(d['filled_gaps'])}")
    for f in d["unexplained"][:5]:
        print(f"  - {f['where']}")
    if len(d["unexplained"]) > 5:
        print(f"  ... and {len(d['unexplained']) - 5} more (every one in the report)")
    print(f"report: {args.out}/report.md")
    return 0


def _hide_and_find(args) -> int:
    from .diagnosis.calibration.effects import CATALOGUE, EffectError, ForceRecord
    from .diagnosis.calibration.presses import PressProtocol, synthesize
    from .diagnosis.calibration.subject import diagnose_record
    from .diagnosis.settings import DiagnosticsSettings
    from .sensor.calibration import detect_impulses
    from .stages.calibration import nominal_circuit

    config, used = _load_config(args)
    params = {}
    for i, item in enumerate(args.param or []):
        name, eq, value = item.partition("=")
        try:
            params[name] = float(value)
        except ValueError:
            eq = ""
        if not eq:
            return _fail(f"--param {item}: give NAME=VALUE with a number, e.g. --param delay_s=0.015 (item {i + 1})")
    given = params
    if args.effect in CATALOGUE:  # the effect's plausible size, the given values over it
        params = {**CATALOGUE[args.effect].example, **given}
    hidden = [{"name": args.effect, "params": params}]
    seed = config["seed"] if args.seed is None else args.seed
    try:
        m = synthesize(PressProtocol.from_config(config["synthesis"]), nominal_circuit(config), seed, hidden)
    except EffectError as e:
        key = "synthesis.hidden_effects[0]"
        return _fail(str(e).replace(f"{key}.params.", "--param ").replace(key, f"hide-and-find {args.effect}"))
    t, f, v = m.time_s, m.force_N, m.voltage_V
    imps = detect_impulses(f, v, t[1] - t[0], 0.2, 0.8)
    circuit = nominal_circuit(config, config["calibration"]["initial_resistance_ohm"])
    settings = DiagnosticsSettings.from_config(config["diagnostics"])
    _, d = diagnose_record(ForceRecord(t, f), v, circuit, [], settings, imps)
    same = {args.effect, *CATALOGUE[args.effect].equivalent_to}
    same |= {e.name for e in CATALOGUE.values() if args.effect in e.equivalent_to}
    first = d["ranking"][0] if d["ranking"] else None
    found = first is not None and first["effect"] in same and d["selected"][:1] == [first["effect"]]
    source = "" if given == params else " (the effect's example" + (", --param over it)" if given else ")")
    print(f"config: {used}; seed {seed}; hidden: {args.effect} {params or '(defaults)'}{source}")
    print(_calibration_model({**config, "model": {"effects": []}}))
    if first is not None:
        print(f"ranked first: {first['effect']} (delta BIC {first['delta_bic']:.4g}): {first['summary']}")
    print(f"selected: {', '.join(d['selected']) or 'nothing'}; verdict: {d['verdict']}")
    for k, val in d["final"]["params"].items():
        lo, hi = d["final"]["ci95"].get(k, [float("nan")] * 2)
        print(f"  {k} = {val:.6g} [{lo:.6g}, {hi:.6g}]" + (f" (hidden {params[k]:.6g})" if k in params else ""))
    ok = found and d["verdict"] == "explained"
    print("FOUND" if ok else "NOT FOUND: " + ("ranked first but " if found else "") + "see the lines above")
    return 0 if ok else EXIT_USER


def _diagnose_bearing(args) -> int:
    from .diagnosis.effect import EffectError
    from .io import MeasurementError, ResultFileError, SignalFileError
    from .stages.bearing_diagnosis import diagnose_bearing

    config, used = _load_config(args)
    config["bearing"]["measurement"] = args.record
    if args.rpm is not None and not args.rpm > 0:
        return _fail(f"--rpm {args.rpm:g}: give the shaft speed in rpm (> 0)")
    # the rig file's own speed stands before the record's *RPM variable; the default config's after it
    rig = read_yaml(args.config) if args.config is not None else {}
    rig_speed = "shaft_speed_rpm" in ((rig or {}).get("bearing") or {})

    cost: dict[str, str] = {}

    def progress(msg: str) -> None:
        for rung in ("dynamic rung", "housing mode rung"):
            if msg.startswith(f"{rung}:") and "CPU" in msg:
                cost[rung] = msg
        if not args.quiet:
            print(f"  fit: {msg}", file=sys.stderr, flush=True)

    try:
        if not args.influence and not args.quiet:
            print("solving the housing's influence line from the config (a few seconds)", file=sys.stderr)
        d = diagnose_bearing(args.record, args.out, config, args.influence, progress, args.sensor_response,
                             args.rpm, rig_speed)
    except (MeasurementError, EffectError, ResultFileError, SignalFileError) as e:
        return _fail(str(e))
    print(f"config: {used}")
    print(_bearing_model(config, args.influence))
    for w in d["record_warnings"]:
        print(f"warning: {w}")
    base, final, f = d["baseline"], d["final"], d["fault"]
    sm, sp = d["sensor_model"], d["shaft_speed"]
    print(f"shaft speed: {sp['rpm']:g} rpm from {sp['source']}, fitted within "
          f"{100 * config['bearing_diagnosis']['speed_tolerance_ratio']:g} % (or a speed_rpm column's)")
    print(f"sensor model: d33/C x FEM correction {sm['fem_factor']:.4g} ({sm['source']})")
    print(f"rate: {d['model_rate']['reason']}")
    print(f"baseline NRMSE {100 * base['nrmse']:.2f}% (noise floor {100 * base['noise_floor_nrmse']:.2f}%)")
    print(
        f"selected: {', '.join(d['selected']) or 'nothing'}; final NRMSE {100 * final['nrmse']:.2f}% "
        f"(floor {100 * final['noise_floor_nrmse']:.2f}%)"
    )
    rung = d.get("dynamic_rung") or {}
    for name, r in (("dynamic rung", rung), ("housing mode rung", rung.get("housing_mode") or {})):
        if r.get("tried"):
            print(f"{cost.get(name, name)}: " + " -> ".join(
                f"{row['model']} {100 * row['nrmse']:.2f}%" for row in r["ladder"]))
    print(f"fault: {f['type']}" + (" (named from its lines)" if f.get("source") == "lines" else "")
          + "".join(f"; {k} = {v:.6g} [{f['ci95'][k][0]:.6g}, {f['ci95'][k][1]:.6g}]" for k, v in f["params"].items() if f["ci95"].get(k)))
    if f.get("source") == "lines":
        print(f"  {f['statement']}")
    if f.get("lines_left"):
        print(f"found, with lines left: {f['statement']}")
    for u in f.get("unidentified") or []:
        print(f"  left out, not identified: {u['effect']}: {u['reason']}")
    print(f"verdict: {d['verdict']}")
    stuck = (d.get("outside_catalogue") or {}).get("stuck") or {}
    if stuck.get("where"):
        print(f"WARNING: {stuck['where']}")
    for u in d["unexplained"][:5]:
        print(f"  - {u['where']}")
    print(f"report: {args.out}/report.md")
    return 0


def _detect(args) -> int:
    from .bearing.kinematics import BearingError
    from .io import MeasurementError
    from .io.vibration import read_record_contents
    from .stages.recording import (
        RigError,
        check_names,
        detect_recording,
        detect_records,
        record_files,
        type_lines,
        write_detection,
    )

    if args.list:
        try:
            for path in record_files(args.record, args.glob):
                print(read_record_contents(path).listing())
        except (MeasurementError, RigError) as e:
            return _fail(str(e))
        return 0
    if args.out is None:
        return _fail("--out is missing; give the folder for the report, e.g. --out results/detect "
                     "(or --list to see what the record holds)")
    if args.jobs < 1:
        return _fail(f"--jobs {args.jobs}: give the number of records to detect at once (1 or more)")
    batch = len(args.record) > 1 or Path(args.record[0]).is_dir()
    if not batch and (args.time_field or args.time_from_name):
        return _fail("--time-field and --time-from-name order several records; give several files or a folder")
    try:
        created = _prepare_out(args.out)
    except UserError as e:
        return _fail(str(e))
    options = {"bearing": args.bearing, "rpm": args.rpm, "fs": args.fs, "channel": args.channel,
               "shaft_Hz": args.shaft_hz, "tachometer": args.tachometer, "pulses_per_rev": args.pulses_per_rev,
               "speed_channel": args.speed_channel}
    if batch:
        from tqdm import tqdm  # a batch's progress bar: one record's detection goes without it

        try:
            files = record_files(args.record, args.glob)
            check_names(files)
            bar = tqdm(total=len(files), desc="detect", unit="record", file=sys.stderr, disable=args.quiet)
            table = detect_records(files, args.out, args.config, time_field=args.time_field,
                                   time_pattern=args.time_from_name, jobs=args.jobs,
                                   progress=lambda row: bar.update(1), **options)
            bar.close()
        except (MeasurementError, RigError, BearingError) as e:
            _remove_empty(created)
            return _fail(str(e))
        for _, row in table.sort_values("order").iterrows():
            said = row["call"] if row["status"] == "ok" else f"not read: {row['error']}"
            print(f"{row['file']}: {said}")
        failed = int((table["status"] != "ok").sum())
        print(f"table: {Path(args.out) / 'detections.csv'}; trend: {Path(args.out) / 'trend.png'}; "
              f"{len(table) - failed} of {len(table)} records detected" + (f", {failed} not read" if failed else ""))
        return EXIT_USER if failed else 0
    try:
        result = detect_recording(args.record[0], args.config, **options)
    except (MeasurementError, RigError, BearingError) as e:
        _remove_empty(created)
        return _fail(str(e))
    paths = write_detection(result, args.out)
    d = result.to_dict()
    print(f"{args.record[0]}: {d['summary']}")
    for line in type_lines(d):
        print(f"  {line}")
    print(f"report: {paths['report']}")
    return 0


def _version() -> str:
    # importlib.metadata costs 0.03-0.04 s of CPU to import and its look-up scans the installed distributions:
    # read where --version is asked for, not by every command
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("piezobearing")
    except PackageNotFoundError:
        return "unknown (not installed)"


class _VersionAction(argparse.Action):
    """argparse's ``version`` action with the version read when the option is given (:func:`_version`)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help="show program's version number and exit"):
        super().__init__(option_strings=option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"{parser.prog} {_version()}")
        parser.exit()


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="piezobearing",
        description=DESCRIPTION,
        epilog="Exit status: 0 done, 1 user error (one line with the fix), 2 usage error, 3 internal error (a bug).",
    )
    p.add_argument("--version", action=_VersionAction)
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    d = sub.add_parser(
        "diagnose",
        help="hold the model against a calibration record and write a report",
        description="Fit the sensor's circuit model (Eq. 6, R fitted, with the effects of model.effects) to a "
        "calibration record of force and voltage; test the residual against the noise floor measured between "
        "the impulses; rank every effect of the catalogue by how much it explains, add them stepwise while the "
        "evidence holds, and give the verdict (explained, or what remains and where). Writes diagnosis.json, "
        "diagnosis.npz, report.md and figures/ to --out; prints the config and the model it used. The record: "
        f"{FORMATS}, channels time_s, force_N, voltage_V (names in calibration.channels).",
    )
    d.add_argument(
        "measurement", help=f"calibration record ({FORMATS}) with time_s, force_N, voltage_V (s, N, V)"
    )
    d.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help="output folder, created if needed (diagnosis.json, diagnosis.npz, report.md, figures/); not inside data/",
    )
    d.add_argument(
        "--config",
        metavar="FILE",
        help="YAML file merged over the checkout's config/config.yaml (model.effects, diagnostics, ...)",
    )
    d.add_argument("--quiet", action="store_true", help="no progress bar")
    d.set_defaults(func=_diagnose)
    b = sub.add_parser(
        "diagnose-bearing",
        help="hold the bearing model against a running-bearing record and write a report",
        description="Fit the running bearing's chain (roller loads with any defect, the housing's influence "
        "line, the sensor's RC circuit; phase, speed and DC level fitted) to a record of the sensor voltage; "
        "look at the residual per roller passage, synchronously averaged, in its envelope at every fault band and "
        "in orders; rank the catalogue's effects (defects, load, clearance, slip, ...), add them stepwise, and "
        "name the fault with its size and position and their 95% intervals. Writes diagnosis.json, report.md and "
        "figures/ to --out; prints the config and the model it used. The record: "
        f"{FORMATS}, channels time_s, voltage_V[, speed_rpm] (names in bearing.channels).",
    )
    b.add_argument("record", help="record with time_s, voltage_V[, speed_rpm] (s, V, rpm): .csv, .mat, .uff, .tdms, .wav")
    b.add_argument("--out", required=True, help="output folder (diagnosis.json, report.md, figures/)")
    b.add_argument("--config", metavar="FILE", help="YAML file merged over config/config.yaml (bearing, sensor, bearing_diagnosis)")
    b.add_argument(
        "--influence",
        help="the housing's influence line (results/bearing/influence_line_healthy.csv); default: solved from the config",
    )
    b.add_argument(
        "--sensor-response",
        metavar="CSV",
        help="the sensor FEM's harmonic response (results/sensor/harmonic.csv) for the FEM correction of the sensor "
        "model; default: the paper sensor's, shipped with the package",
    )
    b.add_argument(
        "--rpm",
        type=float,
        metavar="R",
        help="the nominal shaft speed [rpm] (fitted within bearing_diagnosis.speed_tolerance_ratio); default: the "
        "rig file's bearing.shaft_speed_rpm, else the record's scalar *RPM variable (.mat), else config/config.yaml's",
    )
    b.add_argument("--quiet", action="store_true", help="no progress lines")
    b.set_defaults(func=_diagnose_bearing)
    v = sub.add_parser(
        "validate",
        help="check a calibration record as the workflow does",
        description="Read a calibration record as the workflow does before any job runs and check it: the "
        "file and its channels, finite numbers, an increasing and uniform clock (or resampled), at least two "
        "impulses, the voltage's polarity, dead, constant, clipped or stuck channels. Prints OK with a summary "
        "and the config used, or the one-line problem with its fix (exit status 1). Formats: "
        f"{FORMATS}; channels time_s, force_N, voltage_V (s, N, V), named in calibration.channels where the "
        "file calls them otherwise.",
    )
    v.add_argument("file", help=f"calibration record ({FORMATS}) with time_s, force_N, voltage_V (s, N, V)")
    v.add_argument(
        "--resample-to-uniform",
        action="store_true",
        help="accept an uneven clock and resample it onto the median step (calibration.resample_to_uniform)",
    )
    v.add_argument(
        "--config",
        metavar="FILE",
        help="YAML file merged over the checkout's config/config.yaml (calibration.* settings)",
    )
    v.set_defaults(func=_validate)
    h = sub.add_parser(
        "hide-and-find",
        help="hide a catalogue effect in the synthetic calibration record and check the diagnosis finds it",
        description="Synthesise the configured calibration record with one effect of the catalogue hidden in "
        "it (at the effect's example size, or the --param values), diagnose it with the whole catalogue, and say "
        "whether the diagnosis ranks and selects that effect first with the verdict 'explained' (FOUND, exit 0) "
        "or not (exit 1); prints the fitted parameters with their 95% intervals beside the hidden values, and "
        "the config and model used. The check a new effect module must pass.",
    )
    h.add_argument("effect", help="the effect's identifier (e.g. channel_delay)")
    h.add_argument(
        "--param",
        action="append",
        metavar="NAME=VALUE",
        help="a hidden parameter value, e.g. delay_s=0.015 (repeat for more; others: the effect's example "
        "size, or neutral where it has none)",
    )
    h.add_argument("--seed", type=int, help="seed of the synthetic record (default: the config's seed)")
    h.add_argument(
        "--config", metavar="FILE", help="YAML file merged over config/config.yaml (synthesis, diagnostics)"
    )
    h.set_defaults(func=_hide_and_find)
    t = sub.add_parser(
        "detect",
        help="detect a rolling-bearing fault in a recording and write a report",
        description="Detect an outer-race, inner-race or rolling-element fault in a vibration or sensor record with "
        "the envelope detector (pre-whitening, fast kurtogram, squared envelope spectrum, fault bands).",
    )
    t.add_argument("record", nargs="+",
                   help="the record: .mat (v5/v7.3), .csv, .wav, .uff/.unv, .tdms; several files or a folder give a "
                   "table (detections.csv) and a trend (trend.png), each record's report in --out/<name>/")
    t.add_argument("--out", metavar="DIR",
                   help="output folder (detection.json, report.md, detection.png); not inside data/")
    t.add_argument("--list", action="store_true",
                   help="list every channel, scalar and text field the record holds, by its path, and stop")
    t.add_argument("--config", metavar="RIG.yaml",
                   help="rig file: bearing (designation or geometry), shaft_speed_rpm or shaft_speed_Hz, "
                   "sample_rate_Hz, channel; beside a record, its own RECORD.yaml is used")
    t.add_argument("--bearing", metavar="DESIGNATION", help="a bearing of the designation table, e.g. 'SKF 6205'")
    t.add_argument("--rpm", metavar="R", help="shaft speed [rpm], or the record's field holding it in rpm "
                   "(default: the rig file's, else the record's RPM variable)")
    t.add_argument("--shaft-hz", metavar="F", help="shaft speed [Hz, revolutions per second], or the record's field "
                   "holding it in Hz (bearing.rate)")
    t.add_argument("--fs", metavar="HZ", help="sampling rate [Hz] of a file without a time axis, or the record's "
                   "field holding it (bearing.sr)")
    t.add_argument("--channel", metavar="NAME",
                   help="the channel: its name or path (bearing.gs), or a unique suffix such as _DE_time")
    t.add_argument("--tachometer", metavar="CHANNEL", help="the record's tachometer (pulse) channel: the record is "
                   "order-tracked (resampled at uniform shaft angles) before the envelope analysis")
    t.add_argument("--pulses-per-rev", type=int, metavar="N", help="the tachometer's pulses per shaft revolution "
                   "(default: the rig file's, else 1)")
    t.add_argument("--speed-channel", metavar="CHANNEL", help="the record's shaft-speed channel [rpm], sample by "
                   "sample: the record is order-tracked (default: a channel named speed_rpm)")
    t.add_argument("--time-field", metavar="FIELD", help="several records: each record's time from this field "
                   "(a number, or a date and time as text)")
    t.add_argument("--time-from-name", metavar="PATTERN", help="several records: each record's time from its file "
                   "name by a strftime pattern, e.g. %%Y%%m%%d_%%H%%M%%S")
    t.add_argument("--glob", metavar="PATTERN", help="a folder's records: the files matching this pattern, e.g. "
                   "'*.mat' (default: every file of a record format)")
    t.add_argument("--jobs", type=int, default=1, metavar="N", help="several records: detect N at once")
    t.add_argument("--quiet", action="store_true", help="no progress bar")
    t.set_defaults(func=_detect)
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)  # usage errors exit with status 2 (argparse)
    try:
        return args.func(args)
    except UserError as e:
        return _fail(str(e))
    except KeyboardInterrupt:
        print("piezobearing: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # a bug, not a user error: say so, one line
        if os.environ.get("PIEZOBEARING_DEBUG"):
            raise
        where = e.__traceback__
        while where is not None and where.tb_next is not None:
            where = where.tb_next
        loc = f" at {Path(where.tb_frame.f_code.co_filename).name}:{where.tb_lineno}" if where else ""
        print(
            f"piezobearing: internal error ({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}{loc}); "
            "this is a bug: please report it with the command line and this message "
            "(PIEZOBEARING_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
