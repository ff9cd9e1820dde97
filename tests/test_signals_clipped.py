"""The baseline detector on clipped records (signals/detectors/baseline.py, its clipped-noise model).

The clipped normal's mean and variance in closed form against Monte Carlo;
the noise before the ADC recovered from a clipped record; hide-and-find on
records the ADC clipped (the healthy bumps of test_signals_baseline, 96 V
peak to peak, plus 36 V rms of noise over a +-60 V input: about a quarter of
the samples clipped, the daq_noise study's 1 V/sqrt(Hz) at 2550 Hz), where
the unclipped detector calls the healthy bearing an outer-race fault; and the
false-alarm rate of every type's test on clipped healthy records by Monte
Carlo within its binomial bound.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom
from test_signals_baseline import FS, KIN, healthy, impacts

from piezobearing.signals import daq
from piezobearing.signals.daq import quantise
from piezobearing.signals.detectors import baseline

SIGMA = 36.0  # V: 1 V/sqrt(Hz) over the 1275 Hz of a 2550 Hz DAQ (35.7 V)


def adc(v: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """The record through a 24-bit +-60 V ADC after white noise of ``sigma``."""
    return quantise(v + sigma * rng.standard_normal(v.size), 24, 60.0)[0]


@pytest.mark.parametrize("mu", [-80.0, -45.0, 0.0, 30.0, 59.0, 75.0])
@pytest.mark.parametrize("sigma", [0.0, 5.0, 36.0, 120.0])
def test_clipped_normal_moments_against_monte_carlo(mu, sigma):
    """Mean and variance of clip(mu + sigma Z, -60, 60) within 4 standard errors of 400 000 draws (sigma = 0:
    clip(mu) and 0 exactly); a side left open (hi = inf) is the one-sided clip."""
    z = np.random.default_rng(3).standard_normal(400_000)
    for lo, hi in ((-60.0, 60.0), (-60.0, np.inf)):
        y = np.clip(mu + sigma * z, lo, hi)
        m, v = baseline.clipped_normal_moments(mu, sigma, lo, hi)
        if sigma == 0:
            assert m == np.clip(mu, lo, hi) and v == 0.0
            continue
        se = np.sqrt(y.var() / y.size)
        assert abs(m - y.mean()) < 4 * se + 1e-12, (lo, hi)
        se_v = np.sqrt(np.var((y - y.mean()) ** 2) / y.size)
        assert abs(v - y.var()) < 4 * se_v + 1e-12, (lo, hi)


def test_clip_levels_counts_the_end_codes_only():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(5000)
    assert baseline.clip_levels(x) == (-np.inf, np.inf, 0.0)
    y = adc(40.0 * np.sin(np.arange(5000) * 0.01), 36.0, rng)
    lo, hi, frac = baseline.clip_levels(y)
    assert lo == pytest.approx(-60.0) and hi == pytest.approx(60.0, abs=1e-5)
    assert frac == pytest.approx(np.mean((y <= lo) | (y >= hi)))
    assert 0.1 < frac < 0.4


def test_a_known_adc_reads_clipping_at_its_end_codes_only():
    """At 24 bits over +-60 V (step 7.2 uV) and 0.36 mV of noise, a record whose extreme code two samples share by
    chance (40 V bumps, far inside the range; 9 of 200 such records) is clipped by the two-samples rule and not at the ADC's end codes; a record
    that reaches the end codes is clipped by both, with the same fraction."""
    ends = daq.end_codes_V(daq.NoiseSettings(model="absolute", adc_bits=24, range_V=60.0))
    assert ends == (-60.0, 60.0 - 120.0 / 2**24, 60.0 / 2**24)
    rng = np.random.default_rng(2)
    for _ in range(200):  # a record whose extreme code repeats (9 of these 200 do)
        y = quantise(healthy(2295, peak_V=40.0) + 3.6e-4 * rng.standard_normal(2295), 24, 60.0)[0]
        if baseline.clip_levels(y)[2] > 0:
            break
    else:
        pytest.fail("no record of 200 repeated an extreme code")
    assert baseline.clip_levels(y)[2] > 0 and baseline.clip_levels(y, ends) == (-np.inf, np.inf, 0.0)
    z = adc(40.0 * np.sin(np.arange(5000) * 0.01), 36.0, rng)
    assert baseline.clip_levels(z, ends)[2] == pytest.approx(baseline.clip_levels(z)[2]) and baseline.clip_levels(z, ends)[2] > 0.1
    assert daq.end_codes_V(daq.NoiseSettings()) is None  # the relative model has no ADC


def test_noise_before_the_adc_from_the_clipped_residual():
    """sigma from the residual's mean square against the clipped normal's variance: within 6% of the true 36 V
    on five records with a quarter of their samples clipped, where the clipped residual's own rms is lower."""
    n, dt = 2295, 1 / FS
    h = healthy(n)
    st = baseline.Settings()
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    rng = np.random.default_rng(11)
    for _ in range(5):
        x = adc(h, SIGMA, rng)
        d = baseline.detect(x, 1 / dt, KIN, st, base)
        p = d.details["per_type"]["outer_race"]
        assert 0.15 < p["clipped_fraction"] < 0.35
        assert p["noise_sigma_V"] == pytest.approx(SIGMA, rel=0.06)
        assert p["sigma_V"] < 0.9 * SIGMA  # the clipped residual's rms: what the unclipped model would take
        assert p["gain_tolerance_applied"]  # baseline_gain_tolerance 0: gain 1 either way
    loose = baseline.Settings(gain_tolerance=0.1)
    assert not baseline.detect(x, 1 / dt, KIN, loose, base).details["per_type"]["outer_race"]["gain_tolerance_applied"]
    passage = baseline.Settings(follow_passage_phase=True)
    assert not baseline.detect(x, 1 / dt, KIN, passage, base).details["per_type"]["inner_race"]["follow_passage_phase_applied"]


