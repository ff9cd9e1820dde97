"""Run time and peak memory of the sensor_comparison study's cases; the study's SLURM resources come from here.

    python benchmarks/bench_sensor_comparison.py [--configfile config/ci.yaml] [--cases 2] [--from-rules]

``--from-rules``: gathers what Snakemake measured for every case of the study's last run instead (the
study_case rule's benchmark files, results/benchmarks/rules/study_case_sensor_comparison/*.tsv: seconds and
max RSS per case). Otherwise runs the first ``--cases`` cases of the config's ``sensor_comparison`` table, each in a child process (the
study_case rule's function, :func:`piezobearing.stages.studies.run_case`, on the workflow's resistance fit and
sensor FEM response, which must exist: run the workflow on the config first), and records per case the wall
and CPU seconds and the child's peak RSS. Writes results/benchmarks/sensor_comparison.json beside the rule's
resources in workflow/rules/studies.smk (STUDY_MEM_MB, STUDY_RUNTIME_MIN) for the comparison.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd

REPO = Path(__file__).resolve().parents[1]

# One case in this process; prints its wall and CPU seconds and peak RSS [kB] as JSON.
_CHILD = """
import json, resource, sys, time
from piezobearing import config as cfgmod
from piezobearing.stages.studies import run_case
from piezobearing.studies import check_studies
config = cfgmod.load(*sys.argv[1:2])
table = check_studies(config)["sensor_comparison"]
row = {k: v for k, v in table.iloc[int(sys.argv[2])].to_dict().items()}
inputs = json.loads(sys.argv[3])
t0, c0 = time.perf_counter(), time.process_time()
run_case("sensor_comparison", f"bench{sys.argv[2]}", row, config, sys.argv[4], inputs)
print(json.dumps({"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "overrides": row}))
"""


def _resources() -> dict:
    """The study's resources as studies.smk declares them."""
    text = (REPO / "workflow/rules/studies.smk").read_text()
    out = {}
    for key, name in (("mem_mb", "STUDY_MEM_MB"), ("runtime_min", "STUDY_RUNTIME_MIN")):
        block = text[text.index(f"{name} = {{"):]
        block = block[: block.index("\n}")]
        m = re.search(r'"sensor_comparison":\s*([0-9.]+)', block)
        out[key] = float(m.group(1)) if m else None
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--configfile", default="config/ci.yaml")
    ap.add_argument("--cases", type=int, default=2)
    ap.add_argument("--out", default="results/benchmarks/sensor_comparison.json")
    ap.add_argument("--from-rules", action="store_true", help="gather the study_case rule's benchmark files")
    args = ap.parse_args()
    sys.path.insert(0, str(REPO / "src"))
    from piezobearing import config as cfgmod
    from piezobearing.config import results_folder
    from piezobearing.studies import check_studies

    config = cfgmod.load(args.configfile)
    results = REPO / results_folder(config)
    inputs = {"resistance": str(results / "calibration/resistance.json")}
    if config["signals"]["sensor_fem_correction"]:
        inputs["harmonic"] = str(results / "sensor/harmonic.csv")
    n = min(args.cases, len(check_studies(config)["sensor_comparison"]))
    cases = []
    if args.from_rules:
        for tsv in sorted((results / "benchmarks/rules/study_case_sensor_comparison").glob("*.tsv")):
            row = pd.read_csv(tsv, sep="\t").iloc[0]
            cases.append({"case": tsv.stem, "wall_s": float(row["s"]), "cpu_s": float(row["cpu_time"]),
                          "peak_rss_mb": float(row["max_rss"])})
        n = 0
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(n):
            out = subprocess.run(
                [sys.executable, "-c", _CHILD, args.configfile, str(i), json.dumps(inputs), f"{tmp}/{i}/summary.json"],
                cwd=REPO, capture_output=True, text=True, check=True,
            )
            cases.append(json.loads(out.stdout.strip().splitlines()[-1]))
            print(cases[-1], file=sys.stderr)
    if not cases:
        raise SystemExit("no cases measured: run the study first (snakemake ... study_all) or drop --from-rules")
    record = {
        "configfile": args.configfile,
        "source": "the study_case rule's benchmark files" if args.from_rules else "each case in a child process",
        "n_seeds": config["sensor_comparison"]["n_seeds"],
        "cases": cases,
        "max_wall_s": max(c["wall_s"] for c in cases),
        "max_peak_rss_mb": max(c["peak_rss_mb"] for c in cases),
        "declared": _resources(),
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
