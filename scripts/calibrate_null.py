"""The envelope detector's null calibration table, from simulated records without a fault.

``python scripts/calibrate_null.py [--n 120] [--out src/piezobearing/signals/detectors/null_calibration.json]``

Draws ``--n`` records per kind, length and rate (seeded: the same table on every run) of three kinds of record
without a bearing fault, each at 2, 5 and 10 s and at 12 and 25.6 kHz, an SKF 6205 at a shaft rate drawn in
20-30 Hz and given to the detector within +-1 %:

- **white noise**;
- **resonant noise**: white noise through a structural resonance (two poles, a centre drawn in 1-4 kHz, Q in
  5-30) over a white floor a tenth of its rms: the colour of an accelerometer on a housing;
- **healthy machine**: noise modulated at the shaft rate, its first 8 harmonics far above the noise, a mesh tone
  with shaft-rate sidebands (``null_calibration.healthy_machine``: a healthy machine's lines where a fault's would fall).

Each record is read once with the detector's default settings (:func:`~piezobearing.signals.detectors.envelope.measure`)
and its critical level per test computed (:func:`~piezobearing.signals.detectors.envelope.critical_alpha`); the
table (:func:`~piezobearing.signals.detectors.null_calibration.calibrate`) is, per length, the order statistics of
the records of that length (every kind and rate) at the stated probabilities :data:`PROBABILITIES`. What it is judged on is other: ``validation/envelope_null.py`` (other
seeds, pink noise, the CWRU healthy record).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
from scipy.signal import lfilter

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.signals.detectors import envelope, null_calibration

ROOT = Path(__file__).resolve().parents[1]
BEARING = RollingBearing.from_designation("SKF 6205")
LENGTHS_S = (2.0, 5.0, 10.0)
RATES_HZ = (12000.0, 25600.0)
KINDS = ("white noise", "resonant noise", "healthy machine")
#: The stated probabilities of the table's rows.
PROBABILITIES = (0.01, 0.02, 0.05, 0.1, 0.2)
#: The seed's first element (``validation/envelope_null.py`` draws from others).
SEED = 101


def resonant_noise(rng: np.random.Generator, seconds: float, sample_rate_Hz: float) -> np.ndarray:
    """White noise through a two-pole resonance (centre 1-4 kHz, Q 5-30) over a white floor a tenth of its rms."""
    n = int(sample_rate_Hz * seconds)
    f0, q = rng.uniform(1000.0, 4000.0), rng.uniform(5.0, 30.0)
    r = np.exp(-np.pi * f0 / (q * sample_rate_Hz))
    y = lfilter([1.0], [1.0, -2.0 * r * np.cos(2 * np.pi * f0 / sample_rate_Hz), r * r], rng.standard_normal(n))
    return y / y.std() + 0.1 * rng.standard_normal(n)


def pink_noise(rng: np.random.Generator, seconds: float, sample_rate_Hz: float) -> np.ndarray:
    """Noise of power density 1/f (from 1 Hz), shaped in the frequency domain."""
    n = int(sample_rate_Hz * seconds)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_Hz)
    return np.fft.irfft(spectrum / np.sqrt(np.maximum(f, 1.0)), n)


def record(kind: str, rng: np.random.Generator, shaft_Hz: float, seconds: float, sample_rate_Hz: float) -> np.ndarray:
    """A record without a bearing fault of ``kind`` (module docstring; ``pink noise``: :func:`pink_noise`)."""
    if kind == "white noise":
        return rng.standard_normal(int(seconds * sample_rate_Hz))
    if kind == "resonant noise":
        return resonant_noise(rng, seconds, sample_rate_Hz)
    if kind == "pink noise":
        return pink_noise(rng, seconds, sample_rate_Hz)
    if kind == "healthy machine":
        return null_calibration.healthy_machine(rng, shaft_Hz, seconds, sample_rate_Hz)
    raise ValueError(f"kind '{kind}' unknown")


def critical_levels(kind: str, seconds: float, sample_rate_Hz: float, n: int, seed: tuple[int, ...],
                    settings: envelope.Settings, bearing: RollingBearing = BEARING) -> np.ndarray:
    """The critical level per test (:func:`~piezobearing.signals.detectors.envelope.critical_alpha`) of ``n``
    records of one kind, length and rate; record j from the seed ``(*seed, j)``."""
    out = np.empty(n)
    for j in range(n):
        rng = np.random.default_rng([*seed, j])
        shaft = rng.uniform(20.0, 30.0)
        x = record(kind, rng, shaft, seconds, sample_rate_Hz)
        kin = bearing.kinematics(shaft * rng.uniform(0.99, 1.01)).to_dict()
        out[j] = envelope.critical_alpha(envelope.measure(x, sample_rate_Hz, kin, settings), settings)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=120, help="records per kind, length and rate")
    ap.add_argument("--out", default=str(null_calibration.TABLE.relative_to(ROOT)))
    ap.add_argument("--levels", default="results/validation/null_levels.npz",
                    help="where the records' critical levels go (per length), for another table without a rerun")
    args = ap.parse_args()
    settings = replace(envelope.Settings(), calibrated_null=False)
    cpu = time.process_time()
    rows, cells, total, critical = [], {}, 0, {}
    for length in LENGTHS_S:
        levels = []
        for ki, kind in enumerate(KINDS):
            for rate in RATES_HZ:
                a = critical_levels(kind, length, rate, args.n, (SEED, ki, int(length), int(rate)), settings)
                levels.append(a)
                name = f"{kind}, {length:g} s, {rate:g} Hz"
                cells[name] = {"records": int(a.size), "median_critical_level": float(np.median(a)),
                               "share_below_0.01": float(np.mean(a < 0.01))}
                print(f"{name}: median critical level {np.median(a):.3g}, below 0.01: {np.mean(a < 0.01):.3f}",
                      flush=True)
        rows += null_calibration.calibrate(np.concatenate(levels), PROBABILITIES, length)
        total += sum(a.size for a in levels)
        critical[f"{length:g} s"] = np.concatenate(levels)
    spectrum = {k: v for k, v in asdict(settings).items()
                if k not in ("false_alarm_probability", "min_type_separation_dB", "calibrated_null")}
    table = {
        "what": "per stated false-alarm probability, the envelope detector's level per test (a family in a band)",
        "made_by": f"python scripts/calibrate_null.py --n {args.n}",
        "records": {"kinds": list(KINDS), "lengths_s": list(LENGTHS_S), "rates_Hz": list(RATES_HZ),
                    "per_kind_length_rate": args.n, "total": int(total),
                    "bearing": BEARING.designation, "shaft_Hz": [20.0, 30.0], "speed_given_within": 0.01,
                    "seed": SEED},
        "null": "records without a bearing fault: white noise, noise through a structural resonance, a healthy "
                "machine's shaft harmonics and mesh with sidebands; a real machine's other sources (another "
                "bearing's fault, electrical lines beyond the supply's harmonics) are not in it",
        "confidence": null_calibration.CONFIDENCE,
        "settings": spectrum,
        "rows": rows,
        "cells": cells,
    }
    out = Path(args.out)
    out.write_text(json.dumps(table, indent=2) + "\n", encoding="utf-8")
    Path(args.levels).parent.mkdir(parents=True, exist_ok=True)
    np.savez(args.levels, **critical)
    for r in rows:
        print(f"{r['length_s']:g} s, p = {r['false_alarm_probability']:g}: level per test {r['alpha_per_test']:.4g} "
              f"(effective tests {r['effective_tests']:.3g}, {r['alarms_allowed']} of {r['records']} records)")
    print(f"{out}; {time.process_time() - cpu:.0f} s CPU", file=sys.stderr)


if __name__ == "__main__":
    main()
