"""The sensor comparison's calibrated test seed by seed, resumable: what the study computes per case, for runs
longer than one sitting.

The study (``snakemake study_sensor_comparison``) writes a case only when all its seeds are done. This script
runs the same realisations (:func:`piezobearing.comparison.rig.realise` and :func:`~.rig.observe`, the study's
functions) for several cases in turn, healthy and faulty seeds interleaved in the proportion of
``sensor_comparison.n_healthy_seeds`` to ``n_faulty_seeds``, and appends each seed's calls and true-family
margins to a JSON-lines file as it finishes; a second start skips the seeds already there. ``--report`` reduces
the file to the study's calibrated columns (:func:`piezobearing.comparison.calibrated.sensor_test`) over the
seeds done, adds each sensor's smallest detected width over the cases that differ only in the defect's width
(:func:`~piezobearing.comparison.calibrated.smallest_detected_width`), and draws the healthy-statistic and ROC
figures.

A width sweep judges its faulty seeds against one healthy threshold: ``--healthy-of CASE=REF`` runs only the
faulty seeds of ``CASE`` and takes its healthy seeds from ``REF`` (a case whose config differs from ``CASE``'s
only in the defect, so its healthy realisations are the same rigs: the healthy bearing has no defect and each
realisation is seeded by ``seed`` and its replicate alone); the runner stops on a pair that differs in anything
but the defect's geometry (another fault type has another true family, whose healthy statistic the reference did
not record). The CPU seconds of each seed go to a file of their
own (``<out>.cpu.jsonl``), not to the results.

    python validation/sensor_comparison_calibrated.py --configfile config/config.yaml \\
        --resistance results/calibration/resistance.json --harmonic results/sensor/harmonic.csv \\
        --case rest:base_motion__level=0.0 --case frame:base_motion__level=1.0 --out results/validation/calibrated.jsonl
    python validation/sensor_comparison_calibrated.py --configfile config/config.yaml --case ... \\
        --out results/validation/calibrated.jsonl --report results/validation/calibrated.json
    python validation/sensor_comparison_calibrated.py ... --case rest:base_motion__level=0.0 \\
        --case w02_rest:base_motion__level=0.0,bearing__defects__0__width_m=0.2e-3 --healthy-of w02_rest=rest ...
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import pandas as pd

from piezobearing import config as config_loader
from piezobearing.chain import signals as signal_outputs
from piezobearing.comparison import calibrated
from piezobearing.comparison import rig as comparison
from piezobearing.config.cases import case_config
from piezobearing.io import read_harmonic, read_json
from piezobearing.plotting import save, use_style
from piezobearing.plotting import sensor_comparison as figures
from piezobearing.stages import housing_model
from piezobearing.workflow.registry import reads_digest


def parse_case(text: str) -> tuple[str, dict]:
    """``label:key=value,key=value`` (keys as the study tables' columns) -> (label, overrides)."""
    label, _, rest = text.partition(":")
    overrides = {}
    for item in filter(None, rest.split(",")):
        key, _, value = item.partition("=")
        try:
            overrides[key] = float(value)
        except ValueError:
            overrides[key] = value
    return label, overrides


def schedule(n_healthy: int, n_faulty: int) -> list[tuple[bool, int]]:
    """Healthy and faulty seeds interleaved in their proportion: (faulty, replicate) in the order run."""
    order = sorted([(k / n_healthy, False, k) for k in range(n_healthy)] + [(k / n_faulty, True, k) for k in range(n_faulty)])
    return [(faulty, k) for _, faulty, k in order]


def housings_for(cfg: dict, folder: str | None) -> dict | None:
    """The case's housing models from the workflow's files where they exist (``folder``), else None (built)."""
    if folder is None:
        return None
    digest = reads_digest(cfg, "sensor_comparison_housing")
    files = {faulty: Path(folder) / f"{'faulty' if faulty else 'healthy'}_{digest}.npz" for faulty in (False, True)}
    if not all(f.exists() for f in files.values()):
        return None
    reads = housing_model.housing_reads(cfg)
    return {faulty: housing_model.load_housing(str(f), faulty, reads) for faulty, f in files.items()}


def healthy_sources(pairs: list[str], labels: list[str]) -> dict:
    """``CASE=REF`` items of ``--healthy-of`` -> {CASE: REF}; both must be cases of the run."""
    out = {}
    for item in pairs:
        case, _, ref = item.partition("=")
        if case not in labels or ref not in labels or case == ref:
            raise SystemExit(f"--healthy-of {item}: write CASE=REF with two different --case labels ({', '.join(labels)})")
        out[case] = ref
    return out


def check_borrowed(configs: dict, borrowed: dict) -> None:
    """Each ``--healthy-of CASE=REF`` pair must differ only in its defect's geometry: a seed record holds the
    margin of its case's true fault family, so a reference of another fault type (or speed, base motion, floor...)
    would judge one family's statistic against another's healthy distribution."""
    for case, ref in borrowed.items():
        a, b = configs[case], configs[ref]
        type_a, type_b = a["bearing"]["defects"][0]["type"], b["bearing"]["defects"][0]["type"]
        if type_a != type_b:
            raise SystemExit(f"--healthy-of {case}={ref}: the fault types differ ({type_a}, {type_b}); a case of "
                             f"another fault type needs its own healthy seeds (leave it out of --healthy-of)")
        rest_a, rest_b = ({**c, "bearing": {k: v for k, v in c["bearing"].items() if k != "defects"}}
                          for c in (a, b))
        if rest_a != rest_b:
            keys = sorted(k for k in rest_a.keys() | rest_b.keys() if rest_a.get(k) != rest_b.get(k))
            raise SystemExit(f"--healthy-of {case}={ref}: the cases differ outside bearing.defects (in "
                             f"{', '.join(keys)}); the reference must be the same rig without the narrower defect")


def done_seeds(path: Path) -> set:
    if not path.exists():
        return set()
    return {(r["case"], r["faulty"], r["replicate"]) for r in map(json.loads, path.read_text().splitlines())}


def run(args) -> None:
    base = config_loader.load(*args.configfile)
    cases = list(map(parse_case, args.case))
    borrowed = healthy_sources(args.healthy_of, [label for label, _ in cases])
    configs = {label: case_config(base, overrides, source=f"case {label}") for label, overrides in cases}
    check_borrowed(configs, borrowed)
    resistance = read_json(args.resistance)
    out, cpu = Path(args.out), Path(args.out + ".cpu.jsonl")
    out.parent.mkdir(parents=True, exist_ok=True)
    done = done_seeds(out)
    rigs, plans, built = {}, {}, {}
    for label, overrides in cases:
        cfg = configs[label]
        circuit = signal_outputs.sensor_circuit(cfg, resistance, args.resistance)
        harmonic = read_harmonic(args.harmonic) if cfg["signals"]["sensor_fem_correction"] else None
        t = time.process_time()
        digest = reads_digest(cfg, "sensor_comparison_housing")  # one housing model per mesh, shared by the cases
        if digest not in built:
            built[digest] = housings_for(cfg, args.housing_dir) or {
                faulty: comparison.build_housing(comparison.rig_config(cfg, comparison.ComparisonSettings.from_config(
                    cfg)), faulty) for faulty in (False, True)}
        rigs[label] = comparison.prepare(cfg, circuit, harmonic, built[digest])
        c = cfg["sensor_comparison"]
        plans[label] = [s for s in schedule(c["n_healthy_seeds"], c["n_faulty_seeds"])
                        if (label, *s) not in done and (s[0] or label not in borrowed)]
        print(f"{label}: {len(plans[label])} seeds to run; rig prepared in {time.process_time() - t:.1f} s CPU",
              file=sys.stderr)
    while any(plans.values()):
        for label, plan in plans.items():
            if not plan:
                continue
            faulty, rep = plan.pop(0)
            t = time.process_time()
            r, clean = comparison.realise(rigs[label], faulty, rep)
            seen, _ = comparison.observe(rigs[label], r, clean, faulty, rep)
            dt = time.process_time() - t
            row = {"case": label, "faulty": faulty, "replicate": rep,
                   **{s: {"called": v["called"], "margin_dB": v["margin_dB"]} for s, v in seen.items()}}
            with out.open("a") as f:
                f.write(json.dumps(row) + "\n")
            with cpu.open("a") as f:
                f.write(json.dumps({"case": label, "faulty": faulty, "replicate": rep, "cpu_s": round(dt, 3)}) + "\n")


def report(args) -> None:
    base = config_loader.load(*args.configfile)
    rows = [json.loads(x) for x in Path(args.out).read_text().splitlines()]
    cases, tables = [], []
    parsed = list(map(parse_case, args.case))
    borrowed = healthy_sources(args.healthy_of, [label for label, _ in parsed])
    configs = {label: case_config(base, overrides, source=f"case {label}") for label, overrides in parsed}
    check_borrowed(configs, borrowed)
    for label, overrides in parsed:
        cfg = configs[label]
        c, b = cfg["sensor_comparison"], cfg["bearing"]
        own = [r for r in rows if r["case"] == label and (r["faulty"] or label not in borrowed)]
        lent = [r for r in rows if r["case"] == borrowed[label] and not r["faulty"]] if label in borrowed else []
        mine = sorted(own + lent, key=lambda r: (r["faulty"], r["replicate"]))
        if not any(r["faulty"] for r in mine) or all(r["faulty"] for r in mine):
            continue
        fault = b["defects"][0]["type"]
        summary = {"shaft_speed_rpm": b["shaft_speed_rpm"], "fault_type": fault,
                   "defect_width_m": b["defects"][0]["width_m"], "disturbance_level": cfg["base_motion"]["level"],
                   "roughness_rms_m": c["bearing_floor"]["roughness_rms_m"], "rows": [], "per_seed": []}
        for s in comparison.SENSORS:
            h = [r[s]["margin_dB"] for r in mine if not r["faulty"]]
            f = [r[s]["margin_dB"] for r in mine if r["faulty"]]
            calls_f = [r[s]["called"] for r in mine if r["faulty"]]
            calls_h = [r[s]["called"] for r in mine if not r["faulty"]]
            test = calibrated.sensor_test(h, f, calls_f, fault, c)
            test["false_alarm_rate"] = sum(x != "none" for x in calls_h) / len(calls_h)
            summary["rows"].append({"sensor": s, **test})
            summary["per_seed"].append({"sensor": s, "healthy_margin_dB": h, "faulty_margin_dB": f})
            tables.append({"case": label, "sensor": s, **overrides, "healthy_seeds_of": borrowed.get(label, label),
                           **{k: summary[k] for k in ("shaft_speed_rpm", "fault_type", "defect_width_m",
                                                      "disturbance_level", "roughness_rms_m")}, **test})
        cases.append({"summary": summary, "own_healthy": label not in borrowed})
    if tables:
        widths = calibrated.smallest_detected_width(pd.DataFrame(tables))
        for t, w in zip(tables, widths, strict=True):
            t["smallest_detected_width_m"] = None if pd.isna(w) else float(w)
    Path(args.report).write_text(json.dumps({"cases": tables}, indent=1, default=str))
    use_style()
    stem = Path(args.report).with_suffix("")
    # each healthy distribution once (a width sweep's cases share their reference's); every case's ROC
    save(figures.healthy_distributions([c for c in cases if c["own_healthy"]]), f"{stem}_healthy_statistic.png")
    save(figures.roc_curves(cases), f"{stem}_roc.png")
    keys = ("n_healthy_seeds", "n_faulty_seeds", "calibrated_threshold_dB", "calibrated_detection_probability",
            "calibrated_detection_ci_low", "calibrated_detection_ci_high", "tail_threshold_dB",
            "tail_detection_probability", "tail_shape", "tail_ks_p_value", "roc_auc", "type_correct_rate",
            "alarm_rate_faulty", "false_alarm_rate", "healthy_statistic_median_dB", "faulty_statistic_median_dB",
            "smallest_detected_width_m")
    print("| case | sensor | " + " | ".join(keys) + " |")
    print("|" + "---|" * (len(keys) + 2))
    for t in tables:
        cells = [f"{t[k]:.3g}" if isinstance(t[k], float) else str(t[k]) for k in keys]
        print(f"| {t['case']} | {t['sensor']} | " + " | ".join(cells) + " |")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--configfile", nargs="+", default=["config/config.yaml"])
    ap.add_argument("--resistance", default="results/calibration/resistance.json")
    ap.add_argument("--harmonic", default="results/sensor/harmonic.csv")
    ap.add_argument("--housing-dir", default=None, help="the workflow's housing models (results/.../housing)")
    ap.add_argument("--case", action="append", required=True, help="label:column=value,... (a study table's row)")
    ap.add_argument("--healthy-of", action="append", default=[], metavar="CASE=REF",
                    help="run only CASE's faulty seeds and judge them against REF's healthy ones (a width sweep)")
    ap.add_argument("--out", required=True, help="the seeds' JSON-lines file")
    ap.add_argument("--report", default=None, help="reduce the seeds done to this JSON (and its figures)")
    args = ap.parse_args(argv)
    report(args) if args.report else run(args)


if __name__ == "__main__":
    main()
