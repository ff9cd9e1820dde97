"""The envelope detector's false-alarm rate as measured, against the probability it states, with the calibrated
null and with the Bonferroni split, on records the calibration was not made on.

``python validation/envelope_null.py [--n 250] [--out results/validation] [--cwru ../shared/data/cwru_fan_end]
[--lengths 3 8] [--rates 12000 25600]``

draws records without a fault of three kinds: white noise; pink noise (power 1/f: a colour the calibration's
records do not have); a healthy machine (noise modulated at the shaft rate, its first 8 harmonics far above the
noise, a mesh tone with shaft-rate sidebands) - each at two lengths (3 and 8 s: between the calibration's 2, 5
and 10 s) and two rates (12 and 25.6 kHz), ``--n`` records per kind, length and rate, from seeds other than the
calibration's (``scripts/calibrate_null.py``); an SKF 6205, the shaft speed given within 1 % of the true one.
With ``--cwru``, the healthy CWRU record fe39 too, cut into 2 s and 5 s stretches, its drive-end channel against
the SKF 6205 and its fan-end channel against the SKF 6203 of its rig file.

Each record is read once (:func:`piezobearing.signals.detectors.envelope.measure`) and called at the false-alarm
probabilities 0.1, 0.05, 0.01 and 10^-3 with the detector's default settings, its null calibrated and
(``calibrated_null`` off) split by Bonferroni (:func:`~piezobearing.signals.detectors.envelope.call_of`; a fault
of unknown type is an alarm). Writes ``envelope_null.json`` and ``envelope_null.md``: per kind, null and
probability the alarms, the observed rate, the 99 % interval of the count of a detector at exactly the stated
probability (binomial: the counts it falls below or above with probability 0.005 each), and the one-sided 95 %
upper bound on the rate (Clopper-Pearson).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.stats import beta, binom

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.io import write_json
from piezobearing.io.vibration import read_vibration_record
from piezobearing.signals.detectors import envelope, is_alarm
from piezobearing.stages.recording import read_rig

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from calibrate_null import record  # noqa: E402  (the calibration's record kinds)

BEARING = RollingBearing.from_designation("SKF 6205")
PROBABILITIES = (0.1, 0.05, 0.01, 1e-3)
LENGTHS_S = (3.0, 8.0)
RATES_HZ = (12000.0, 25600.0)
KINDS = ("white noise", "pink noise", "healthy machine")
NULLS = ("calibrated", "Bonferroni")
#: The healthy CWRU record and its stretches [s].
CWRU_HEALTHY = "fe39"
STRETCHES_S = (2.0, 5.0)


def calls(reading: envelope.Reading, settings: envelope.Settings) -> dict[tuple[str, float], bool]:
    """Alarm or not at every probability, with either null."""
    out = {}
    for null in NULLS:
        s = replace(settings, calibrated_null=null == "calibrated")
        for p in PROBABILITIES:
            call, _, _ = envelope.call_of(reading, replace(s, false_alarm_probability=p))
            out[(null, p)] = is_alarm(call)
    return out


def cwru_readings(folder: Path, settings: envelope.Settings) -> list[envelope.Reading]:
    """fe39's stretches, each channel against its bearing (the drive end's SKF 6205, the fan end's rig file)."""
    rig = read_rig(folder / f"{CWRU_HEALTHY}.yaml")
    out = []
    for suffix, bearing in (("_DE_time", BEARING), ("_FE_time", rig.bearing)):
        rec = read_vibration_record(folder / f"{CWRU_HEALTHY}.mat", suffix, rig.sample_rate_Hz)
        kin = bearing.kinematics(rec.speed_rpm / 60.0).to_dict()
        for seconds in STRETCHES_S:
            n = int(seconds * rec.sample_rate_Hz)
            for i in range(rec.samples.size // n):
                out.append(envelope.measure(rec.samples[i * n:(i + 1) * n], rec.sample_rate_Hz, kin, settings))
    return out


def rows_of(name: str, counts: dict, n: int) -> list[dict]:
    rows = []
    for null in NULLS:
        for p in PROBABILITIES:
            k = counts[(null, p)]
            lo, hi = binom.ppf(0.005, n, p), binom.ppf(0.995, n, p)
            upper = float(beta.ppf(0.95, k + 1, n - k)) if k < n else 1.0
            rows.append({"kind": name, "null": null, "false_alarm_probability": p, "records": n, "alarms": k,
                         "observed_rate": k / n, "interval_99": [int(lo), int(hi)], "upper_95_rate": upper,
                         "verdict": "within" if lo <= k <= hi else ("above" if k > hi else "below")})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=250, help="records per kind, length and rate")
    parser.add_argument("--out", default="results/validation")
    parser.add_argument("--cwru", default="../shared/data/cwru_fan_end",
                        help="folder of the CWRU fan-end set (its healthy record fe39); left out where absent")
    parser.add_argument("--lengths", type=float, nargs="+", default=list(LENGTHS_S), help="record lengths [s]")
    parser.add_argument("--rates", type=float, nargs="+", default=list(RATES_HZ), help="sampling rates [Hz]")
    args = parser.parse_args()
    settings = envelope.Settings()
    cpu = time.process_time()
    rows, cells = [], {}
    for ki, kind in enumerate(KINDS):
        counts = {(null, p): 0 for null in NULLS for p in PROBABILITIES}
        for length in args.lengths:
            for rate in args.rates:
                cell = {(null, p): 0 for null in NULLS for p in PROBABILITIES}
                for j in range(args.n):
                    rng = np.random.default_rng([23, ki, int(length), int(rate), j])
                    shaft = rng.uniform(20.0, 30.0)
                    x = record(kind, rng, shaft, length, rate)
                    kin = BEARING.kinematics(shaft * rng.uniform(0.99, 1.01)).to_dict()
                    for key, alarm in calls(envelope.measure(x, rate, kin, settings), settings).items():
                        cell[key] += alarm
                for key in cell:
                    counts[key] += cell[key]
                name = f"{kind}, {length:g} s, {rate:g} Hz"
                cells[name] = {f"{null} {p:g}": cell[(null, p)] for null, p in cell}
                print(f"{name}: {cells[name]}", flush=True)
        rows += rows_of(kind, counts, args.n * len(args.lengths) * len(args.rates))
    all_counts = {key: sum(r["alarms"] for r in rows if (r["null"], r["false_alarm_probability"]) == key)
                  for key in ((null, p) for null in NULLS for p in PROBABILITIES)}
    rows += rows_of("all simulated", all_counts, args.n * len(args.lengths) * len(args.rates) * len(KINDS))
    folder = Path(args.cwru)
    if (folder / f"{CWRU_HEALTHY}.mat").exists():
        readings = cwru_readings(folder, settings)
        counts = {(null, p): 0 for null in NULLS for p in PROBABILITIES}
        for reading in readings:
            for key, alarm in calls(reading, settings).items():
                counts[key] += alarm
        rows += rows_of(f"CWRU {CWRU_HEALTHY} stretches", counts, len(readings))
    summary = {"settings": "envelope.Settings() defaults, the false-alarm probability and the null varied",
               "n_per_cell": args.n, "lengths_s": args.lengths, "rates_Hz": args.rates, "kinds": list(KINDS),
               "rows": rows, "cells": cells, "cpu_s": time.process_time() - cpu}
    out = Path(args.out)
    write_json(summary, out / "envelope_null.json")
    lines = ["| records | null | stated probability | alarms | observed rate | 99 % interval of the count | "
             "95 % upper bound of the rate | |",
             "|---|---|---:|---:|---:|---|---:|---|"]
    lines += [f"| {r['kind']} ({r['records']}) | {r['null']} | {r['false_alarm_probability']:g} | {r['alarms']} | "
              f"{r['observed_rate']:.4f} | {r['interval_99'][0]}-{r['interval_99'][1]} | {r['upper_95_rate']:.4f} | "
              f"{r['verdict']} |" for r in rows]
    (out / "envelope_null.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
