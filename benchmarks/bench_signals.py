"""Time of one envelope analysis (whole periods, band, envelope spectrum, indicator) at the paper's rate.

Writes results/benchmarks/signals.json: seconds per record for the kurtogram and the fixed band, for
1 s and 10 s records at 2550 Hz, and the cost of a 31-SNR x 50-seed x 2-case study.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from piezobearing.signals import detection
from piezobearing.signals.envelope import EnvelopeSettings

FS = 2550.0
DT = 1 / FS
BPFO = FS / 36


def seconds_per_record(n: int, rule: str, repeat: int = 20) -> float:
    rng = np.random.default_rng(0)
    x = rng.standard_normal(n)
    env, ind = EnvelopeSettings(band_rule=rule), detection.IndicatorSettings()
    detection.analyse(x, DT, BPFO, env, ind)
    t0 = time.perf_counter()
    for _ in range(repeat):
        detection.analyse(x, DT, BPFO, env, ind)
    return (time.perf_counter() - t0) / repeat


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n")[0]).parse_args()  # no options: --help only
    out = {"cpu_count": os.cpu_count(), "sample_rate_Hz": FS}
    for secs in (1, 10):
        for rule in ("kurtogram", "fixed"):
            out[f"seconds_per_record_{rule}_{secs}s"] = seconds_per_record(int(secs * FS), rule)
    out["study_seconds_estimate_kurtogram_1s"] = 31 * 50 * 2 * out["seconds_per_record_kurtogram_1s"]
    path = Path("results/benchmarks/signals.json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
