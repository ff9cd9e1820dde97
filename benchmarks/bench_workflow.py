"""Whole workflow runs, the previous code beside this checkout's, in one call (the whole paper, or CI).

For each side (``--old REF``, a git revision of this repository, exported to a temporary folder; and the
working tree's committed HEAD) a clean ``snakemake --cores 2 [--configfile FILE] TARGETS`` runs in a fresh
copy, both at the same time (so both see the same machine: on a shared machine the ratio is the result,
not the seconds), each under GNU time (``/usr/bin/time -v``: wall, user and system seconds of the run and
all its jobs, and the peak RSS of its largest single process). Then every result file of the two runs is
compared: byte-identical (SHA-256), or for CSV/JSON the largest relative difference of their numbers.

Writes ``results/benchmarks/workflow_<name>.json``; ``--parse OLD_LOG NEW_LOG OLD_DIR NEW_DIR`` writes the
same record from two GNU time logs and result folders of runs made by hand the same way.

Usage (from the repository root, the package's environment active)::

    python benchmarks/bench_workflow.py --name ci --old main --configfile config/ci.yaml
    python benchmarks/bench_workflow.py --name paper --old main
    python benchmarks/bench_workflow.py --name ci_solver --old HEAD --old-env PIEZOBEARING_SOLVER=superlu \
        --configfile config/ci.yaml
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
SKIP = ("results/logs", "results/benchmarks", "results/notebooks", "results/.checked")

def export_revision(rev: str, dest: Path) -> Path:
    """Revision ``rev`` of this repository as a plain folder ``dest`` (with an empty ``data/``)."""
    dest.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", rev], cwd=ROOT, capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    (dest / "data").mkdir(exist_ok=True)
    return dest


TIME_FIELDS = {
    "user_s": r"User time \(seconds\): ([\d.]+)",
    "system_s": r"System time \(seconds\): ([\d.]+)",
    "wall": r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)",
    "peak_rss_kB": r"Maximum resident set size \(kbytes\): (\d+)",
}


def parse_time_log(text: str) -> dict:
    """Wall, user, system seconds and peak RSS from GNU time -v's report."""
    out = {}
    for key, pattern in TIME_FIELDS.items():
        m = re.search(pattern, text)
        if m is None:
            raise ValueError(f"GNU time field {key} not found")
        out[key] = m.group(1)
    parts = [float(x) for x in out.pop("wall").split(":")]
    wall = sum(v * 60**i for i, v in enumerate(reversed(parts)))
    user, system = float(out["user_s"]), float(out["system_s"])
    return {"wall_s": wall, "user_s": user, "system_s": system, "cpu_s": user + system,
            "peak_rss_MB": int(out["peak_rss_kB"]) / 1024, "exit_ok": "rc=0" in text or "Exit status: 0" in text}


def _numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?|nan|inf", text)]


def compare_results(old: Path, new: Path) -> dict:
    """Per result file: identical bytes, or the largest relative difference of the numbers (CSV/JSON)."""
    files = {}
    names = {p.relative_to(old).as_posix() for p in (old / "results").rglob("*") if p.is_file()}
    names |= {p.relative_to(new).as_posix() for p in (new / "results").rglob("*") if p.is_file()}
    for rel in sorted(n for n in names if not n.startswith(SKIP)):
        a, b = old / rel, new / rel
        if not (a.exists() and b.exists()):
            files[rel] = {"status": "only in old" if a.exists() else "only in new"}
            continue
        ha, hb = (hashlib.sha256(p.read_bytes()).hexdigest() for p in (a, b))
        if ha == hb:
            files[rel] = {"status": "identical", "sha256": ha}
            continue
        rec = {"status": "differs"}
        if a.suffix in {".csv", ".json"}:
            x, y = _numbers(a.read_text()), _numbers(b.read_text())
            if len(x) == len(y):
                rel_diff = [abs(p - q) / max(abs(p), abs(q)) for p, q in zip(x, y, strict=True)
                            if p != q and math.isfinite(p) and math.isfinite(q)]
                rec["max_rel_diff"] = max(rel_diff, default=0.0)
            else:
                rec["note"] = f"{len(x)} numbers against {len(y)}"
        files[rel] = rec
    counts: dict[str, int] = {}
    for r in files.values():
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    return {"counts": counts, "files": files}


def _run(folder: Path, args: list[str], log: Path, extra_env: dict) -> None:
    env = {**os.environ, "PATH": f"{BIN}:{os.environ['PATH']}", "PYTHONPATH": str(folder / "src"), **extra_env}
    cmd = ["/usr/bin/time", "-v", str(BIN / "snakemake"), "--cores", "2", *args]
    with log.open("w") as f:
        code = subprocess.run(cmd, cwd=folder, env=env, stdout=f, stderr=subprocess.STDOUT).returncode
        f.write(f"\nrc={code}\n")


