"""Measure every rule's run time and peak memory on a config; the rules' `resources` come from here.

    python benchmarks/bench_rules.py [--configfile config/config.yaml] [--targets all study_all]

1. Reruns the whole workflow (--forceall) with each rule's `benchmark:` file
   and gathers results/benchmarks/rules/*.tsv: seconds and max RSS per job.
2. Snakemake's benchmark samples memory sparsely after the first seconds of a
   job, so it can miss the peak of long jobs. Every rule whose jobs run longer
   than --exact-after seconds is therefore run again on its own
   (--forcerun RULE --allowed-rules RULE) in a child process that reports the
   largest peak RSS of its descendants (getrusage RUSAGE_CHILDREN): the peak
   of the rule's largest job.

Writes results/benchmarks/rules_<config>.json with, per rule, the seconds
(longest job), the benchmark's max RSS and, where measured, the exact peak
(`peak_rss_mb`). The rules' mem_mb and runtime are set from these with a
margin (docs/performance.md).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd

REPO = Path(__file__).resolve().parents[1]

# Runs argv and prints the largest peak RSS [kB] among its descendants.
_PEAK = (
    "import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True); "
    "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
)


def rule_of(job: str, rules: list[str]) -> str:
    """The rule a benchmark file stem belongs to (the longest rule name it starts with)."""
    return max((r for r in rules if job == r or job.startswith(r + "_")), key=len)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--configfile", default="config/config.yaml")
    ap.add_argument("--targets", nargs="+", default=["all"])
    ap.add_argument("--exact-after", type=float, default=10.0, help="seconds; longer rules get an exact peak")
    args = ap.parse_args()
    exe = str(Path(sys.executable).with_name("snakemake"))
    bench_dir = REPO / "results/benchmarks/rules"
    # study cases: rules/study_case_<study>/<case>.tsv (a case name alone can take most of a file name's 255)
    for f in [*bench_dir.glob("*.tsv"), *bench_dir.glob("*/*.tsv")]:
        f.unlink()
    base = ["--cores", "2", *args.targets, "--configfile", args.configfile]
    subprocess.run([exe, "--forceall", *base], cwd=REPO, check=True)
    rules = sorted(
        set(
            re.findall(
                r"^rule (\w+):", "".join(p.read_text() for p in (REPO / "workflow/rules").glob("*.smk")), re.M
            )
        )
    )
    rows: dict[str, dict] = {}
    for f in sorted([*bench_dir.glob("*.tsv"), *bench_dir.glob("*/*.tsv")]):
        b = pd.read_csv(f, sep="\t")
        stem = f.stem if f.parent == bench_dir else f.parent.name
        r = rows.setdefault(rule_of(stem, rules), {"seconds": 0.0, "max_rss_mb": 0.0, "jobs": 0})
        r["seconds"] = max(r["seconds"], float(b["s"].max()))
        r["max_rss_mb"] = max(r["max_rss_mb"], float(b["max_rss"].max()))
        r["jobs"] += 1
    for name, r in rows.items():
        if r["seconds"] > args.exact_after:
            cmd = [sys.executable, "-c", _PEAK, exe, "--forcerun", name, "--allowed-rules", name, *base]
            out = subprocess.run(cmd, cwd=REPO, check=True, capture_output=True, text=True)
            r["peak_rss_mb"] = int(out.stdout.split()[-1]) / 1024
            print(f"{name}: peak {r['peak_rss_mb']:.0f} MB", flush=True)
    tag = Path(args.configfile).stem
    out = REPO / f"results/benchmarks/rules_{tag}.json"
    out.write_text(
        json.dumps({"cpu_count": os.cpu_count(), "config": args.configfile, "rules": rows}, indent=2)
    )
    print(pd.DataFrame(rows).T.to_string())


if __name__ == "__main__":
    main()
