"""The sensor comparison's calibrated test, per seed: the CPU seconds of one rig realisation (the LPM with the
healthy bearing's floor, the housing, both sensors' chains and DAQs, the envelope detector on each record), at
rest and under base motion, and what a case of ``n_healthy_seeds`` + ``n_faulty_seeds`` costs at that rate.

    python benchmarks/bench_calibrated_seed.py [--configfile config/config.yaml] [--seeds 3] \\
        [--results results/sensor_comparison_calibrated]
    python benchmarks/bench_calibrated_seed.py --from-runs results/validation/calibrated_paper.jsonl.cpu.jsonl

The first form runs ``--seeds`` healthy and as many faulty seeds per condition in this process (the functions of
``validation/sensor_comparison_calibrated.py`` and of the study: :func:`piezobearing.comparison.rig.realise`,
:func:`~piezobearing.comparison.rig.observe`), after one warm-up seed (the compiled kernels' first call); it needs
the workflow's resistance fit, sensor FEM response and the comparison's housing models under ``--results`` (run
``snakemake --cores 1 study_sensor_comparison --configfile config/sensor_comparison_calibrated.yaml --omit-from
study_case`` first). ``--from-runs`` reads instead the per-seed CPU seconds the runner wrote beside its results
(``<out>.cpu.jsonl``: every seed of a long run, each timed by ``time.process_time`` around the same two calls).
Cases whose label is ``frame`` or ends in ``_frame`` count as under base motion, the others as at rest (the
labels of docs/validation/sensor_comparison.md's runs); a file's
other cases (width sweeps: faulty seeds only) count too. CPU seconds, not wall: the machine may be shared.

Writes results/benchmarks/calibrated_seed.json.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import sys
import time
from pathlib import Path

from piezobearing import config as config_loader
from piezobearing.chain import signals as signal_outputs
from piezobearing.comparison import rig as comparison
from piezobearing.config.cases import case_config
from piezobearing.io import read_harmonic, read_json

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "results" / "benchmarks" / "calibrated_seed.json"
CONDITIONS = {"at_rest": "base_motion__level=0.0", "base_motion": "base_motion__level=1.0"}


def summary(cpu: list[float]) -> dict:
    """Median, quartiles, extremes and count of per-seed CPU seconds."""
    q = statistics.quantiles(cpu, n=4) if len(cpu) >= 2 else [cpu[0]] * 3
    return {"seeds": len(cpu), "median_cpu_s": statistics.median(cpu), "q1_cpu_s": q[0], "q3_cpu_s": q[2],
            "min_cpu_s": min(cpu), "max_cpu_s": max(cpu)}


def condition_of(label: str) -> str:
    return "base_motion" if label == "frame" or label.endswith("_frame") else "at_rest"


def from_runs(paths: list[str]) -> dict:
    """The per-seed CPU seconds of the runner's ``.cpu.jsonl`` files, per condition and healthy / faulty."""
    out = {c: {"healthy": [], "faulty": []} for c in CONDITIONS}
    for p in paths:
        for line in Path(p).read_text().splitlines():
            r = json.loads(line)
            out[condition_of(r["case"])]["faulty" if r["faulty"] else "healthy"].append(float(r["cpu_s"]))
    return {"source": "the runner's per-seed CPU records", "files": [str(p) for p in paths],
            "conditions": {c: {k: summary(v) for k, v in d.items() if v} for c, d in out.items()}}


def measure(configfile: list[str], results: Path, seeds: int) -> dict:
    """Run ``seeds`` healthy and faulty seeds per condition here, each timed."""
    sys.path.insert(0, str(REPO / "validation"))
    # the runner's own helpers: a script under validation/, importable only once that folder is on the path
    import sensor_comparison_calibrated as runner

    base = config_loader.load(*configfile)
    resistance_path = str(results / "calibration" / "resistance.json")
    resistance = read_json(resistance_path)
    conditions, n_case = {}, None
    for name, text in CONDITIONS.items():
        _, overrides = runner.parse_case(f"{name}:{text}")
        cfg = case_config(base, overrides, source=f"case {name}")
        circuit = signal_outputs.sensor_circuit(cfg, resistance, resistance_path)
        harmonic = read_harmonic(str(results / "sensor" / "harmonic.csv")) if cfg["signals"][
            "sensor_fem_correction"] else None
        housings = runner.housings_for(cfg, str(results / "sensor_comparison" / "housing"))
        if housings is None:
            raise SystemExit(f"no housing models for this config under {results}/sensor_comparison/housing: run the "
                             "workflow's sensor_comparison_housing rule first (see this script's docstring)")
        rig = comparison.prepare(cfg, circuit, harmonic, housings)
        c = cfg["sensor_comparison"]
        n_case = (c["n_healthy_seeds"], c["n_faulty_seeds"])
        comparison.observe(rig, *comparison.realise(rig, False, 10_000), False, 10_000)  # warm-up, not timed
        cpu = {"healthy": [], "faulty": []}
        for faulty in (False, True):
            for rep in range(seeds):
                t = time.process_time()
                run, clean = comparison.realise(rig, faulty, rep)
                comparison.observe(rig, run, clean, faulty, rep)
                cpu["faulty" if faulty else "healthy"].append(time.process_time() - t)
        conditions[name] = {k: summary(v) for k, v in cpu.items()}
    return {"source": "seeds run in this process", "configfile": configfile, "conditions": conditions,
            "case_seeds": list(n_case), "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--configfile", nargs="+", default=["config/config.yaml"])
    ap.add_argument("--results", default="results/sensor_comparison_calibrated", type=Path,
                    help="the workflow's results folder for the config (resistance, harmonic, housing models)")
    ap.add_argument("--seeds", type=int, default=3, help="healthy and faulty seeds per condition")
    ap.add_argument("--from-runs", nargs="+", default=None, help="the runner's <out>.cpu.jsonl files instead")
    ap.add_argument("--case-seeds", nargs=2, type=int, default=None, metavar=("HEALTHY", "FAULTY"),
                    help="the case size the cost is given for (default: the config's n_healthy/n_faulty_seeds)")
    ap.add_argument("--out", default=str(OUT))
    a = ap.parse_args(argv)
    record = from_runs(a.from_runs) if a.from_runs else measure(a.configfile, a.results, a.seeds)
    if a.case_seeds or "case_seeds" not in record:
        record["case_seeds"] = list(a.case_seeds or (200, 100))
    nh, nf = record["case_seeds"]
    for d in record["conditions"].values():
        # the median seed of each kind times the case's count of that kind
        both = "healthy" in d and "faulty" in d
        d["case_cpu_s"] = nh * d["healthy"]["median_cpu_s"] + nf * d["faulty"]["median_cpu_s"] if both else None
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record["conditions"], indent=1))


if __name__ == "__main__":
    main()
