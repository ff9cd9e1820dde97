"""CPU of the LPM kernel's numba compile in a fresh clone (issue 14): a previous revision against this checkout.

For each side (``--old REV`` and the committed HEAD, each exported to a temporary folder with an empty
``__pycache__``), a fresh process runs the ``bearing_lpm`` stage on config/ci.yaml (both cases, files
written) with an empty numba cache (cold: what every fresh clone and every user's first run pays) and then
again with the cache that run left (warm). CPU seconds (user + system of the process, ``resource``),
the best of ``--repeat`` cold/warm pairs; the compile is cold minus warm. The stage's output files of the
two revisions are compared byte for byte (SHA-256).

Writes results/benchmarks/lpm_compile.json. Run from the repository root, the package's environment active:
``python benchmarks/bench_lpm_compile.py --old main``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_startup import export_revision  # benchmarks/ is on sys.path when run as a script

ROOT = Path(__file__).resolve().parents[1]

STAGE = """
import sys
from piezobearing.config import load as load_config
from piezobearing.stages import bearing as stage
out = __import__('pathlib').Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
stage.bearing_lpm(
    out / "kinematics.json",
    {c: out / f"contact_{c}.npz" for c in stage.CASES},
    {c: out / f"contact_forces_{c}.csv" for c in stage.CASES},
    out / "lpm.json",
    load_config("config/ci.yaml"),
)
"""


def cpu_of(folder: Path, cache: Path, out: Path) -> float:
    """User + system CPU seconds of one fresh process running the stage in ``folder``."""
    env = {**os.environ, "PYTHONPATH": str(folder / "src"), "NUMBA_CACHE_DIR": str(cache)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # bytecode caches on, as in a user's clone
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", STAGE, str(out)], cwd=folder, env=env, check=True, capture_output=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def side(folder: Path, repeat: int) -> dict:
    """Best cold and warm CPU over ``repeat`` pairs, and the hashes of the files written."""
    cold, warm = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as cache:
            cold.append(cpu_of(folder, Path(cache), folder / "out"))
            warm.append(cpu_of(folder, Path(cache), folder / "out"))
    files = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted((folder / "out").iterdir())}
    return {"cold_cpu_s": min(cold), "warm_cpu_s": min(warm), "compile_cpu_s": min(cold) - min(warm),
            "cold_all_s": cold, "warm_all_s": warm, "files": files}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default="main", help="git revision of the previous kernel")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_lpm_compile_"))
    old = side(export_revision(a.old, tmp / "old"), a.repeat)
    new = side(export_revision("HEAD", tmp / "new"), a.repeat)
    same = sorted(k for k in old["files"] if old["files"][k] == new["files"].get(k))
    rec = {
        "what": "bearing_lpm stage on config/ci.yaml in a fresh process: empty numba cache (cold) and filled (warm)",
        "cpu_count": os.cpu_count(),
        "load_average_1_5_15_at_end": os.getloadavg(),
        "old": {"revision": a.old, **old},
        "new": {"revision": "HEAD", **new},
        "new_over_old": {k: new[k] / old[k] for k in ("cold_cpu_s", "warm_cpu_s", "compile_cpu_s")},
        "files_byte_identical": same,
        "files_differing": sorted(set(old["files"]) - set(same)),
    }
    out = ROOT / "results/benchmarks/lpm_compile.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps({k: rec[k] for k in ("new_over_old", "files_byte_identical", "files_differing")}, indent=1))
    print({s: {k: rec[s][k] for k in ("cold_cpu_s", "warm_cpu_s", "compile_cpu_s")} for s in ("old", "new")})


if __name__ == "__main__":
    main()