def _job_dag(folder: Path, args: list[str]) -> tuple[dict[int, str], list[tuple[int, int]]]:
    """The jobs of ``snakemake --dag --forceall`` in ``folder`` (id -> rule) and their edges (parent, child)."""
    env = {**os.environ, "PATH": f"{BIN}:{os.environ['PATH']}", "PYTHONPATH": str(folder / "src")}
    dot = subprocess.run([str(BIN / "snakemake"), "--dag", "--forceall", *args], cwd=folder, env=env,
                         capture_output=True, text=True, check=True).stdout
    jobs = {int(i): rule for i, rule in re.findall(r'^\s*(\d+)\[label = "(\w+)', dot, re.M)}
    edges = [(int(a), int(b)) for a, b in re.findall(r"^\s*(\d+) -> (\d+)", dot, re.M)]
    return jobs, edges


def critical_path(folder: Path, args: list[str]) -> dict:
    """The longest chain of jobs of a finished run in ``folder``: each job weighted by the wall seconds of its
    rule's longest job (``results/benchmarks/rules/<rule>*.tsv``, column ``s``); the floor of the run's wall time
    on any number of cores. Also the rules' summed wall and CPU seconds (column ``cpu_time``)."""
    jobs, edges = _job_dag(folder, args)
    bench = folder / "results/benchmarks/rules"
    seconds, cpu = {}, {}
    for f in sorted(bench.rglob("*.tsv")):
        rows = [line.split("\t") for line in f.read_text().splitlines()[1:] if line.strip()]
        rule = next((r for r in sorted(set(jobs.values()), key=len, reverse=True)
                     if f.relative_to(bench).as_posix().startswith(r)), None)
        if rule is None or not rows:
            continue
        seconds[rule] = max(seconds.get(rule, 0.0), float(rows[-1][0]))
        cpu[rule] = cpu.get(rule, 0.0) + float(rows[-1][-1])
    children: dict[int, list[int]] = {}
    for a, b in edges:  # snakemake draws an edge from the job that makes a file to the job that reads it
        children.setdefault(a, []).append(b)
    memo: dict[int, tuple[float, list[str]]] = {}

    def longest(j: int) -> tuple[float, list[str]]:
        if j not in memo:
            w = seconds.get(jobs[j], 0.0)
            tail = max((longest(c) for c in children.get(j, ())), default=(0.0, []))
            memo[j] = (w + tail[0], [jobs[j], *tail[1]])
        return memo[j]

    total, path = max(longest(j) for j in jobs)
    return {"seconds": round(total, 1), "rules": [r for r in path if r != "all"],
            "rules_wall_s": round(sum(seconds.values()), 1), "rules_cpu_s": round(sum(cpu.values()), 1)}


def record(name: str, old: str, args: list[str], logs: tuple[Path, Path], dirs: tuple[Path, Path],
           when: str = "at the same time") -> dict:
    t_old, t_new = (parse_time_log(p.read_text()) for p in logs)
    ratio = {k: t_new[k] / t_old[k] for k in ("wall_s", "cpu_s", "peak_rss_MB") if t_old[k]}
    load = os.getloadavg()
    return {
        "what": f"snakemake --cores 2 {' '.join(args)} in a fresh copy, old and new {when}",
        "old": {"revision": old, **t_old},
        "new": {"revision": "HEAD", **t_new},
        "new_over_old": ratio,
        "critical_path": {"old": critical_path(dirs[0], args), "new": critical_path(dirs[1], args)},
        "load_average_1_5_15_at_end": load,
        "results": compare_results(*dirs),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--name", help="the record's name: results/benchmarks/workflow_NAME.json (default: the config "
                    "file's stem, or paper)")
    ap.add_argument("--old", default="main", help="git revision of the previous code")
    ap.add_argument("--configfile", default=None)
    ap.add_argument("--old-env", action="append", default=[], metavar="NAME=VALUE",
                    help="environment of the old run (PIEZOBEARING_SOLVER=superlu: the previous solver)")
    ap.add_argument("targets", nargs="*")
    ap.add_argument("--parse", nargs=4, metavar=("OLD_LOG", "NEW_LOG", "OLD_DIR", "NEW_DIR"))
    ap.add_argument("--alone", action="store_true",
                    help="run the two sides one after the other, each with the whole machine (its wall time is the "
                    "run's own), instead of at the same time")
    a = ap.parse_args()
    args = [*a.targets, *(["--configfile", a.configfile] if a.configfile else [])]
    a.name = a.name or (Path(a.configfile).stem if a.configfile else "paper")
    if a.parse:
        logs, dirs = (Path(a.parse[0]), Path(a.parse[1])), (Path(a.parse[2]), Path(a.parse[3]))
    else:
        tmp = Path(tempfile.mkdtemp(prefix="bench_workflow_"))
        dirs = (export_revision(a.old, tmp / "old"), export_revision("HEAD", tmp / "new"))
        logs = (tmp / "old.log", tmp / "new.log")
        envs = (dict(e.split("=", 1) for e in a.old_env), {})
        with ThreadPoolExecutor(1 if a.alone else 2) as pool:
            list(pool.map(lambda k: _run(dirs[k], args, logs[k], envs[k]), (0, 1)))
    out = ROOT / "results/benchmarks" / f"workflow_{a.name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    rec = record(a.name, a.old + "".join(f" {e}" for e in a.old_env), args, logs, dirs,
                 "one after the other" if a.alone else "at the same time")
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps({k: rec[k] for k in ("old", "new", "new_over_old", "critical_path")}, indent=1))
    print(rec["results"]["counts"])


if __name__ == "__main__":
    main()
