"""The CI test suite's cost (issue 14: `.ci/run` within 3 min), one revision beside another, and its parts.

``suite``: ``CI=true pytest -n 2 --dist loadgroup -q --durations=0`` in a detached git worktree of each revision
(the package imported from that worktree's ``src``), one after the other; for each its wall seconds, its CPU
seconds (user + system of pytest and every process it waited for: the xdist workers, the Snakemake runs and their
jobs, the warm servers), the pass/fail line and the per-file sums of the ``--durations`` lines (setup + call +
teardown, wall seconds of each worker). ``--which old|new`` runs one side and keeps the other's entry, so the two
can run at different times (say so; compare CPU seconds, which a shared machine inflates far less than wall).

``rerun``: the reproducibility rerun (``ci_rerun``) both ways in fresh copies of this checkout: ``snakemake``
with every script job a fresh process, and ``tests/warm_jobs.py`` (script jobs forked warm); CPU seconds of each
and whether the two runs' number files are byte-identical.

``clone``: what CI runs, for each revision: a fresh ``git clone`` of it, then its own ``.ci/run`` (venv, install,
tests) with ``CI=true``, one revision after the other; ``PYTEST_ADDOPTS`` adds ``--durations=0`` for the per-file
sums. For each its wall and CPU seconds (the install's and the tests' together, every process waited for), the
largest process's peak RSS, pytest's own line and seconds, and the per-file sums. Both sides install from the same
pip cache; run it on an otherwise idle machine (the wall seconds are the target's unit).

``files``: some test files (default: the tests that start Snakemake besides the CI workflow runs, :data:`FILES`)
in a detached worktree of each revision, old and new in turn, ``-n`` pairs (default 3; the first pair compiles
the worktrees' bytecode and is kept apart as the warm-up); CPU and wall seconds of each run, the median of the
pairs' CPU ratios, each side's pass/fail line, and each test's seconds (setup + call + teardown) of the last pair.

``ci_run``: the CI workflow run of the ``ci_run`` fixture (``all study_all`` on config/ci.yaml, warm script jobs),
in fresh copies of this checkout, the way ``--old REV``'s tests ran it (a fresh ``python tests/warm_jobs.py``
process with that revision's tests/warm_jobs.py) and the way this checkout's do (a child forked from a
tests/warm_snakemake.py server, which the worker starts anyway for its other workflow tests: its start is
measured once apart; the job server keeping one scheduler re-evaluation timer), alternating, ``-n`` pairs: CPU
seconds of each run (every process under it), of its script jobs (the job server's children) and the rest (Snakemake,
the job server's start, the notebooks' papermill runs), the medians' ratio, and the two ways' number files compared
byte for byte (the reproducibility test's files).

``--key NAME`` stores a ``files`` result under NAME instead of ``snakemake_tests`` (several sets side by side).

Writes ``results/benchmarks/ci_tests.json``. Usage:
``python benchmarks/bench_ci_tests.py suite --old REV [--new HEAD] [--which both|old|new]``,
``python benchmarks/bench_ci_tests.py rerun``, ``python benchmarks/bench_ci_tests.py clone --old REV [--new HEAD]``,
``python benchmarks/bench_ci_tests.py files --old REV [--new HEAD] [-n 3] [--key NAME] [TEST ...]``,
``python benchmarks/bench_ci_tests.py ci_run --old REV [-n 3]``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results/benchmarks/ci_tests.json"
BIN = Path(sys.executable).parent


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(cmd: list[str], cwd: Path, env: dict | None = None) -> tuple[subprocess.CompletedProcess, float, float]:
    """Run ``cmd``; (its result, CPU seconds of it and its waited-for descendants, wall seconds)."""
    c0, t0 = _cpu_children(), time.perf_counter()
    out = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    return out, _cpu_children() - c0, time.perf_counter() - t0


def per_file(durations: str) -> dict[str, float]:
    """Sums of the ``--durations=0`` lines per test file (setup + call + teardown)."""
    out: dict[str, float] = defaultdict(float)
    for m in re.finditer(r"^([\d.]+)s (?:call|setup|teardown)\s+(\S+?)::", durations, re.M):
        out[m.group(2)] += float(m.group(1))
    return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def suite(rev: str, tmp: Path) -> dict:
    """The CI test command in a detached worktree of ``rev``."""
    sha = subprocess.run(["git", "rev-parse", rev], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    wt = tmp / sha[:10]
    subprocess.run(["git", "worktree", "add", "--detach", str(wt), sha], cwd=ROOT, capture_output=True, check=True)
    try:
        env = {**os.environ, "CI": "true", "PYTHONPATH": str(wt / "src")}
        cmd = [str(BIN / "pytest"), "-n", "2", "--dist", "loadgroup", "-q", "--durations=0", "-p", "no:cacheprovider"]
        out, cpu, wall = timed(cmd, wt, env)
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(wt)], cwd=ROOT, capture_output=True)
    summary = [ln for ln in out.stdout.splitlines() if re.search(r"\d+ (passed|failed)", ln)]
    return {
        "revision": sha,
        "returncode": out.returncode,
        "summary": summary[-1] if summary else out.stdout[-500:],
        "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1),
        "load_average_after": os.getloadavg(),
        "per_file_worker_s": {k: round(v, 1) for k, v in per_file(out.stdout).items()},
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }


#: The tests that start Snakemake other than through the CI workflow runs (``ci_run``, ``ci_rerun``).
FILES = (
    "tests/test_workflow_rerun.py",
    "tests/test_bad_inputs.py",
    "tests/test_workflow_quality.py::test_ruff_is_clean",
    "tests/test_workflow_quality.py::test_snakefmt_is_clean",
    "tests/test_workflow_quality.py::test_snakemake_lint_is_clean",
    "tests/test_workflow_quality.py::test_slurm_profile_dry_run",
)


def per_test(durations: str) -> dict[str, float]:
    """Seconds per test of the ``--durations=0`` lines (setup + call + teardown)."""
    out: dict[str, float] = defaultdict(float)
    for m in re.finditer(r"^([\d.]+)s (?:call|setup|teardown)\s+(\S+)", durations, re.M):
        out[m.group(2)] += float(m.group(1))
    return {k: round(v, 2) for k, v in sorted(out.items(), key=lambda kv: -kv[1])}


def files(old: str, new: str, tests: list[str], n: int, tmp: Path) -> dict:
    """``pytest TESTS`` in detached worktrees of ``old`` and ``new``, in turn, ``n`` pairs."""
    import statistics

    trees = {}
    for side, rev in (("old", old), ("new", new)):
        sha = subprocess.run(["git", "rev-parse", rev], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.strip()
        trees[side] = (sha, tmp / side)
        subprocess.run(["git", "worktree", "add", "--detach", str(tmp / side), sha], cwd=ROOT, capture_output=True,
                       check=True)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    cmd = [str(BIN / "pytest"), "-q", "--durations=0", "-p", "no:cacheprovider", *tests]
    runs: dict[str, list] = {"old": [], "new": []}
    try:
        for _ in range(n):
            for side in ("old", "new"):
                wt = trees[side][1]
                out, cpu, wall = timed(cmd, wt, {**env, "CI": "true", "PYTHONPATH": str(wt / "src")})
                summary = [ln for ln in out.stdout.splitlines() if re.search(r"\d+ (passed|failed)", ln)]
                runs[side].append({"cpu_s": round(cpu, 2), "wall_s": round(wall, 2), "returncode": out.returncode,
                                   "summary": summary[-1] if summary else out.stdout[-500:],
                                   "per_test_s": per_test(out.stdout), "load_average": os.getloadavg()})
    finally:
        for side in ("old", "new"):
            subprocess.run(["git", "worktree", "remove", "--force", str(trees[side][1])], cwd=ROOT,
                           capture_output=True)
    all_pairs = list(zip(runs["old"], runs["new"], strict=True))
    pairs = all_pairs[1:] or all_pairs
    return {
        "tests": list(tests),
        "old_revision": trees["old"][0],
        "new_revision": trees["new"][0],
        "pairs_after_warm_up": len(pairs),
        "old_cpu_s": [r["cpu_s"] for r in runs["old"]],
        "new_cpu_s": [r["cpu_s"] for r in runs["new"]],
        "old_wall_s": [r["wall_s"] for r in runs["old"]],
        "new_wall_s": [r["wall_s"] for r in runs["new"]],
        "cpu_ratio_old_over_new_median": round(statistics.median(o["cpu_s"] / w["cpu_s"] for o, w in pairs), 2),
        "old_summary": runs["old"][-1]["summary"],
        "new_summary": runs["new"][-1]["summary"],
        "all_passed": all(r["returncode"] == 0 for side in runs.values() for r in side),
        "old_per_test_s_last": runs["old"][-1]["per_test_s"],
        "new_per_test_s_last": runs["new"][-1]["per_test_s"],
        "load_average": [r["load_average"] for side in ("old", "new") for r in runs[side]],
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }


def clone(rev: str, tmp: Path) -> dict:
    """``.ci/run`` with ``CI=true`` in a fresh clone of ``rev``."""
    sha = subprocess.run(["git", "rev-parse", rev], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    work = tmp / f"clone_{sha[:10]}"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(work)], check=True)
    subprocess.run(["git", "checkout", "-q", sha], cwd=work, check=True)
    env = {k: v for k, v in os.environ.items() if k != "VIRTUAL_ENV"}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if Path(p) != BIN)
    env.update(CI="true", PYTEST_ADDOPTS="--durations=0 -p no:cacheprovider")
    out, cpu, wall = timed(["/usr/bin/time", "-f", "largest process %M kB", "bash", ".ci/run"], work, env)
    rss = re.findall(r"largest process (\d+) kB", out.stderr)
    summary = [ln for ln in out.stdout.splitlines() if re.search(r"\d+ (passed|failed)", ln)]
    tests_s = re.search(r" in ([\d.]+)s", summary[-1]) if summary else None
    return {
        "revision": sha,
        "returncode": out.returncode,
        "summary": summary[-1] if summary else out.stdout[-500:] + out.stderr[-1500:],
        "wall_s": round(wall, 1),
        "tests_wall_s": float(tests_s.group(1)) if tests_s else None,
        "cpu_s": round(cpu, 1),
        "largest_process_GB": round(int(rss[-1]) / 1e6, 2) if rss else None,  # GNU time: the largest of the tree
        "load_average_after": os.getloadavg(),
        "per_file_worker_s": {k: round(v, 1) for k, v in per_file(out.stdout).items()},
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }


def rerun(tmp: Path) -> dict:
    """The reproducibility rerun, cold and warm, in fresh copies of this checkout, over the first run's targets."""
    sys.path.insert(0, str(ROOT / "tests"))
    from conftest import _copy_repo, result_numbers

    first = _copy_repo(tmp / "first")
    out, cpu_first, _ = timed([str(BIN / "snakemake"), "--cores", "2", "all", "--configfile", "config/ci.yaml"], first)
    assert out.returncode == 0, out.stderr[-3000:]
    targets = result_numbers(first)
    runs = {}
    for name, exe in (("cold", [str(BIN / "snakemake")]), ("warm", [sys.executable, str(ROOT / "tests/warm_jobs.py")])):
        work = _copy_repo(tmp / name)
        out, cpu, wall = timed([*exe, "--cores", "2", *targets, "--configfile", "config/ci.yaml"], work)
        assert out.returncode == 0, out.stderr[-3000:]
        runs[name] = {"cpu_s": round(cpu, 1), "wall_s": round(wall, 1), "folder": work}
    differ = [t for t in targets if (runs["cold"]["folder"] / t).read_bytes() != (runs["warm"]["folder"] / t).read_bytes()]
    differ_first = [t for t in targets if (first / t).read_bytes() != (runs["warm"]["folder"] / t).read_bytes()]
    return {
        "first_run_all_cpu_s": round(cpu_first, 1),
        "number_files": len(targets),
        "cold": {k: v for k, v in runs["cold"].items() if k != "folder"},
        "warm": {k: v for k, v in runs["warm"].items() if k != "folder"},
        "cpu_ratio_cold_over_warm": round(runs["cold"]["cpu_s"] / runs["warm"]["cpu_s"], 2),
        "files_differing_cold_vs_warm": differ,
        "files_differing_first_vs_warm": differ_first,
        "load_average_after": os.getloadavg(),
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }


