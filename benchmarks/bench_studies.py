"""Each parameter study's cost, read from the Snakemake benchmark files of a ``study_all`` run.

Every job of rule ``study_case`` writes ``results/benchmarks/rules/study_case_<study>/<case>.tsv`` (Snakemake's
``benchmark:``: wall seconds ``s``, CPU seconds ``cpu_time``, peak RSS ``max_rss``), and each study's summary
``results/benchmarks/rules/study_summary_<study>.tsv``. This script sums them per study of the configuration:
the cases run, their CPU and wall seconds (a case's job, its start-up included), the median and largest case,
the summary job, and the peak RSS of the largest job. The jobs that build a study's shared inputs (the housing
models of ``sensor_comparison_housing`` and ``sensor_design_housing``, the calibrated test's figures) are not
attributed to a study: ``bench_command.py study_all`` measures the whole run, those included.

Usage, from the repository root, after the run::

    python benchmarks/bench_command.py study_all -- snakemake --cores 2 study_all
    python benchmarks/bench_studies.py

Writes ``results/benchmarks/studies.json``. A study with a case of its table that has no benchmark file stops the
script with the study and the count (the run did not finish); files of cases no longer in the table are not read.
"""

from __future__ import annotations

import argparse
import csv
import json
import statistics
import sys
from pathlib import Path

from snakemake.utils import Paramspace

from piezobearing import config as config_loader
from piezobearing.config.cases import check_studies

ROOT = Path(__file__).resolve().parents[1]


def read_jobs(path: Path) -> list[dict]:
    """The rows of one Snakemake benchmark file (one per repeat; the workflow writes one)."""
    with path.open() as f:
        return [{"wall_s": float(r["s"]), "cpu_s": float(r["cpu_time"]), "max_rss_MB": float(r["max_rss"])}
                for r in csv.DictReader(f, delimiter="\t")]


def study_costs(results: Path, cfg: dict) -> dict:
    """Per study of ``cfg``: its cases' and its summary's costs from ``results/benchmarks/rules``."""
    rules = results / "benchmarks" / "rules"
    out = {}
    for name, table in check_studies(cfg).items():
        # the table's cases as the workflow names them (workflow/rules/studies.smk): files of cases no longer in
        # the table are not counted
        files = [rules / f"study_case_{name}" / f"{case}.tsv"
                 for case in Paramspace(table, filename_params="*", single_wildcard="case").instance_patterns]
        missing = [f for f in files if not f.exists()]
        if missing:
            raise SystemExit(f"study {name}: {len(missing)} of its {len(files)} cases have no benchmark file in "
                             f"{rules / f'study_case_{name}'}; run `snakemake --cores 2 study_all` to the end first")
        cases = [job for tsv in files for job in read_jobs(tsv)]
        summary_file = rules / f"study_summary_{name}.tsv"
        summary = read_jobs(summary_file) if summary_file.exists() else []
        cpu = [c["cpu_s"] for c in cases]
        out[name] = {
            "cases": len(cases),
            "cases_cpu_s": round(sum(cpu), 2),
            "cases_wall_s": round(sum(c["wall_s"] for c in cases), 2),
            "case_cpu_median_s": round(statistics.median(cpu), 2),
            "case_cpu_max_s": round(max(cpu), 2),
            "summary_cpu_s": round(sum(s["cpu_s"] for s in summary), 2) if summary else None,
            "peak_rss_MB": round(max(j["max_rss_MB"] for j in cases + summary), 1),
        }
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--results", type=Path, default=ROOT / "results", help="the run's results folder")
    ap.add_argument("--configfile", action="append", default=[], help="the run's config files (default: the paper's)")
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "benchmarks" / "studies.json")
    a = ap.parse_args(argv)
    cfg = config_loader.load(*a.configfile)
    record = {"configfiles": a.configfile or ["config/config.yaml"], "studies": study_costs(a.results, cfg)}
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(record, indent=1) + "\n")
    for name, s in record["studies"].items():
        print(f"{name}: {s['cases']} cases, {s['cases_cpu_s']:.0f} s CPU (median case {s['case_cpu_median_s']:.1f} s)")
    print(f"-> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
