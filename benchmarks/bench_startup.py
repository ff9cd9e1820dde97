"""Snakemake's start-up on this workflow (``snakemake -n``), the previous code beside this checkout's, as ratios.

Every ``snakemake`` call parses the Snakefile, which hashes the package code each rule runs
(``registry.code_hash``): a dry run, each of the rerun test's 42 dry runs, the start of every real run. The same
dry run warm (a child forked from each tree's own ``tests/warm_snakemake.py`` server, as the tests ask theirs),
old and new in turn too.
``--old REV`` (a git revision) is exported to a temporary folder; the two run in turn (old, new, old, new
...), each a fresh process, and each call's CPU seconds (user + system, this process's children) and wall
seconds are recorded; the ratio is taken pair by pair, which keeps it meaningful on a shared machine.

Writes ``results/benchmarks/startup.json``. Usage: ``python benchmarks/bench_startup.py --old main [-n 5]``.
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

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def export_revision(rev: str, dest: Path) -> Path:
    """Revision ``rev`` of this repository as a plain folder ``dest`` (with an empty ``data/``)."""
    dest.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", rev], cwd=ROOT, capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    (dest / "data").mkdir(exist_ok=True)
    return dest


def timed(folder: Path, args: list[str]) -> dict:
    """One ``snakemake ARGS`` in ``folder`` with its own package (PYTHONPATH): CPU and wall seconds."""
    env = {**os.environ, "PYTHONPATH": str(folder / "src")}
    r0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    out = subprocess.run([str(BIN / "snakemake"), *args], cwd=folder, env=env, capture_output=True, text=True)
    wall, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-2000:])
    return {"cpu_s": r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime, "wall_s": wall}


def warm_server(folder: Path):
    """The warm Snakemake server of the tree ``folder`` (its own tests/warm_snakemake.py, its package)."""
    import importlib.util

    sys.path.insert(0, str(folder / "tests"))  # the tree's own tests/warm_jobs.py (its ForkServer), not another's
    sys.modules.pop("warm_jobs", None)
    spec = importlib.util.spec_from_file_location(f"warm_snakemake_{folder.name}", folder / "tests/warm_snakemake.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.WarmSnakemake({**os.environ, "PYTHONPATH": str(folder / "src")})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default="main")
    ap.add_argument("-n", type=int, default=5)
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_startup_"))
    old, new = export_revision(a.old, tmp / "old"), export_revision("HEAD", tmp / "new")
    args = ["-n", "--configfile", "config/ci.yaml"]
    timed(old, args), timed(new, args)  # warm-up: bytecode compiled, files in the page cache
    pairs = [(timed(old, args), timed(new, args)) for _ in range(a.n)]
    servers = {}
    server_start = {}
    for side, folder in (("old", old), ("new", new)):  # one at a time: each server's own start, CPU seconds
        c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        probe = warm_server(folder)
        probe.close()
        c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        server_start[side] = c1.ru_utime - c0.ru_utime + c1.ru_stime - c0.ru_stime
        servers[side] = warm_server(folder)
    warm_pairs = []
    for _ in range(a.n):  # old, new, old, new, ...: each side's children from its own tree's server and package
        pair = []
        for side, folder in (("old", old), ("new", new)):
            t0 = time.perf_counter()
            assert servers[side].run(args, folder).returncode == 0
            pair.append({"cpu_s": servers[side].last_cpu_s, "wall_s": time.perf_counter() - t0})
        warm_pairs.append(pair)
    for server in servers.values():
        server.close()
    warm_runs = [p[1] for p in warm_pairs]
    rec = {
        "what": "snakemake -n --configfile config/ci.yaml (a clean folder: every job listed), a fresh process",
        "old_revision": a.old,
        "runs": a.n,
        "old": {k: statistics.median(p[0][k] for p in pairs) for k in ("cpu_s", "wall_s")},
        "new": {k: statistics.median(p[1][k] for p in pairs) for k in ("cpu_s", "wall_s")},
        "new_over_old_median_of_pairs": {
            k: statistics.median(p[1][k] / p[0][k] for p in pairs) for k in ("cpu_s", "wall_s")
        },
        "pairs": pairs,
        "new_warm": {k: statistics.median(r[k] for r in warm_runs) for k in ("cpu_s", "wall_s")},
        "new_warm_note": "the same dry run as a child forked from tests/warm_snakemake.py's server (Snakemake "
        "and the package imported once), as the rerun test asks its 42 dry runs",
        "old_warm": {k: statistics.median(p[0][k] for p in warm_pairs) for k in ("cpu_s", "wall_s")},
        "old_warm_note": "the old revision's own tests/warm_snakemake.py server and package",
        "warm_new_over_old_median_of_pairs": {
            k: statistics.median(p[1][k] / p[0][k] for p in warm_pairs) for k in ("cpu_s", "wall_s")
        },
        "warm_pairs": warm_pairs,
        "warm_server_start_cpu_s": server_start,
        "load_average_1_5_15_at_end": os.getloadavg(),
    }
    out = ROOT / "results/benchmarks/startup.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps({k: rec[k] for k in ("old", "new", "new_over_old_median_of_pairs", "old_warm", "new_warm",
                                          "warm_new_over_old_median_of_pairs", "warm_server_start_cpu_s")},
                     indent=1))


if __name__ == "__main__":
    main()
