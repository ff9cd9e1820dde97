"""The whole paper on 2 idle cores, from one run's job CPU times: critical path, list schedule, rule priorities.

Reads the job DAG (``snakemake --dag`` in a finished run's folder) and each job's CPU seconds (its
``results/benchmarks/rules/<rule>[_<wildcards>].tsv``, Snakemake's ``cpu_time``; Snakemake samples it, so
every job is scaled by ``--scale``, the run's GNU-time CPU over the sum of its jobs', to account for what the
samples miss). Then, as an idle machine would run it: each job's level (CPU seconds on its longest path to
the end), the critical path, and the makespan of a 2-core list schedule that starts the ready job of the
highest level first (what the rules' ``priority:`` in ``workflow/rules/common.smk`` asks Snakemake to do;
the values there are these levels, by rule). Snakemake's own start (``snakemake -n``, about 3.5 s of CPU)
comes before the first job and is not included.

Writes ``results/benchmarks/schedule_<name>.json``. Usage (a finished run in FOLDER)::

    python benchmarks/bench_schedule.py --run FOLDER --name paper [--scale 1.2]
"""

from __future__ import annotations

import argparse
import heapq
import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def dag(folder: Path) -> tuple[dict, list]:
    """Jobs (id -> (rule, wildcard values)) and edges (from, to) of ``snakemake --dag`` in ``folder``."""
    env = {**os.environ, "PYTHONPATH": str(folder / "src")}
    dot = subprocess.run([str(BIN / "snakemake"), "--dag", "-q"], cwd=folder, env=env, capture_output=True,
                         text=True, check=True).stdout
    nodes = {}
    for m in re.finditer(r'\t(\d+)\[label = "([^"]+)"', dot):
        lab = m.group(2).split("\\n")
        nodes[m.group(1)] = (lab[0], [x.split(": ", 1)[1] for x in lab[1:]])
    edges = [(m.group(1), m.group(2)) for m in re.finditer(r"\t(\d+) -> (\d+)", dot)]
    return nodes, edges


def job_cpu(bench: Path, rule: str, wildcards: list[str], used: set) -> float:
    """CPU seconds of one job from its benchmark file (a rule with unlabelled wildcards: its files in turn)."""
    name = bench / ("_".join([rule, *wildcards]) + ".tsv")
    files = [name] if name.exists() else sorted(bench.glob(f"{rule}_*.tsv"))
    files = [f for f in files if f not in used] or files
    if not files:
        return 0.0
    used.add(files[0])
    return float(files[0].read_text().splitlines()[-1].split()[-1])


def schedule(nodes: dict, edges: list, dur: dict, cores: int = 2) -> dict:
    succ, pred = {n: [] for n in nodes}, {n: [] for n in nodes}
    for a, b in edges:
        succ[a].append(b)
        pred[b].append(a)
    level: dict = {}

    def lv(n):
        if n not in level:
            level[n] = dur[n] + max((lv(s) for s in succ[n]), default=0.0)
        return level[n]

    for n in nodes:
        lv(n)
    t, done, running, free, start = 0.0, set(), [], cores, {}
    ready = [n for n in nodes if not pred[n]]
    while len(done) < len(nodes):
        ready.sort(key=lambda n: -level[n])
        while free and ready:
            n = ready.pop(0)
            start[n] = t
            heapq.heappush(running, (t + dur[n], n))
            free -= 1
        t, n = heapq.heappop(running)
        free += 1
        done.add(n)
        ready += [s for s in succ[n] if all(p in done for p in pred[s])]
    by_rule: dict = {}
    for n, (rule, _) in nodes.items():
        by_rule[rule] = max(by_rule.get(rule, 0.0), level[n])
    return {"total_cpu_s": sum(dur.values()), "critical_path_s": max(level.values()), "makespan_s": t,
            "rule_levels_s": {r: round(v, 1) for r, v in sorted(by_rule.items(), key=lambda kv: -kv[1])}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--run", required=True, type=Path, help="folder of a finished whole-paper run")
    ap.add_argument("--name", required=True)
    ap.add_argument("--scale", type=float, default=1.0, help="job CPU scale: GNU-time CPU / sum of job CPU")
    a = ap.parse_args()
    nodes, edges = dag(a.run)
    used: set = set()
    dur = {n: a.scale * job_cpu(a.run / "results/benchmarks/rules", r, w, used) for n, (r, w) in nodes.items()}
    rec = {"run": str(a.run), "scale": a.scale, "jobs": len(nodes), **schedule(nodes, edges, dur)}
    out = ROOT / "results/benchmarks" / f"schedule_{a.name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps({k: v for k, v in rec.items() if k != "rule_levels_s"}, indent=1))


if __name__ == "__main__":
    main()
