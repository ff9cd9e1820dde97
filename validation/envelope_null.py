"""The envelope detector's false-alarm rate as measured, against the probability it states.

``python validation/envelope_null.py [--n 250] [--out results/validation]`` draws records without a fault
of two kinds: white noise, and a healthy machine (white noise modulated at the shaft rate, its first 8
harmonics far above the noise, a mesh tone with shaft-rate sidebands: ``tests/test_envelope_detector.machine``),
each at two lengths (2 and 5 s) and two rates (12 and 25.6 kHz), ``--n`` records per kind,
length and rate; the shaft speed is given within 1 % of the true one. Each record is read once
(:func:`piezobearing.signals.detectors.envelope.measure`) and called at the false-alarm probabilities 0.1,
0.05, 0.01 and 10^-3 with the detector's default settings (:func:`~piezobearing.signals.detectors.envelope.call_of`;
a fault of unknown type is an alarm). Writes ``envelope_null.json`` and ``envelope_null.md``: per kind and
probability the alarms, the observed rate, and the 99 % Clopper-Pearson interval of a detector at exactly the
stated probability (the count it exceeds with probability 0.005).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.stats import binom

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.io import write_json
from piezobearing.signals.detectors import envelope, is_alarm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_envelope_detector import machine  # noqa: E402  (the healthy machine of the detector's tests)

BEARING = RollingBearing.from_designation("SKF 6205")
PROBABILITIES = (0.1, 0.05, 0.01, 1e-3)
LENGTHS_S = (2.0, 5.0)
RATES_HZ = (12000.0, 25600.0)
KINDS = ("white noise", "healthy machine")


def record(kind: str, rng: np.random.Generator, shaft_Hz: float, seconds: float, sample_rate_Hz: float) -> np.ndarray:
    if kind == "white noise":
        return rng.standard_normal(int(seconds * sample_rate_Hz))
    return machine(rng, shaft_Hz, seconds, sample_rate_Hz)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=250, help="records per kind, length and rate")
    parser.add_argument("--out", default="results/validation")
    args = parser.parse_args()
    settings = envelope.Settings()
    counts = {k: {p: 0 for p in PROBABILITIES} for k in KINDS}
    cells = {}
    cpu = time.process_time()
    for ki, kind in enumerate(KINDS):
        for length in LENGTHS_S:
            for rate in RATES_HZ:
                cell = {p: 0 for p in PROBABILITIES}
                for j in range(args.n):
                    rng = np.random.default_rng([23, ki, int(length), int(rate), j])
                    shaft = rng.uniform(20.0, 30.0)
                    x = record(kind, rng, shaft, length, rate)
                    kin = BEARING.kinematics(shaft * rng.uniform(0.99, 1.01)).to_dict()
                    reading = envelope.measure(x, rate, kin, settings)
                    for p in PROBABILITIES:
                        call, _, _ = envelope.call_of(reading, replace(settings, false_alarm_probability=p))
                        cell[p] += is_alarm(call)
                for p in PROBABILITIES:
                    counts[kind][p] += cell[p]
                cells[f"{kind}, {length:g} s, {rate:g} Hz"] = {str(p): cell[p] for p in PROBABILITIES}
                print(f"{kind}, {length:g} s at {rate:g} Hz: {cell}", flush=True)
    n = args.n * len(LENGTHS_S) * len(RATES_HZ)
    rows = []
    for kind in KINDS:
        for p in PROBABILITIES:
            lo, hi = binom.ppf(0.005, n, p), binom.ppf(0.995, n, p)
            k = counts[kind][p]
            rows.append({"kind": kind, "false_alarm_probability": p, "records": n, "alarms": k,
                         "observed_rate": k / n, "interval_99": [int(lo), int(hi)],
                         "verdict": "within" if lo <= k <= hi else ("above" if k > hi else "below")})
    summary = {"settings": "envelope.Settings() defaults, the false-alarm probability varied", "n_per_cell": args.n,
               "lengths_s": list(LENGTHS_S), "rates_Hz": list(RATES_HZ), "rows": rows, "cells": cells,
               "cpu_s": time.process_time() - cpu}
    out = Path(args.out)
    write_json(summary, out / "envelope_null.json")
    lines = ["| records | stated probability | alarms | observed rate | 99 % interval of the count | |",
             "|---|---:|---:|---:|---|---|"]
    lines += [f"| {r['kind']} ({r['records']}) | {r['false_alarm_probability']:g} | {r['alarms']} | "
              f"{r['observed_rate']:.4f} | {r['interval_99'][0]}-{r['interval_99'][1]} | {r['verdict']} |"
              for r in rows]
    (out / "envelope_null.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