def ci_run(old: str, n: int, tmp: Path) -> dict:
    """The ``ci_run`` fixture's workflow run, ``old``'s way and this checkout's, alternating, ``n`` pairs."""
    import statistics

    sys.path.insert(0, str(ROOT / "tests"))
    from conftest import _copy_repo, result_numbers, workflow_env
    from warm_snakemake import WarmSnakemake

    old_sha = subprocess.run(["git", "rev-parse", old], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.strip()
    old_jobs = tmp / "old_warm_jobs.py"  # the old revision's warm_jobs.py (the job server runs it too: __file__)
    old_jobs.write_text(subprocess.run(["git", "show", f"{old_sha}:tests/warm_jobs.py"], cwd=ROOT,
                                       capture_output=True, text=True, check=True).stdout)
    args = ["--cores", "2", "all", "study_all", "--configfile", "config/ci.yaml"]
    env = {k: v for k, v in workflow_env().items() if k != "PYTHONDONTWRITEBYTECODE"}
    c0 = _cpu_children()
    server = WarmSnakemake(env)
    runs: dict[str, list] = {"old": [], "new": []}
    folders = {}
    try:
        for k in range(n):
            for side in ("old", "new"):
                work = _copy_repo(tmp / f"{side}_{k}")
                t0 = time.perf_counter()
                if side == "old":
                    out, cpu, wall = timed([sys.executable, str(old_jobs), *args], work, env)
                    rc, err = out.returncode, out.stderr
                else:
                    out = server.run(args, work, env=env, warm_jobs=True)
                    cpu, wall, rc, err = out.cpu_s, time.perf_counter() - t0, out.returncode, out.stderr
                assert rc == 0, err[-3000:]
                jobs = float(re.search(r"warm jobs: ([\d.]+) s of CPU", err).group(1))
                runs[side].append({"cpu_s": round(cpu, 2), "jobs_cpu_s": jobs, "rest_cpu_s": round(cpu - jobs, 2),
                                   "wall_s": round(wall, 1), "load_average": os.getloadavg()})
                folders.setdefault(side, work)
    finally:
        server.close()
        # the server (reaped at its close) with every child it waited for, less the runs timed above
        server_start = _cpu_children() - c0 - sum(r["cpu_s"] for side in runs.values() for r in side)
    numbers = result_numbers(folders["old"])
    differ = [f for f in numbers if (folders["old"] / f).read_bytes() != (folders["new"] / f).read_bytes()]

    def med(side: str, key: str) -> float:
        return round(statistics.median(r[key] for r in runs[side]), 2)

    return {
        "what": "python tests/warm_jobs.py " + " ".join(args) + " (old: a fresh process, the old revision's "
                "warm_jobs.py) against a child of a warm Snakemake server (new), in fresh copies of this checkout",
        "old_revision": old_sha,
        "new_revision": subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                                       check=True).stdout.strip(),
        "pairs": n,
        "old": runs["old"],
        "new": runs["new"],
        "median_cpu_s": {"old": med("old", "cpu_s"), "new": med("new", "cpu_s")},
        "median_rest_cpu_s": {"old": med("old", "rest_cpu_s"), "new": med("new", "rest_cpu_s")},
        "median_jobs_cpu_s": {"old": med("old", "jobs_cpu_s"), "new": med("new", "jobs_cpu_s")},
        "cpu_ratio_old_over_new": round(med("old", "cpu_s") / med("new", "cpu_s"), 3),
        "rest_cpu_ratio_old_over_new": round(med("old", "rest_cpu_s") / med("new", "rest_cpu_s"), 3),
        "warm_server_start_and_own_cpu_s": round(server_start, 2),
        "number_files": len(numbers),
        "number_files_differing": differ,
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=("suite", "clone", "rerun", "files", "ci_run"))
    ap.add_argument("tests", nargs="*", help="files: the tests (default: FILES)")
    ap.add_argument("-n", type=int, default=3, help="files: pairs of runs (the first a warm-up)")
    ap.add_argument("--old", default="main")
    ap.add_argument("--new", default="HEAD")
    ap.add_argument("--which", choices=("both", "old", "new"), default="both")
    ap.add_argument("--key", default="snakemake_tests", help="files: the JSON key of the result")
    a = ap.parse_args()
    record = json.loads(OUT.read_text()) if OUT.exists() else {}
    tmp = Path(tempfile.mkdtemp(prefix="bench_ci_tests_"))
    if a.what == "rerun":
        record["rerun"] = rerun(tmp)
    elif a.what == "files":
        result = files(a.old, a.new, a.tests or list(FILES), a.n, tmp)
        record = json.loads(OUT.read_text()) if OUT.exists() else {}  # another run may have written meanwhile
        record[a.key] = result
    elif a.what == "ci_run":
        result = ci_run(a.old, a.n, tmp)
        record = json.loads(OUT.read_text()) if OUT.exists() else {}
        record["ci_run"] = result
    else:
        for side in ("old", "new"):
            if a.which in ("both", side):
                result = (suite if a.what == "suite" else clone)(a.old if side == "old" else a.new, tmp)
                record = json.loads(OUT.read_text()) if OUT.exists() else {}  # another side may have finished
                record.setdefault(a.what, {})[side] = result
                OUT.parent.mkdir(parents=True, exist_ok=True)
                OUT.write_text(json.dumps(record, indent=2) + "\n")
        s = record.setdefault(a.what, {})
        if "old" in s and "new" in s:
            s["cpu_ratio_old_over_new"] = round(s["old"]["cpu_s"] / s["new"]["cpu_s"], 2)
            s["wall_ratio_old_over_new"] = round(s["old"]["wall_s"] / s["new"]["wall_s"], 2)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(record, indent=2) + "\n")
    print(json.dumps(record, indent=2))


if __name__ == "__main__":
    main()
