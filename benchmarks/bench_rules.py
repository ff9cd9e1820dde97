"""Measure every rule's run time and peak memory on a config; the rules' `resources` come from here.

    python benchmarks/bench_rules.py [--configfile config/ci.yaml] [--targets all study_all]

Reruns the whole workflow (--forceall) with each rule's `benchmark:` file,
then gathers results/benchmarks/rules/*.tsv into
results/benchmarks/rules_<config>.json: seconds and max RSS per rule (the
rules' mem_mb and runtime are set from these with a margin).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--configfile", default="config/config.yaml")
    ap.add_argument("--targets", nargs="+", default=["all"])
    args = ap.parse_args()
    exe = Path(sys.executable).with_name("snakemake")
    bench_dir = REPO / "results/benchmarks/rules"
    for f in bench_dir.glob("*.tsv"):
        f.unlink()
    cmd = [str(exe), "--cores", "2", "--forceall", *args.targets, "--configfile", args.configfile]
    subprocess.run(cmd, cwd=REPO, check=True)
    rows = {}
    for f in sorted(bench_dir.glob("*.tsv")):
        b = pd.read_csv(f, sep="\t")
        rows[f.stem] = {"seconds": float(b["s"].max()), "max_rss_mb": float(b["max_rss"].max())}
    tag = Path(args.configfile).stem
    out = REPO / f"results/benchmarks/rules_{tag}.json"
    out.write_text(
        json.dumps({"cpu_count": os.cpu_count(), "config": args.configfile, "rules": rows}, indent=2)
    )
    print(pd.DataFrame(rows).T.to_string())


if __name__ == "__main__":
    main()
