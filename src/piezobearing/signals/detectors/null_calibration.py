"""The envelope detector's null, calibrated: the level of each test that makes the stated false-alarm probability
the rate at which records without a fault are called faulty.

The detector tests every family in every band (:mod:`.envelope`); a record raises an alarm at a level per test
``alpha`` where any of those tests passes, that is where ``alpha`` lies above the record's critical level
(:func:`.envelope.critical_alpha`). Split by Bonferroni (``pfa`` over the families and bands) the level is an
upper bound: the tests are correlated (the two bands hold the same impulses; the families share bins), and each
test's computed null is itself conservative (the Hann window's correlated bins: fewer independent maxima than
bins). Measured, the rate lay 12-25 times below the stated probability at 0.01-0.1.

How conservative depends on the record's length: a longer record has more bins per line window and a
wider median floor (of fixed width in Hz), and its computed null is nearer the truth. The calibration table
(``null_calibration.json``, written by ``python scripts/calibrate_null.py``) holds, per record length and stated
probability ``p``, the level per test at which a share ``p`` of its records without a fault (the binomial
count's median, :data:`CONFIDENCE`) raise an alarm: an order statistic of their critical levels. Its records, what null they
stand for, and the settings it was made with are in the table itself. Between its probabilities the level is
interpolated in log-log; below the smallest, the smaller of the smallest's ratio to the probability (its
effective number of independent tests) and the power law fitted to the length's rows; above the largest, the
largest's ratio; between lengths it is interpolated in log-log; below the shortest, the shortest's level, and
beyond the longest the smaller of the longest's and the Bonferroni split (:func:`alpha_per_test`).
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path

import numpy as np

#: The committed table.
TABLE = Path(__file__).with_name("null_calibration.json")
#: The count of alarms a level lets through on the table's records: the binomial quantile of the stated
#: probability at this confidence; 0.5, its median, calibrates the rate itself (a larger confidence sets the
#: level lower, for a rate below the stated one with that confidence) [-].
CONFIDENCE = 0.5


@lru_cache(maxsize=1)
def table() -> dict:
    """The committed calibration table (:data:`TABLE`)."""
    return json.loads(TABLE.read_text(encoding="utf-8"))


def alpha_per_test(pfa: float, seconds: float, n_tests: int, calibration: dict | None = None) -> float:
    """The level per test for a stated false-alarm probability ``pfa`` and a record of ``seconds`` [-]
    (module docstring): each calibrated length's level for ``pfa``, interpolated in log-log over the length.
    A record shorter than the shortest length takes that length's level (a shorter record's null is more
    conservative still); one longer than the longest the smaller of that length's level and the Bonferroni
    split ``pfa / n_tests`` (the calibration has not measured it)."""
    if calibration is None:
        return _committed_level(float(pfa), float(seconds), int(n_tests))
    rows = calibration["rows"]
    lengths = sorted({r["length_s"] for r in rows})
    levels = np.log([_level(pfa, [r for r in rows if r["length_s"] == t]) for t in lengths])
    level = float(math.exp(np.interp(math.log(max(seconds, lengths[0])), np.log(lengths), levels)))
    return min(level, pfa / n_tests) if seconds > lengths[-1] else level


@lru_cache(maxsize=256)
def _committed_level(pfa: float, seconds: float, n_tests: int) -> float:
    """:func:`alpha_per_test` of the committed table (a record's level is asked for at every decision)."""
    return alpha_per_test(pfa, seconds, n_tests, table())


def _level(pfa: float, rows: list[dict]) -> float:
    """One length's level for ``pfa``: log-log interpolation between its rows; above the largest probability the
    largest's ratio of level to probability; below the smallest, the smaller of the smallest's ratio (a constant
    effective number of tests) and the least-squares power law through the rows (where the share of records
    with a small critical level falls slower than the level, that ratio would overstate the level)."""
    rows = sorted(rows, key=lambda r: r["false_alarm_probability"])
    p = np.log([r["false_alarm_probability"] for r in rows])
    a = np.log([r["alpha_per_test"] for r in rows])
    lp = math.log(pfa)
    if lp >= p[-1]:
        return float(math.exp(a[-1] + lp - p[-1]))
    if lp > p[0]:
        return float(math.exp(np.interp(lp, p, a)))
    ratio = a[0] + lp - p[0]
    if p.size < 2:
        return float(math.exp(ratio))
    slope, intercept = np.polyfit(p, a, 1)
    return float(math.exp(min(ratio, intercept + slope * lp)))


def calibrate(critical: np.ndarray, probabilities: tuple[float, ...], seconds: float,
              confidence: float = CONFIDENCE) -> list[dict]:
    """The table's rows for records of ``seconds`` from the critical levels of such records without a fault
    (:func:`.envelope.critical_alpha`).

    For each probability ``p`` of ``probabilities`` the level is the (k+1)-th smallest critical level, k the
    count of alarms that ``n`` records at a rate of exactly ``p`` reach with probability ``confidence``
    (binomial): at that level k of the records raise an alarm. A probability whose bound is no alarm at all
    (n p too small) has no row: give more records.
    """
    # Imported here: scipy.stats costs about 0.6 s of import, and only the table's making needs it (a
    # detection reads the table).
    from scipy.stats import binom

    a = np.sort(np.asarray(critical, dtype=float))
    n = a.size
    rows = []
    for p in probabilities:
        k = int(binom.ppf(1.0 - confidence, n, p))
        if k < 1:
            continue
        level = float(a[k])
        rows.append({"length_s": float(seconds), "false_alarm_probability": float(p), "alpha_per_test": level, "alarms_allowed": k,
                     "records": int(n), "effective_tests": float(p / level)})
    return rows


def healthy_machine(rng: np.random.Generator, shaft_Hz: float, seconds: float, sample_rate_Hz: float) -> np.ndarray:
    """A record of a healthy machine, one kind of the table's records without a fault (and of the null's
    validation and tests): white noise modulated at the shaft rate, its first 8 harmonics far above the noise,
    and a 31 x shaft mesh tone with +-1, +-2 shaft-rate sidebands [g], sampled at ``sample_rate_Hz`` [Hz]."""
    t = np.arange(int(sample_rate_Hz * seconds)) / sample_rate_Hz
    phase = 2 * np.pi * shaft_Hz * t
    x = (1.0 + 0.5 * np.cos(phase + rng.uniform(0, 2 * np.pi))) * rng.standard_normal(t.size)
    for k in range(1, 9):
        x += 3.0 / k * np.cos(k * phase + rng.uniform(0, 2 * np.pi))
    x += 2.0 * (1 + 0.6 * np.cos(phase) + 0.3 * np.cos(2 * phase)) * np.cos(31 * phase)
    return x
