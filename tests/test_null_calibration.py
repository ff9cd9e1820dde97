"""The envelope detector's calibrated null: a record's critical level is where its call turns into an alarm, the
table's levels are the order statistics they claim, and the level between and beyond the table's rows."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import binom

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.signals.detectors import envelope, is_alarm, null_calibration
from piezobearing.signals.detectors.null_calibration import healthy_machine

BEARING = RollingBearing.from_designation("SKF 6205")
FS = 12000.0


def _readings(n: int, seconds: float = 2.0):
    settings = replace(envelope.Settings(), calibrated_null=False)
    out = []
    for j in range(n):
        rng = np.random.default_rng([71, j])
        shaft = rng.uniform(20.0, 30.0)
        x = healthy_machine(rng, shaft, seconds, FS) if j % 2 else rng.standard_normal(int(seconds * FS))
        out.append(envelope.measure(x, FS, BEARING.kinematics(shaft * 1.005).to_dict(), settings))
    return out, settings


def test_the_critical_level_is_where_the_call_becomes_an_alarm():
    readings, settings = _readings(8)
    for reading in readings:
        a = envelope.critical_alpha(reading, settings)
        tests = len(settings.families) * len(reading.bands)
        for factor, alarm in ((0.97, False), (1.03, True)):
            pfa = a * factor * tests
            if pfa >= 1.0:
                continue
            call, _, _ = envelope.call_of(reading, replace(settings, false_alarm_probability=pfa))
            assert is_alarm(call) == alarm, (a, factor, call)


def test_a_fault_has_a_small_critical_level_and_two_lines_asked_raise_it():
    rng = np.random.default_rng(3)
    shaft = 1797.0 / 60.0
    kin = BEARING.kinematics(shaft)
    t = np.arange(int(4 * FS)) / FS
    x = rng.standard_normal(t.size)
    for t0 in np.cumsum(rng.normal(1 / kin.bpfo_Hz, 0.01 / kin.bpfo_Hz, int(4 * kin.bpfo_Hz))):
        on = (t >= t0) & (t < t0 + 0.01)
        x[on] += 3.0 * np.exp(-(t[on] - t0) / 1e-3) * np.sin(2 * np.pi * 3200.0 * (t[on] - t0))
    settings = replace(envelope.Settings(), calibrated_null=False)
    reading = envelope.measure(x, FS, kin.to_dict(), settings)
    one = envelope.critical_alpha(reading, settings)
    two = envelope.critical_alpha(reading, replace(settings, min_lines_above=2))
    assert one < 1e-6
    assert two >= one


def test_the_table_is_the_order_statistic_of_the_binomial_count():
    # critical levels of a detector whose per-test levels are exact: uniform
    levels = np.random.default_rng(0).uniform(size=4000)
    rows = null_calibration.calibrate(levels, (0.01, 0.05, 0.1), 5.0)
    for r in rows:
        p = r["false_alarm_probability"]
        k = int(binom.ppf(0.5, 4000, p))
        assert r["alarms_allowed"] == k
        assert np.sum(levels < r["alpha_per_test"]) == k
        assert r["alpha_per_test"] == pytest.approx(p, abs=3 * math.sqrt(p * (1 - p) / 4000))
    bound = null_calibration.calibrate(levels, (0.05,), 5.0, confidence=0.95)[0]
    assert bound["alarms_allowed"] == int(binom.ppf(0.05, 4000, 0.05)) < rows[1]["alarms_allowed"]
    assert null_calibration.calibrate(levels, (1e-5,), 5.0) == []  # no alarm at the count's median: no row


def test_the_level_between_and_beyond_the_rows():
    table = {"rows": [{"length_s": t, "false_alarm_probability": p, "alpha_per_test": p * c}
                      for t, c in ((2.0, 1.0), (8.0, 0.25)) for p in (0.01, 0.1)]}

    def level(p, t):
        return null_calibration.alpha_per_test(p, t, 6, table)

    assert level(0.01, 2.0) == pytest.approx(0.01)
    assert level(0.1, 8.0) == pytest.approx(0.025)
    assert level(0.001, 2.0) == pytest.approx(0.001)  # below the rows: the smallest's ratio (here the power law too)
    assert level(0.01, 4.0) == pytest.approx(0.01 * 0.5)  # log-log between the lengths
    assert level(0.01, 1.0) == level(0.01, 2.0)  # shorter than the shortest: the shortest's
    assert level(0.1, 20.0) == pytest.approx(0.1 / 6)  # longer than the longest: at most Bonferroni's
    assert level(0.01, 20.0) == pytest.approx(0.01 / 6)
    # a tail heavier than the rows' ratio: below them the power law through the rows, the smaller
    heavy = {"rows": [{"length_s": 5.0, "false_alarm_probability": p, "alpha_per_test": a}
                      for p, a in ((0.01, 0.001), (0.1, 0.02))]}
    assert null_calibration.alpha_per_test(0.001, 5.0, 6, heavy) == pytest.approx(0.001 * 10 ** -math.log10(20))


def test_the_committed_table_says_how_it_was_made_and_its_levels_grow_with_the_probability():
    table = null_calibration.table()
    assert table["made_by"].startswith("python scripts/calibrate_null.py")
    for t in {r["length_s"] for r in table["rows"]}:
        rows = sorted((r for r in table["rows"] if r["length_s"] == t), key=lambda r: r["false_alarm_probability"])
        levels = [r["alpha_per_test"] for r in rows]
        assert levels == sorted(levels)
    # the default's level per test, 1e-3 stated: never below Bonferroni's split over 3 families and 2 bands
    assert null_calibration.alpha_per_test(1e-3, 5.0, 6) >= 1e-3 / 6
