"""Speed of the running bearing's diagnosis, and the verified table of hide-and-find.

Timing: a synthetic 2 s record at 2550 Hz (the paper's clock) and at 25.6 kHz,
healthy, with a 0.6 mm outer-race groove and with a 0.8 mm inner-race groove
hidden (the inner race's lines lift the record's floor: the engine runs twice),
diagnosed with the whole catalogue (the default diagnostics settings) from
record to JSON (no figures). The target: at most 60 s at 2550 Hz and 3 min at
25.6 kHz on 2 cores. Each run gives its wall time and its CPU time (the
process's, one BLAS thread): on a shared machine the CPU time is what an idle
one would take. ``--old FILE`` (a run of the method before a change, same
script) adds the ratios old / new of the CPU times.

``--verify``: every catalogue effect hidden alone, exactly as
tests/test_diagnosis_bearing.py does (its values, 0.5 s at 2550 Hz, seed 11,
the CI mesh's influence line, the first ranking and step), at 30 and 10 dB;
writes the hidden value, the fitted value with its 95% interval, the rank
and the NRMSE ladder for docs/validation/bearing_diagnosis.md.

Writes results/benchmarks/diagnosis_bearing.json (and diagnosis_bearing_verified.json).
``--coverage N``: the 95% intervals' coverage over N noise seeds (outer groove, clearance; writes
results/benchmarks/diagnosis_bearing_coverage.json).

``--no-prepass``: the method before the noise-floor pre-pass (for ``--old``).

Usage: python benchmarks/bench_diagnosis_bearing.py [--ci] [--verify] [--old FILE] [--out FILE] [--note TEXT] [--coverage N]
       [--no-prepass] [--verify-only --snr 10 --effects NAME ...]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import sys
import time
from pathlib import Path

from piezobearing import config
from piezobearing.diagnosis.bearing.subject import SUBJECT, synthesise
from piezobearing.stages.bearing_diagnosis import influence_from_config

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_diagnosis_bearing import HIDDEN, misses  # noqa: E402

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)


def diagnose(c, influence, hidden, snr, fs, tach=False, duration=2.0):
    c = copy.deepcopy(c)
    c["bearing_diagnosis"].update(synthetic_snr_dB=snr, synthetic_sample_rate_Hz=fs, synthetic_duration_s=duration,
                                  synthetic_tachometer=tach)
    rec = synthesise(c, 11, hidden, influence)
    t0, c0 = time.perf_counter(), time.process_time()
    d = SUBJECT.diagnose((rec, influence), c)[1]
    return d, time.perf_counter() - t0, time.process_time() - c0


def coverage(seeds: int, names=("outer_race_defect", "clearance"), snr: float = 30.0) -> dict:
    """How often the 95% interval holds the hidden value over ``seeds`` noise draws (seeds 100, 101, ...).

    Each record as the tests make it (0.5 s at 2550 Hz, the CI mesh's line); the baseline and the hidden
    effect fitted as the engine ranks it (warm start, the effect's starts), its Jacobian interval. For
    each parameter: z = (found - hidden) / (half-width / 1.96), its mean and standard deviation (0 and 1
    for honest intervals) and the share of |z| <= 1.96 (0.95).
    """
    import numpy as np
    from threadpoolctl import threadpool_limits

    from piezobearing.diagnosis.bearing.effects import CATALOGUE
    from piezobearing.diagnosis.fit import fit_model
    from piezobearing.diagnosis.selection import add_effect
    from piezobearing.diagnosis.settings import DiagnosticsSettings

    c = copy.deepcopy(config.load(CONFIG / "ci.yaml"))
    c["bearing_diagnosis"].update(synthetic_duration_s=0.5, synthetic_sample_rate_Hz=2550.0, synthetic_snr_dB=snr)
    infl = influence_from_config(c)
    st = DiagnosticsSettings.from_config(c["diagnostics"])
    out = {}
    with threadpool_limits(limits=1, user_api="blas"):
        for name in names:
            zs = {k: [] for k in HIDDEN[name] if k != "roller_defect_index"}
            for seed in range(100, 100 + seeds):
                rec = synthesise(c, seed, [{"name": name, "params": HIDDEN[name]}], infl)
                p = SUBJECT.problem((rec, infl), c)
                base = fit_model(p.baseline, p.record, p.voltage_V, p.floor, start=p.baseline_start,
                                 starts=p.baseline_starts, max_nfev=st.max_nfev, ftol=st.ftol)
                f = add_effect(base, CATALOGUE[name], p.record, p.voltage_V, p.floor, st)
                for k in zs:
                    lo, hi = f.result.ci95[k]
                    zs[k].append((f.values[k] - HIDDEN[name][k]) / ((hi - lo) / 3.92))
            for k, z in zs.items():
                z = np.array(z)
                out[k] = {"effect": name, "snr_dB": snr, "seeds": seeds, "mean_z": float(z.mean()),
                          "sd_z": float(z.std(ddof=1)), "coverage95": float(np.mean(np.abs(z) <= 1.96)), "z": z.tolist()}
                print(json.dumps({kk: v for kk, v in out[k].items() if kk != "z"} | {"param": k}), flush=True)
    return out


def ratios(out: dict, old_path: str) -> None:
    """Add each run's CPU time before the change and the ratio old / new (``--old``)."""
    old = json.loads(Path(old_path).read_text())
    ref = {(r["sample_rate_Hz"], r["hidden"]): r for r in old["runs"]}
    for r in out["runs"]:
        o = ref.get((r["sample_rate_Hz"], r["hidden"]))
        if o is not None and "cpu_seconds" in r:
            r["old_cpu_seconds"] = o.get("cpu_seconds")
            r["old_seconds"] = o.get("seconds")
            r["old_error"] = o.get("error")
            r["speedup_cpu"] = o["cpu_seconds"] / r["cpu_seconds"] if o.get("cpu_seconds") else None
    out["old"] = {"file": Path(old_path).name, "note": old.get("note", ""), "load_average_1min": old.get("load_average_1min")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="the CI housing mesh (config/ci.yaml)")
    ap.add_argument("--verify", action="store_true", help="also the hide-and-find table (slow)")
    ap.add_argument("--verify-only", action="store_true", help="only the hide-and-find table")
    ap.add_argument("--old", help="a previous run's JSON (the method before a change): CPU-time ratios old / new")
    ap.add_argument("--out", default="results/benchmarks/diagnosis_bearing.json")
    ap.add_argument("--note", default="", help="what this run measures (kept in the JSON)")
    ap.add_argument("--no-prepass", action="store_true",
                    help="the method before the floor pre-pass: the engine runs twice where a fault lifts the floor")
    ap.add_argument("--ratios-only", action="store_true", help="add --old's ratios to --out (no runs)")
    ap.add_argument("--snr", type=float, nargs="+", default=[30.0, 10.0], help="--verify: the SNRs (dB)")
    ap.add_argument("--effects", nargs="+", default=list(HIDDEN), help="--verify: the hidden effects")
    ap.add_argument("--coverage", type=int, default=0, metavar="SEEDS", help="only the 95%% intervals' coverage over SEEDS seeds")
    args = ap.parse_args()
    if args.coverage:
        Path("results/benchmarks").mkdir(parents=True, exist_ok=True)
        cov = coverage(args.coverage)
        Path("results/benchmarks/diagnosis_bearing_coverage.json").write_text(json.dumps(cov, indent=2) + "\n")
        return
    if args.ratios_only:
        out = json.loads(Path(args.out).read_text())
        ratios(out, args.old)
        Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
        return
    if args.no_prepass:  # no pre-pass: the old method (the engine's second run on the final model's residual)
        from piezobearing.diagnosis.bearing import subject

        subject.floor_prepass = lambda problem, *_args, **_kw: problem
    c = config.load(CONFIG / "ci.yaml") if args.ci or args.verify_only else config.load()
    t0 = time.perf_counter()
    influence = influence_from_config(c)
    out = {"cpu_count": os.cpu_count(), "load_average_1min": os.getloadavg()[0], "influence_line_s": time.perf_counter() - t0,
           "note": args.note, "runs": []}
    cases = [("healthy", [])] + [(n, [{"name": n, "params": HIDDEN[n]}]) for n in ("outer_race_defect", "inner_race_defect")]
    for fs in () if args.verify_only else (2550.0, 25600.0):
        for label, hidden in cases:
            try:
                d, sec, cpu = diagnose(c, influence, hidden, 30.0, fs)
            except RuntimeError as e:  # a method that fails on a case is recorded, not hidden
                out["runs"].append({"sample_rate_Hz": fs, "duration_s": 2.0, "hidden": label, "error": str(e)})
                print(json.dumps(out["runs"][-1]), flush=True)
                continue
            row = {"sample_rate_Hz": fs, "duration_s": 2.0, "hidden": label, "seconds": sec, "cpu_seconds": cpu,
                   "load_average_1min": os.getloadavg()[0], "selected": d["selected"], "verdict": d["verdict"],
                   "floor_remeasured": "final model's residual" in d["noise_floor"]["method"],
                   "floor_prepass": "pre-pass" in d["noise_floor"]["method"], "final_nrmse": d["final"]["nrmse"],
                   "floor_nrmse": d["noise_floor_nrmse"]}
            out["runs"].append(row)
            print(json.dumps(row), flush=True)
    if args.old:
        ratios(out, args.old)
    Path("results/benchmarks").mkdir(parents=True, exist_ok=True)
    if not args.verify_only:
        Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
    if args.verify or args.verify_only:
        rows = []
        cv = copy.deepcopy(config.load(CONFIG / "ci.yaml"))
        cv["diagnostics"]["max_steps"] = 1
        infl_v = influence if args.ci or args.verify_only else influence_from_config(cv)
        for snr in args.snr:
            for name in args.effects:
                params = HIDDEN[name]
                d, sec, cpu = diagnose(cv, infl_v, [{"name": name, "params": params}], snr, 2550.0,
                                  tach=(name == "cage_slip"), duration=0.5)
                first = d["ranking"][0]
                rows.append({
                    "effect": name, "snr_dB": snr, "hidden": params, "first": first["effect"],
                    "found": {k: first["params"].get(k) for k in params}, "ci95": {k: first["ci95"].get(k) for k in params},
                    "selected": d["selected"], "verdict": d["verdict"],
                    "ladder_nrmse": [s["nrmse"] for s in d["steps"]], "floor_nrmse": d["noise_floor_nrmse"], "seconds": sec,
                    "cpu_seconds": cpu, "load_average_1min": os.getloadavg()[0],
                    "runner_up": d["ranking"][1]["effect"] if len(d["ranking"]) > 1 else None,
                    "margin_delta_bic": first["delta_bic"] - d["ranking"][1]["delta_bic"] if len(d["ranking"]) > 1 else None,
                    "interval_method": {k: d["identifiability"].get("intervals", {}).get(k, {}).get("method") for k in params},
                    "test_misses": misses(d, name), "floor_method": d["noise_floor"]["method"],
                })
                print(json.dumps(rows[-1]), flush=True)
        verified = Path("results/benchmarks/diagnosis_bearing_verified.json")
        if args.snr != [30.0, 10.0] or args.effects != list(HIDDEN):  # a part: the other rows of the last run are kept
            keep = [r for r in json.loads(verified.read_text()) if (r["effect"], r["snr_dB"]) not in
                    {(r["effect"], r["snr_dB"]) for r in rows}] if verified.exists() else []
            rows = keep + rows
        verified.write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
