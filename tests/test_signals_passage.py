"""The record on its roller-passage clock (signals/passage.py) and the baseline detector's folds on it.

A cage whose slip jitters from passage to passage: passage k lasts (1 - s) / (1 - s_k) mean periods, s_k drawn
with standard deviation ``jitter`` around the mean slip s (the LPM's `bearing.slip_jitter`). The healthy record is
the smooth roller bump of test_signals_baseline at the jittered passage phase theta(t); the faults' impacts fall
where their own phase crosses a whole cycle (outer race: theta; inner race: Z f_shaft t - theta; rolling element:
(2 BSF / BPFO) theta), seen near the sensor only.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom
from test_signals_baseline import FS, KIN, SLIP

from piezobearing.signals import harmonics, passage
from piezobearing.signals.detectors import baseline
from piezobearing.signals.fault_bands import slipped_frequencies

Z = 11
N = 2295  # the paper's record at 2550 Hz after the circuit's settling
F = slipped_frequencies(KIN, SLIP)


def passage_theta(t: np.ndarray, jitter: float, rng: np.random.Generator) -> np.ndarray:
    """Passage phase [cycles] of a cage at the mean slip whose slip is redrawn at every passage."""
    n = int(t[-1] * F["bpfo_Hz"] * 1.5) + 5
    s = SLIP + jitter * rng.standard_normal(n)
    tau = np.concatenate([[0.0], np.cumsum((1 - SLIP) / (1 - s) / F["bpfo_Hz"])]) - 0.3 / F["bpfo_Hz"]
    return np.interp(t, tau, np.arange(n + 1))


def jittered(kind: str, jitter: float, rng: np.random.Generator, amp_V: float = 100.0) -> tuple[np.ndarray, np.ndarray]:
    """(record [V], its true passage phase [cycles]): the roller bumps, plus the impacts of ``kind``."""
    t = np.arange(N) / FS
    th = passage_theta(t, jitter, rng)
    v = 96.0 * np.exp(10.0 * (np.cos(2 * np.pi * (th + 0.3)) - 1.0))
    v -= v.mean()
    if kind == "none":
        return v, th
    near = np.radians(40)
    ph, seen = {
        "outer_race": (th + 0.17, np.ones(N, bool)),
        "inner_race": (Z * KIN["shaft_Hz"] * t - th + 0.17,
                       np.abs(np.angle(np.exp(2j * np.pi * (KIN["shaft_Hz"] * t + 0.1)))) < near),
        "rolling_element": (F["2bsf_Hz"] / F["bpfo_Hz"] * th + 0.17,
                            np.abs(np.angle(np.exp(2j * np.pi * (th / Z + 0.4)))) < near),
    }[kind]
    i = np.nonzero((np.floor(ph[1:]) > np.floor(ph[:-1])) & seen[1:])[0] + 1
    i = i[i < N - 1]
    v[i] += amp_V
    v[i + 1] -= amp_V / 3
    return v, th


def noisy(v: np.ndarray, rng: np.random.Generator, snr_dB: float = 10.0) -> np.ndarray:
    return v + np.sqrt(np.mean(v**2) / 10.0 ** (snr_dB / 10.0)) * rng.standard_normal(v.size)


def test_kernel_keeps_dc_and_nearly_the_variance_of_white_noise():
    """The Kaiser-windowed sinc (half-width 16, beta 8) passes DC to 4e-5 at every fractional position; the sum of
    its squared weights (white noise's variance after it) is 1 on the grid and 0.938 half-way between samples
    (the band's edge a finite kernel cannot pass)."""
    w = passage.kernel_weights(np.linspace(0.0, 1.0, 101)[:-1])
    assert np.abs(w.sum(axis=1) - 1.0).max() < 1e-4
    var = (w**2).sum(axis=1)
    assert var[0] == pytest.approx(1.0, abs=1e-12) and 0.93 < var.min() <= var.max() <= 1.0 + 1e-12


@pytest.mark.parametrize("snr_dB", [np.inf, 10.0])
def test_passage_phase_follows_a_jittered_cage(snr_dB):
    """At 2% jitter the passage phase wanders 0.03 cycle rms about its mean rate over this record (a tenth of a
    cycle at its ends); the measured phase follows it to 0.008 cycle rms (0.003 without noise, the smoothing's lag
    behind the passage-to-passage changes; 0.006 at 10 dB)."""
    rng = np.random.default_rng(3)
    v, th = jittered("none", 0.02, rng)
    y = v if np.isinf(snr_dB) else noisy(v, rng, snr_dB)
    t = np.arange(N) / FS

    def off(phase):
        e = phase - th
        return float(np.sqrt(np.mean((e - e.mean())[100:-100] ** 2)))

    wander = off(np.polyval(np.polyfit(t, th, 1), t))
    assert wander > 0.025
    assert off(passage.passage_phase(y, 1 / FS, F["bpfo_Hz"])) < 0.008


def test_on_its_passage_clock_the_jittered_train_is_periodic_again():
    """The noiseless jittered train's residual after the roller-passage fit: 13 V rms on the record's clock, 0.25 V
    on the passage clock (the phase's 0.003 cycle lag on the bumps' flanks)."""
    v, _ = jittered("none", 0.02, np.random.default_rng(4))
    dt = 1 / FS
    f0, p = harmonics.refine_period(v, dt, F["bpfo_Hz"])
    clock = passage.on_passage_clock(v, dt, f0)
    _, pw = harmonics.refine_period(clock.voltage_V, dt, clock.f0_Hz)
    assert abs(clock.voltage_V.size - (N - 2 * passage.HALF_WIDTH)) <= 2  # the mean rate's samples between the ends
    assert np.std(clock.voltage_V - pw) < np.std(v - p) / 40


def test_a_record_without_a_roller_train_is_refused():
    with pytest.raises(ValueError, match="follow_passage_phase"):
        passage.passage_phase(np.random.default_rng(0).standard_normal(N), 1 / FS, F["bpfo_Hz"])


def test_folds_on_the_passage_clock_keep_their_false_alarm_rate():
    """Healthy records at 2% jitter and 10 dB: each fold's p-value falls below 0.05 at most as often as the
    binomial bound of 0.05 allows (Monte Carlo, 60 records; the folds' chi^2 holds on the resampled noise)."""
    st = baseline.Settings(follow_passage_phase=True)
    base = baseline.Baseline.from_record(jittered("none", 0.0, np.random.default_rng(0))[0], 1 / FS, KIN, st)
    m = 60
    hits = np.zeros(2, int)
    records = []
    for j in range(m):
        rng = np.random.default_rng([9, j])
        records.append(noisy(jittered("none", 0.02, rng)[0], rng))
    for d in baseline.detect_many(records, FS, KIN, st, base):  # each detection the record's alone
        hits += [d.details["tests"][t]["log10_p"] < np.log10(0.05) for t in ("inner_race", "rolling_element")]
    assert hits.max() <= binom.ppf(0.999, m, 0.05), hits


def test_jitter_no_longer_reads_as_an_inner_race_or_roller_fault():
    """Healthy at 2% jitter and 10 dB: folded on a constant period the smeared roller train's residual is called
    an inner-race and a roller fault in 10 of 10 records; on the passage clock in none. A fault of 30 V impacts
    (found 8 of 8 at no jitter on the constant period) is found 8 of 8 through the jitter on the passage clock."""
    st = baseline.Settings(follow_passage_phase=True)
    fixed = baseline.Settings()
    base = baseline.Baseline.from_record(jittered("none", 0.0, np.random.default_rng(0))[0], 1 / FS, KIN, st)
    folds = ("inner_race", "rolling_element")
    alarms = {True: np.zeros(2, int), False: np.zeros(2, int)}
    ys = []
    for j in range(10):
        rng = np.random.default_rng([9, j])
        ys.append(noisy(jittered("none", 0.02, rng)[0], rng))
    for s in (st, fixed):
        for d in baseline.detect_many(ys, FS, KIN, s, base):
            alarms[s.follow_passage_phase] += [d.details["per_type"][t]["detected"] for t in folds]
    assert alarms[False].tolist() == [10, 10] and alarms[True].tolist() == [0, 0], alarms
    for kind in folds:
        records = []
        for j in range(8):
            rng = np.random.default_rng([11, j])
            records.append(noisy(jittered(kind, 0.02, rng, 30.0)[0], rng))
        found = sum(d.details["per_type"][kind]["detected"] for d in baseline.detect_many(records, FS, KIN, st, base))
        assert found == 8, (kind, found)


def test_follow_passage_phase_from_config(paper_config):
    sig = paper_config["signals"]
    assert baseline.Settings.from_config(sig).follow_passage_phase is False
    on = {**sig, "detector": {**sig["detector"], "follow_passage_phase": True}}
    assert baseline.Settings.from_config(on).follow_passage_phase is True
