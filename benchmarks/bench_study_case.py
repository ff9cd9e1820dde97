"""One parameter-study case: what running the workflow's rules in memory costs against running their stages
through files.

Runs, in fresh processes, one ``fault_detection`` case and one ``calibration_circuit`` case
(``stages.studies.run_case``) on the CI config cut to a 0.35 s bearing record (coarse housing mesh, 5 noise
seeds, as ``tests/test_signals_fault_study.py``), and records wall and CPU time, the child's peak RSS and the
bytes written into the case folder. With ``--old-src DIR`` (the ``src`` folder of a checkout before the one
pipeline, whose study kinds ran the stages into the case folder and deleted the large files) the same cases
run with both codes, with their ratios (new / old) and a check that the summaries are byte-identical.

Usage: ``python benchmarks/bench_study_case.py [--old-src ../old/src] [--repeat 2]``; writes
results/benchmarks/study_case.json. Times depend on the machine's load; the bytes do not.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "results" / "benchmarks" / "study_case.json"

CHILD = r"""
import json, resource, sys, time
from pathlib import Path
from piezobearing import config
from piezobearing.stages.studies import run_case
kind, work = sys.argv[1], Path(sys.argv[2])
c = config.load(CONFIG / "ci.yaml")
c["bearing"].update(duration_s=0.35, settle_s=0.01)
c["housing"].update(mesh_level=0.35, n_modes=4)
c["signals"].update(study_n_seeds=5, sensor_fem_correction=False)
res = work / "resistance.json"
res.write_text(json.dumps({"resistance_ohm": 50.0e6}))
ov, inputs = {}, {}
if kind == "fault_detection":
    ov, inputs = {"bearing__shaft_speed_rpm": 1200.0}, {"resistance": str(res)}
out = work / "case" / "summary.json"
t0, c0 = time.perf_counter(), time.process_time()
run_case(kind, "case", ov, c, str(out), inputs)
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
files = [p for p in out.parent.iterdir()]
print(json.dumps({"wall_s": wall, "cpu_s": cpu, "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "files_left": len(files), "bytes_left": sum(p.stat().st_size for p in files),
                  "summary": out.read_text()}))
"""


def measure(kind: str, src: str | None) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1")
    if src:
        env["PYTHONPATH"] = str(Path(src).resolve())
    with tempfile.TemporaryDirectory() as d:
        out = subprocess.run([sys.executable, "-c", CHILD, kind, d], env=env, capture_output=True, text=True,
                             check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-src", help="src folder of a checkout before the one pipeline: both codes, ratios")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each case and code (the fastest is kept)")
    args = ap.parse_args()
    rows = {}
    for kind in ("fault_detection", "calibration_circuit"):
        codes = {"new": None, **({"old": args.old_src} if args.old_src else {})}
        runs = {name: [measure(kind, src) for _ in range(args.repeat)] for name, src in codes.items()}
        best = {name: min(r, key=lambda x: x["wall_s"]) for name, r in runs.items()}
        row = {name: {k: v for k, v in b.items() if k != "summary"} for name, b in best.items()}
        if "old" in best:
            row["new_over_old"] = {k: best["new"][k] / best["old"][k] for k in ("wall_s", "cpu_s", "peak_rss_MB")}
            row["summary_identical"] = best["new"]["summary"] == best["old"]["summary"]
        rows[kind] = row
        print(kind, json.dumps(row, indent=1), flush=True)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps({"cases": rows, "repeat": args.repeat}, indent=2) + "\n")


if __name__ == "__main__":
    main()