def test_hide_and_find_on_clipped_records():
    """A clipped healthy record -> none in 8 of 8 seeds (the unclipped detector: outer race in most of them);
    a clipped outer-race fault (100 V impacts every passage) -> outer race in 8 of 8."""
    n, dt = 2295, 1 / FS
    st = baseline.Settings()
    h = healthy(n)
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    rng = np.random.default_rng(5)
    xs = [adc(h, SIGMA, rng) for _ in range(8)]
    got = [d.fault_type for d in baseline.detect_many(xs, 1 / dt, KIN, st, base)]
    old = [d.fault_type for d in baseline._detect_unclipped(xs, dt, KIN, base, st)]  # the model without clipping
    assert got == ["none"] * 8, got
    assert old.count("outer_race") >= 6, old  # the bug the clipped model fixes
    faulty = [d.fault_type for d in baseline.detect_many([adc(h + impacts("outer_race", n), SIGMA, rng) for _ in range(8)],
                                                   1 / dt, KIN, st, base)]
    assert faulty == ["outer_race"] * 8, faulty


def test_unclipped_records_go_through_the_baseline_detector_unchanged():
    n, dt = 1200, 1 / FS
    st = baseline.Settings()
    h = healthy(n)
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    x = h + 3.0 * np.random.default_rng(2).standard_normal(n)
    a, b = baseline.detect(x, 1 / dt, KIN, st, base), baseline._detect_unclipped([x], dt, KIN, base, st)[0]
    assert a == b
    for t in st.fault_types:
        assert a.details["per_type"][t]["clipped_fraction"] == 0.0


@pytest.mark.slow
def test_clipped_false_alarm_rate_by_monte_carlo():
    """Clipped healthy records (a quarter of the samples clipped): each type's rate of p < 5% within the binomial
    99.9% interval of 5% (400 records, 1 s at 2550 Hz), and no record called faulty more often than the
    configured 1e-3 allows (at most the binomial 99.9% quantile). The records detected together
    (``detect_many``: each detection the record's alone, the same 400 records and numbers as one by one)."""
    n, dt, m = 2550, 1 / FS, 400
    st = baseline.Settings()
    h = healthy(n)
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    rng = np.random.default_rng(17)
    p, called = {t: [] for t in st.fault_types}, 0
    for d in baseline.detect_many([adc(h, SIGMA, rng) for _ in range(m)], 1 / dt, KIN, st, base):
        called += d.fault_type != "none"
        for t in st.fault_types:
            p[t].append(d.details["per_type"][t]["p_value"])
    lo, hi = binom.ppf([0.0005, 0.9995], m, 0.05) / m
    for t, v in p.items():
        assert lo <= np.mean(np.array(v) < 0.05) <= hi, (t, np.mean(np.array(v) < 0.05))
    assert called <= binom.ppf(0.9995, m, st.false_alarm_probability)


def test_every_fault_type_found_where_its_peaks_clip():
    """The bumps shifted to reach 56 V, 11 V rms of noise (the paper's 10 dB) over the +-60 V input: 4-9% of the
    samples clipped (the bumps' tops and the impacts); healthy -> none and each fault -> its type, 3 seeds each
    (the residual's mean square, which the impacts raise, leaves the folds their margin)."""
    n, dt = 2295, 1 / FS
    st = baseline.Settings()
    h = healthy(n) - 30.0
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    rng = np.random.default_rng(3)
    for true in ("none", "outer_race", "inner_race", "rolling_element"):
        v = h + (impacts(true, n) if true != "none" else 0.0)
        got = []
        for d in baseline.detect_many([adc(v, 11.0, rng) for _ in range(3)], 1 / dt, KIN, st, base):
            assert d.details["per_type"]["outer_race"]["clipped_fraction"] > 0.02
            got.append(d.fault_type)
        assert got == [true] * 3, (true, got)
