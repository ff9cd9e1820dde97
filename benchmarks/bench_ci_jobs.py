"""The CPU of the CI workflow run and of each of its jobs, the previous code beside this checkout's (issue 14, CI row).

The run is the one the test suite's ``ci_run`` fixture makes (tests/conftest.py): ``python tests/warm_jobs.py
--cores 2 all study_all --configfile config/ci.yaml`` in a fresh copy of a tree (its Python script jobs forked warm
from a server of that tree; the notebooks papermill runs). For each side (``--old REF``, a git revision, and
``--new REF``, default ``HEAD``; each exported to a fresh folder a run, with its own package on PYTHONPATH, so its
numba cache and bytecode start empty as in a fresh clone) the run repeats ``-n`` times, old and new alternating,
one at a time. Measured: the whole run's CPU (user + system of every process, ``getrusage`` of the children) and
wall, and each job's CPU from its rule's ``benchmark:`` file (tests/warm_jobs.py writes the forked child's CPU
there; a notebook's is Snakemake's own measurement). The machine may be shared: compare the medians' ratio, and
the spread (min, max) says how much to trust it. Then every JSON and CSV result of the first old and new runs is
compared as the reproducibility test does (results/logs, benchmarks and notebooks left out):
byte-identical, or the largest relative difference of their numbers (bench_workflow.compare_results); and their
figures (PNG), byte for byte.

Writes ``results/benchmarks/ci_jobs.json``. Usage (repository root, the package's environment active)::

    python benchmarks/bench_ci_jobs.py --old main -n 3
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_startup import export_revision  # benchmarks/ is on sys.path when run as a script
from bench_workflow import compare_results

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["--cores", "2", "all", "study_all", "--configfile", "config/ci.yaml"]
#: What the comparison leaves out, as the reproducibility test does (tests/conftest.py, NUMBERS_SKIP), and the
#: figures (PNG/PDF: drawn by matplotlib, not numbers).
SKIP_SUFFIXES = (".png", ".pdf", ".svg", ".vtk", ".npz", ".html", ".ipynb", ".log")


def job_cpu(folder: Path) -> dict[str, float]:
    """CPU seconds of each job of a finished run, from its benchmark file (results/benchmarks/rules/**.tsv)."""
    out = {}
    rules = folder / "results/benchmarks/rules"
    for f in sorted(rules.rglob("*.tsv")):
        head, last = f.read_text().strip().splitlines()[:2]
        out[f.relative_to(rules).with_suffix("").as_posix()] = float(dict(zip(head.split("\t"), last.split("\t"),
                                                                               strict=True))["cpu_time"])
    return out


def one_run(rev: str, tmp: Path, k: int) -> tuple[dict, Path]:
    """One warm CI run of revision ``rev`` in a fresh export; (its record, its folder)."""
    folder = export_revision(rev, tmp / f"{rev.replace('/', '_')}_{k}")
    bindir = Path(sys.executable).parent  # left out of PATH, as the tests' workflow runs do (workflow_env)
    path = os.pathsep.join(p for p in os.environ["PATH"].split(os.pathsep) if p and Path(p) != bindir)
    env = {**os.environ, "PATH": path, "PYTHONPATH": str(folder / "src")}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as the test suite runs (tests/conftest.py turns bytecode caches on)
    r0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    out = subprocess.run([sys.executable, "tests/warm_jobs.py", *ARGS], cwd=folder, env=env, capture_output=True,
                         text=True)
    wall, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"{rev}: the CI run failed\n{out.stderr[-3000:]}")
    cpu = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
    return {"cpu_s": cpu, "wall_s": wall, "jobs_cpu_s": job_cpu(folder)}, folder


def summary(values: list[float]) -> dict:
    return {"median": statistics.median(values), "min": min(values), "max": max(values), "runs": values}


def figures(folder: Path) -> dict[str, bytes]:
    """The run's figures (results/**.png), by path."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted((folder / "results").rglob("*.png"))}


def number_files(folder: Path) -> None:
    """Leave only the number files (JSON, CSV) the reproducibility test compares, outside its skipped folders."""
    for p in (folder / "results").rglob("*"):
        if p.is_file() and p.suffix in SKIP_SUFFIXES:
            p.unlink()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default="main", help="git revision of the previous code")
    ap.add_argument("--new", default="HEAD", help="git revision of the new code")
    ap.add_argument("-n", type=int, default=3, help="runs of each side, alternating")
    ap.add_argument("--out", default="results/benchmarks/ci_jobs.json")
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_ci_jobs_"))
    runs: dict[str, list[dict]] = {"old": [], "new": []}
    first: dict[str, Path] = {}
    for k in range(a.n):
        for side, rev in (("old", a.old), ("new", a.new)):
            rec, folder = one_run(rev, tmp, k)
            runs[side].append(rec)
            first.setdefault(side, folder)
            print(f"{side} {k}: {rec['cpu_s']:.1f} CPU s, {rec['wall_s']:.1f} s", file=sys.stderr, flush=True)
    sides = {}
    for side, recs in runs.items():
        jobs = sorted(set().union(*(r["jobs_cpu_s"] for r in recs)))
        sides[side] = {
            "revision": a.old if side == "old" else a.new,
            "cpu_s": summary([r["cpu_s"] for r in recs]),
            "wall_s": summary([r["wall_s"] for r in recs]),
            "jobs_cpu_s": {j: summary([r["jobs_cpu_s"].get(j, 0.0) for r in recs]) for j in jobs},
        }
    jobs = sorted(set(sides["old"]["jobs_cpu_s"]) | set(sides["new"]["jobs_cpu_s"]))
    per_job = {}
    for j in jobs:
        o = sides["old"]["jobs_cpu_s"].get(j, {"median": 0.0})["median"]
        n = sides["new"]["jobs_cpu_s"].get(j, {"median": 0.0})["median"]
        per_job[j] = {"old_s": o, "new_s": n, "saved_s": o - n}
    per_job = dict(sorted(per_job.items(), key=lambda kv: -kv[1]["saved_s"]))
    same_figures = figures(first["old"]) == figures(first["new"])
    for folder in first.values():
        number_files(folder)
    result = {
        "what": f"python tests/warm_jobs.py {' '.join(ARGS)} in a fresh export, old and new alternating, "
                f"{a.n} runs each (CPU: user + system of every process)",
        "old": sides["old"],
        "new": sides["new"],
        "new_over_old": {k: sides["new"][k]["median"] / sides["old"][k]["median"] for k in ("cpu_s", "wall_s")},
        "jobs_median_cpu_s": per_job,
        "load_average_1_5_15_at_end": os.getloadavg(),
        "results": compare_results(first["old"], first["new"]),
        "figures_byte_identical": same_figures,
    }
    out = ROOT / a.out
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps({k: result[k] for k in ("new_over_old",)}, indent=1))
    print(json.dumps({k: {"cpu_s": sides[k]["cpu_s"]["median"]} for k in sides}))
    print(result["results"]["counts"])


if __name__ == "__main__":
    main()
