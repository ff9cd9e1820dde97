"""The start of every workflow job: the imports of its script, the previous code beside this checkout's, as ratios.

Each ``workflow/scripts/*.py`` job starts a fresh Python process that imports the package modules of its stage
before it does any work (the whole paper runs about 30 such jobs, the CI workflow as many). For every script,
its ``from piezobearing... import ...`` lines run alone in a fresh process (``python -c``), once with the old
revision's package (``--old REV``, exported to a temporary folder) and once with this checkout's committed
HEAD, in turn (old, new, old, new ...), ``-n`` pairs; the CPU seconds (user + system of the child) are
recorded and the ratio taken pair by pair, which keeps it meaningful on a shared machine. The import of
scipy.signal, scipy.stats, scipy.optimize and scipy.constants at the top of modules every stage imports cost
most of it; they are now imported in the functions that use them.

Writes ``results/benchmarks/job_start.json``. Usage: ``python benchmarks/bench_job_start.py --old main [-n 5]``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_startup import export_revision  # benchmarks/ is on sys.path when run as a script

ROOT = Path(__file__).resolve().parents[1]


def script_imports(folder: Path) -> dict[str, str]:
    """Per workflow script (name without .py): its package import lines, as one ``python -c`` program."""
    out = {}
    for f in sorted((folder / "workflow/scripts").glob("*.py")):
        lines = [ln for ln in f.read_text().splitlines() if re.match(r"(from|import) piezobearing\b", ln)]
        if lines:
            out[f.stem] = "\n".join(lines)
    return out


def cpu_of(folder: Path, program: str) -> float:
    """CPU seconds (user + system) of a fresh ``python -c PROGRAM`` with ``folder``'s package."""
    env = {**os.environ, "PYTHONPATH": str(folder / "src")}
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", program], cwd=folder, env=env, check=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default="main")
    ap.add_argument("-n", type=int, default=5)
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_job_start_"))
    old, new = export_revision(a.old, tmp / "old"), export_revision("HEAD", tmp / "new")
    progs_old, progs_new = script_imports(old), script_imports(new)
    jobs = {}
    for name in sorted(set(progs_old) & set(progs_new)):
        cpu_of(old, progs_old[name]), cpu_of(new, progs_new[name])  # warm-up: bytecode, page cache
        pairs = [(cpu_of(old, progs_old[name]), cpu_of(new, progs_new[name])) for _ in range(a.n)]
        jobs[name] = {
            "old_cpu_s": statistics.median(p[0] for p in pairs),
            "new_cpu_s": statistics.median(p[1] for p in pairs),
            "new_over_old": statistics.median(p[1] / p[0] for p in pairs),
        }
        print(name, jobs[name], flush=True)
    total_old = sum(j["old_cpu_s"] for j in jobs.values())
    total_new = sum(j["new_cpu_s"] for j in jobs.values())
    rec = {
        "what": "the package imports of each workflow/scripts/*.py job, a fresh python -c process, CPU seconds "
                "(user + system), median of pairs",
        "old_revision": a.old,
        "runs": a.n,
        "sum_over_scripts": {"old_cpu_s": total_old, "new_cpu_s": total_new, "new_over_old": total_new / total_old},
        "load_average_1_5_15_at_end": os.getloadavg(),
        "jobs": jobs,
    }
    out = ROOT / "results/benchmarks/job_start.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps(rec["sum_over_scripts"], indent=1))


if __name__ == "__main__":
    main()
