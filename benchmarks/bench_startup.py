"""Start-up of the package and of ``piezobearing detect``: a previous revision beside this checkout.

Four commands, each in a fresh process, the two sides alternating (old, new, old, new, ...) so that both see
the same machine: ``import piezobearing``, ``piezobearing detect --help``, ``piezobearing detect`` on a 10 s,
12 kHz CWRU record (reading the .mat file, detecting, writing detection.json, report.md and detection.png), and
``snakemake -n --configfile config/ci.yaml`` in each side's own tree with nothing built (the start every dry run,
every workflow test and every run of the workflow pays: Snakemake's import, the Snakefile, the config's reading
and validation, the rules' code hashes, the DAG). Per
command and side: the median wall and CPU (user + system of the child) seconds over the runs, and their ratio
old / new; the heavy dependencies each side's ``import piezobearing`` loads (from ``sys.modules``); and each
workflow script's package imports (the start-up every job of its rule pays), in CPU seconds, and their sum.

The old side is ``--old REF`` (a git revision, exported to a temporary folder) run with this environment's
Python and its ``src`` first on ``PYTHONPATH``; the new side is this checkout (the dry run: its committed
``HEAD``, exported beside the old). On a loaded machine the wall seconds grow and the CPU seconds
much less: quote the CPU and the ratio.

    python benchmarks/bench_startup.py --old REV [--data ../shared/data/cwru_fan_end] [--runs 7]

Writes results/benchmarks/startup.json.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_workflow import export_revision

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "benchmarks" / "startup.json"
HEAVY = ("numpy", "scipy", "pandas", "matplotlib", "sfepy", "numba", "h5py", "pyuff", "nptdms", "meshio",
         "jsonschema", "snakemake")
#: The record: the fan-end set's healthy-machine record of an SKF 6203 (its rig file beside it).
RECORD = "fe05"


def timed(argv: list[str], env: dict, cwd: Path | None = None) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of ``argv`` in a child process (in folder ``cwd``)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(argv, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


#: The dry run's label: run in each side's own exported tree (the other commands run here).
DRY_RUN = "snakemake -n (CI config, nothing built)"


def commands(data: Path | None, out: Path) -> dict[str, list[str]]:
    py = sys.executable
    cli = [py, "-c", "import sys; from piezobearing.cli import main; sys.exit(main())"]
    out_cmds = {
        "import piezobearing": [py, "-c", "import piezobearing"],
        "piezobearing detect --help": [*cli, "detect", "--help"],
    }
    if data is not None:
        out_cmds["piezobearing detect (10 s at 12 kHz)"] = [
            *cli, "detect", str(data / f"{RECORD}.mat"), "--config", str(data / f"{RECORD}.yaml"), "--out", str(out),
        ]
    out_cmds[DRY_RUN] = [str(Path(py).parent / "snakemake"), "-n", "--configfile", "config/ci.yaml"]
    return out_cmds


def script_imports(script: Path) -> str:
    """The package imports of a workflow script (what its job loads before it computes), as one statement list."""
    tree = ast.parse(script.read_text())
    return "\n".join(ast.unparse(n) for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))
                     and "piezobearing" in ast.unparse(n))


def job_imports(sides: dict, old_root: Path, runs: int) -> dict:
    """CPU seconds of each workflow script's package imports, old and new side (median of ``runs``): the start-up
    every job of that rule pays before its stage computes."""
    out = {}
    for script in sorted((ROOT / "workflow" / "scripts").glob("*.py")):
        codes = {"new": script_imports(script)}
        old_script = old_root / "workflow" / "scripts" / script.name
        codes["old"] = script_imports(old_script) if old_script.is_file() else ""
        if not codes["new"] or not codes["old"]:
            continue
        cpu = {side: statistics.median(timed([sys.executable, "-c", codes[side]], sides[side])[1]
                                       for _ in range(runs)) for side in ("old", "new")}
        out[script.stem] = {"old_cpu_s": cpu["old"], "new_cpu_s": cpu["new"]}
        print(f"  job {script.stem}: old {cpu['old']:.2f} s CPU, new {cpu['new']:.2f} s CPU", flush=True)
    return out


def heavy_loaded(env: dict) -> list[str]:
    code = "import piezobearing, sys, json; print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return sorted(set(json.loads(out.stdout)) & set(HEAVY))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="git revision of the old side")
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data" / "cwru_fan_end",
                    help="folder of CWRU fan-end records (fe05.mat, fe05.yaml); the detect row needs it")
    ap.add_argument("--runs", type=int, default=7, help="counted runs per command and side (after one warm-up)")
    ap.add_argument("--job-runs", type=int, default=3,
                    help="runs of each workflow script's imports per side (0: leave the per-job start-up out)")
    args = ap.parse_args()
    data = args.data if (args.data / f"{RECORD}.mat").is_file() else None
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        old_src = export_revision(args.old, tmp / "old") / "src"
        sides = {name: {**os.environ, "PYTHONPATH": str(src)} for name, src in (("old", old_src), ("new", ROOT / "src"))}
        trees = {"old": tmp / "old", "new": export_revision("HEAD", tmp / "new")}
        rows = {}
        for label, argv in commands(data, tmp / "detect").items():
            runs: dict[str, list[tuple[float, float]]] = {"old": [], "new": []}
            for i in range(args.runs + 1):
                for side, env in sides.items():
                    shutil.rmtree(tmp / "detect", ignore_errors=True)
                    if label == DRY_RUN:  # the tree's own package, Snakefile and config
                        t = timed(argv, {**env, "PYTHONPATH": str(trees[side] / "src")}, trees[side])
                    else:
                        t = timed(argv, env)
                    if i:  # the first round warms the caches (bytecode, numba, the file)
                        runs[side].append(t)
            med = {side: {"wall_s": statistics.median(w for w, _ in r), "cpu_s": statistics.median(c for _, c in r)}
                   for side, r in runs.items()}
            rows[label] = {**med, "ratio_wall": med["old"]["wall_s"] / med["new"]["wall_s"],
                           "ratio_cpu": med["old"]["cpu_s"] / med["new"]["cpu_s"], "runs": args.runs}
            print(f"{label}: old {med['old']['wall_s']:.2f} s wall {med['old']['cpu_s']:.2f} s CPU, new "
                  f"{med['new']['wall_s']:.2f} s wall {med['new']['cpu_s']:.2f} s CPU", flush=True)
        loaded = {side: heavy_loaded(env) for side, env in sides.items()}
        jobs = job_imports(sides, old_src.parent, args.job_runs) if args.job_runs else {}
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps({"old": args.old, "record": RECORD if data else None, "commands": rows,
                               "import_piezobearing_loads": loaded, "job_imports": jobs,
                               "job_imports_cpu_s": {side: sum(j[f"{side}_cpu_s"] for j in jobs.values())
                                                     for side in ("old", "new")},
                               "cpus": os.cpu_count(),
                               "load_average": os.getloadavg()}, indent=1) + "\n")
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
