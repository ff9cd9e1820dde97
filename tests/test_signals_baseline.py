"""The baseline detector (roller-passage part removed, harmonics against a healthy baseline, impacts folded).

Signals of known content: a healthy record of smooth roller-passage bumps
(periodic at the slipped BPFO, sampled off the period's grid), and a fault's
short impacts at its kinematic times, seen only near the sensor (inner race:
the defect's shaft angle; rolling element: the flat roller's cage angle;
outer race: the groove under the sensor, every passage). Closed-form checks
of each step, the false-alarm rates by Monte Carlo within their binomial
bounds, and hide-and-find: healthy -> none, each fault -> its type, at the
paper's relative 10 dB and at a DAQ's micro-volt noise.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom, chi2
from test_signals_synthetic import FS, KIN  # the N 305 at 1000 rpm, no slip; the paper's DAQ rate

from piezobearing.signals import harmonics, outer_race
from piezobearing.signals.detectors import baseline
from piezobearing.signals.fault_bands import slipped_frequencies

SLIP = 0.015


def healthy(n: int, slip: float = SLIP, fs: float = FS, peak_V: float = 96.0) -> np.ndarray:
    """Smooth bumps, one per roller passing the sensor, periodic at BPFO(slip): a von Mises bump
    exp(10 (cos - 1)) (0.12 BPFO periods at half height; its harmonics fall as I_k(10), 1e-17 at k = 36)."""
    f0 = slipped_frequencies(KIN, slip)["bpfo_Hz"]
    t = np.arange(n) / fs
    v = peak_V * np.exp(10.0 * (np.cos(2 * np.pi * (t * f0 + 0.3)) - 1.0))
    return v - v.mean()


def impacts(fault_type: str, n: int, amp_V: float = 100.0, slip: float = SLIP, fs: float = FS) -> np.ndarray:
    """A fault's impacts (one sample at amp, the next at -amp/3) where the sensor sees them."""
    f = slipped_frequencies(KIN, slip)
    rate = {"outer_race": f["bpfo_Hz"], "inner_race": f["bpfi_Hz"], "rolling_element": f["2bsf_Hz"]}[fault_type]
    times = (0.17 + np.arange(int(n / fs * rate) + 2)) / rate
    if fault_type == "inner_race":  # the defect within +-40 deg of the sensor
        seen = np.abs(np.angle(np.exp(2j * np.pi * (f["shaft_Hz"] * times + 0.1)))) < np.radians(40)
    elif fault_type == "rolling_element":  # the flat roller within +-40 deg of the sensor
        seen = np.abs(np.angle(np.exp(2j * np.pi * (f["ftf_Hz"] * times + 0.4)))) < np.radians(40)
    else:
        seen = np.ones(times.size, bool)
    x = np.zeros(n)
    i = np.round(times[seen] * fs).astype(int)
    i = i[i < n - 1]
    x[i] += amp_V
    x[i + 1] -= amp_V / 3
    return x


def test_slip_from_the_roller_passage_lines():
    """The slip that puts the roller-passage lines at their peaks: within 2e-5 of the true one, noise or not."""
    n = 2295
    for s in (0.0, 0.008, 0.015, 0.027):
        v = healthy(n, s)
        assert baseline.estimate_slip(v, 1 / FS, KIN["bpfo_Hz"], 0.03) == pytest.approx(s, abs=2e-5)
    rng = np.random.default_rng(1)
    v = healthy(n) + 11.4 * rng.standard_normal(n)  # the paper's 10 dB
    assert baseline.estimate_slip(v, 1 / FS, KIN["bpfo_Hz"], 0.03) == pytest.approx(SLIP, abs=2e-4)


def test_periodic_part_takes_the_folded_harmonics_too():
    """A periodic record sampled off its period's grid: the fit up to f_s leaves < 1e-6 of it; up to Nyquist
    only, its harmonics above Nyquist stay (folded into the band) as the residual."""
    n = 2295
    f0 = slipped_frequencies(KIN, SLIP)["bpfo_Hz"]
    t = np.arange(n) / FS
    k = np.arange(1, 30)  # harmonics to 2090 Hz, beyond the 1275 Hz Nyquist frequency
    v = (np.cos(2 * np.pi * f0 * np.outer(t, k) + 0.7 * k) / k).sum(axis=1)
    r_full = v - harmonics.periodic_part(v, 1 / FS, f0, alias_folds=1.0)
    r_half = v - harmonics.periodic_part(v, 1 / FS, f0, alias_folds=0.5)
    assert np.std(r_full) < 1e-6 * np.std(v)
    above = (np.cos(2 * np.pi * f0 * np.outer(t, k[k * f0 > 0.4995 * FS]) + 0.7 * k[k * f0 > 0.4995 * FS])
             / k[k * f0 > 0.4995 * FS]).sum(axis=1)
    assert np.std(r_half) == pytest.approx(np.std(above), rel=0.2)


def test_fold_test_false_alarm_rate_by_monte_carlo():
    """White noise, known sigma: the search-corrected fold p-value is uniform in its tail: the rate of
    p < alpha within the binomial 99.9% interval of alpha (alpha = 5% and 1%, 3000 records)."""
    rng = np.random.default_rng(7)
    n, m = 2295, 3000
    period = 1 / slipped_frequencies(KIN, SLIP)["bpfi_Hz"]
    lp = np.array([baseline.fold_test(rng.standard_normal(n), 1 / FS, period)["log10_p"] for _ in range(m)])
    for alpha in (0.05, 0.01):
        lo, hi = binom.ppf([0.0005, 0.9995], m, alpha) / m
        assert lo <= np.mean(lp < np.log10(alpha)) <= hi, (alpha, np.mean(lp < np.log10(alpha)))


def test_fold_test_finds_impacts_on_their_period_only():
    """22 impacts on the 1/BPFI grid at 6 sigma: the BPFI fold's best cell holds them all (p < 1e-50); the 2 BSF
    fold spreads them (its best cell catches a few: p 1e-7, over 40 decades less significant)."""
    n = 2295
    rng = np.random.default_rng(3)
    z = rng.standard_normal(n) + impacts("inner_race", n, amp_V=6.0)
    f = slipped_frequencies(KIN, SLIP)
    right = baseline.fold_test(z, 1 / FS, 1 / f["bpfi_Hz"])["log10_p"]
    wrong = baseline.fold_test(z, 1 / FS, 1 / f["2bsf_Hz"])["log10_p"]
    assert right < -50 and wrong > right + 40


def test_harmonic_test_is_chi_square_under_noise():
    """Healthy bumps plus white noise against their own noiseless baseline: q over 2K - 1 degrees of freedom,
    the rate of q above its 95% quantile within the binomial 99.9% interval (1000 records, sigma known)."""
    n, m = 640, 1000
    dt = 1 / FS
    base = baseline.Baseline.from_record(healthy(n), dt, KIN, baseline.Settings())
    f0 = slipped_frequencies(KIN, base.slip)["bpfo_Hz"]
    rng = np.random.default_rng(11)
    x = np.array([healthy(n) + 2.0 * rng.standard_normal(n) for _ in range(m)])
    res = baseline.one_blas_thread(outer_race.harmonic_tests)(x, dt, [f0] * m, [base] * m, [2.0] * m)
    qs, dof = [r["statistic"] for r in res], res[0]["dof"]
    assert dof == 2 * harmonics.below_nyquist(dt, f0) - 1
    lo, hi = binom.ppf([0.0005, 0.9995], m, 0.05) / m
    assert lo <= np.mean(np.array(qs) > chi2.ppf(0.95, dof)) <= hi


def test_harmonic_fit_in_closed_form_equals_the_qr_solution():
    """The normal equations with A^T A from geometric sums and A^T x from the DTFT (or the chirp z-transform
    for long records) give the pivoted-QR least squares to 1e-9 of the coefficients."""
    rng = np.random.default_rng(4)
    for n, fs in ((2295, FS), (6000, 25600.0)):
        f0 = slipped_frequencies(KIN, SLIP)["bpfo_Hz"]
        k = harmonics.below_nyquist(1 / fs, f0)
        x = healthy(n, fs=fs) + rng.standard_normal(n)
        c, gram, _ = harmonics.harmonic_fit(x, 1 / fs, f0, k)
        a = harmonics.harmonic_matrix(n, 1 / fs, f0, k)
        assert np.allclose(gram, a.T @ a, rtol=0, atol=1e-9 * n)
        assert np.allclose(c, harmonics.lstsq_qr(a, x), rtol=0, atol=1e-9 * np.abs(c).max())


def test_slip_searched_harmonic_test_threshold_by_monte_carlo():
    """The outer-race test at the fundamental of the healthy model (the baseline's waveform fitted over the slip
    window, 0-3%): q below the likelihood ratio with f fitted in both models, chi^2 with 2K - 1 degrees of freedom
    (Wilks): with the roller train far above the noise per coefficient (96 V bumps, 2 V noise, sigma known) and
    buried in it (-10 dB relative), the rate above the chi^2_{2K-1} 95% quantile within the binomial 99.9% interval
    of 5% (300 records each) and the mean of q within 4 standard errors of 2K - 1."""
    n, m, dt = 640, 300, 1 / FS
    base = baseline.Baseline.from_record(healthy(n), dt, KIN, baseline.Settings())
    f_true = slipped_frequencies(KIN, SLIP)["bpfo_Hz"]
    window = (KIN["bpfo_Hz"] * 0.97, KIN["bpfo_Hz"])
    rng = np.random.default_rng(12)
    lo, hi = binom.ppf([0.0005, 0.9995], m, 0.05) / m
    for noise in (2.0, np.sqrt(10.0 * np.mean(healthy(n) ** 2))):
        x = np.array([healthy(n) + noise * rng.standard_normal(n) for _ in range(m)])
        res = baseline.one_blas_thread(outer_race.harmonic_tests)(x, dt, [f_true] * m, [base] * m, [noise] * m, 0.0, window)
        q, dof = np.array([r["statistic"] for r in res]), res[0]["dof"]
        assert dof == 2 * harmonics.below_nyquist(dt, window[1]) - 1
        assert lo <= np.mean(q > chi2.ppf(0.95, dof)) <= hi, (noise, np.mean(q > chi2.ppf(0.95, dof)))
        assert abs(q.mean() - dof) < 4.0 * np.sqrt(2.0 * dof / m), (noise, q.mean())


def test_tolerance_absorbs_a_baseline_off_by_its_size():
    """A healthy bearing 1% stronger than its baseline at micro-volt noise: exact baseline -> outer race
    'detected'; a 2% tolerance -> not."""
    n, dt = 2295, 1 / FS
    st = baseline.Settings()
    base = baseline.Baseline.from_record(healthy(n), dt, KIN, st)
    x = 1.01 * healthy(n) + 1e-4 * np.random.default_rng(2).standard_normal(n)
    assert baseline.detect(x, 1 / dt, KIN, st, base).details["per_type"]["outer_race"]["detected"]
    d = baseline.detect(x, 1 / dt, KIN, baseline.Settings(tolerance=0.02), base)
    assert not d.details["per_type"]["outer_race"]["detected"] and d.fault_type == "none"


def test_baseline_tolerances_from_config(paper_config):
    """signals.detector.baseline_tolerance and baseline_gain_tolerance reach the detector's settings (defaults 0:
    the workflow's baseline is the model's own noiseless healthy record)."""
    assert baseline.Settings.from_config(paper_config["signals"]) == baseline.Settings()
    sig = {**paper_config["signals"], "detector": {**paper_config["signals"]["detector"], "baseline_tolerance": 0.1,
                                                   "baseline_gain_tolerance": 0.05}}
    st = baseline.Settings.from_config(sig)
    assert (st.tolerance, st.gain_tolerance) == (0.1, 0.05)


def test_gain_tolerance_absorbs_a_level_off_but_not_the_fault():
    """A healthy bearing 10% stronger than its baseline (a load share off by 10%) at 0.01 V noise: outer race
    'detected' with g = 1, absorbed with a 10% gain tolerance; a synthetic outer-race fault at 10 dB stays
    detected with it (its impacts are not a change of level)."""
    n, dt = 2295, 1 / FS
    rng = np.random.default_rng(2)
    fixed, loose = baseline.Settings(), baseline.Settings(gain_tolerance=0.1)
    base = baseline.Baseline.from_record(healthy(n), dt, KIN, fixed)
    x = 1.1 * healthy(n) + 1e-2 * rng.standard_normal(n)
    assert baseline.detect(x, 1 / dt, KIN, fixed, base).details["per_type"]["outer_race"]["detected"]
    assert baseline.detect(x, 1 / dt, KIN, loose, base).fault_type == "none"
    v = healthy(n) + impacts("outer_race", n)
    d = baseline.detect(v + np.sqrt(np.mean(v**2) / 10.0) * rng.standard_normal(n), 1 / dt, KIN, loose, base)
    assert d.fault_type == "outer_race"


@pytest.mark.parametrize("noise", ["relative_10dB", "absolute_1uV"])
def test_hide_and_find(noise):
    """Healthy -> none, each fault type -> its type, 6 seeds each, at the paper's relative 10 dB (noise 11 V rms,
    the impacts' 100 V single samples) and at a DAQ's noise (3.6e-4 V rms, 1e-5 V/sqrt(Hz) over 1275 Hz) where
    the healthy bumps are 100 dB above the noise."""
    n, dt = 2295, 1 / FS
    st = baseline.Settings()
    h = healthy(n)
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    rng = np.random.default_rng(5)
    for true in ("none", "outer_race", "inner_race", "rolling_element"):
        v = h + (impacts(true, n) if true != "none" else 0.0)
        sigma = np.sqrt(np.mean(v**2) / 10.0) if noise == "relative_10dB" else 3.6e-4
        got = [d.fault_type for d in baseline.detect_many([v + sigma * rng.standard_normal(n) for _ in range(6)], 1 / dt, KIN,
                                                   st, base)]
        assert got == [true] * 6, (true, got)


def test_detect_reports_per_type_keys_and_refuses_another_clock():
    n, dt = 1200, 1 / FS
    st = baseline.Settings()
    base = baseline.Baseline.from_record(healthy(n), dt, KIN, st)
    d = baseline.detect(healthy(n) + np.random.default_rng(0).standard_normal(n), 1 / dt, KIN, st, base).to_dict()
    assert set(d["families"]) == set(d["details"]["per_type"]) == set(st.fault_types)
    assert d["method"] == "baseline" and d["band_Hz"] is None
    for r in d["details"]["per_type"].values():
        assert {"indicator", "threshold", "detected", "p_value", "margin"} <= set(r)
        assert r["threshold"] == pytest.approx(-np.log10(1e-3 / 3))
    with pytest.raises(ValueError, match="step"):
        baseline.detect(healthy(n), 1 / (0.5 * dt), KIN, st, base)


def test_fast_roller_passage_fit_equals_the_qr_method():
    """The normal equations in closed form (signals/harmonics.py) against the explicit matrix and pivoted QR
    (refine_period_qr), every harmonic to f_s at 25.6 kHz (K = 365, 731 columns): the same
    Gauss-Newton f0 to 1e-9 Hz and the same periodic part to 1e-10 of the 96 V train; at an f0 with f_s
    exactly 36 f0 (the paper's 2550 Hz without slip: folded harmonics coincide) the fit and step are the QR's."""
    rng = np.random.default_rng(5)
    for fs, n, slip in ((25600.0, 6000, SLIP), (FS, 2295, 0.0)):
        v = healthy(n, slip=slip, fs=fs) + 1e-3 * rng.standard_normal(n)
        f0 = slipped_frequencies(KIN, slip)["bpfo_Hz"] * (1 + 1e-6)
        fa, pa = harmonics.refine_period(v, 1 / fs, f0)
        fb, pb = harmonics.refine_period_qr(v, 1 / fs, f0)
        assert fa == pytest.approx(fb, abs=1e-9)
        assert np.abs(pa - pb).max() < 1e-10 * 96.0
    assert harmonics.Harmonics(2295, 1 / FS, FS / 36, harmonics.n_fitted(1 / FS, FS / 36, 1.0)).by_qr
    # started exactly at f_s / 36 at a DAQ's noise: the QR method's step (the FWL step there was +-3e-3 Hz of noise)
    f0 = slipped_frequencies(KIN, 0.0)["bpfo_Hz"]
    for _ in range(5):
        v = healthy(2295, slip=0.0) + 3.6e-4 * rng.standard_normal(2295)
        assert harmonics.refine_period(v, 1 / FS, f0)[0] == harmonics.refine_period_qr(v, 1 / FS, f0)[0]
    assert not harmonics.Harmonics(6000, 1 / 25600.0, 70.0, harmonics.n_fitted(1 / 25600.0, 70.0, 1.0)).by_qr


def test_chirp_sum_is_the_dtft():
    """Bluestein's sum_j u_j exp(2 pi i nu j m) equals the direct sum to 1e-12 of its size."""
    rng = np.random.default_rng(6)
    u = rng.standard_normal(3000) + 1j * rng.standard_normal(3000)
    nu = 0.0027671234
    m = np.arange(400)
    direct = np.exp(2j * np.pi * nu * np.outer(m, np.arange(u.size))) @ u
    assert np.abs(harmonics.chirp_sum(u, nu, m.size) - direct).max() < 1e-12 * np.abs(direct).max()


@pytest.mark.parametrize("noise", ["relative_10dB", "daq_3.6e-4V"])
def test_fast_detector_gives_the_qr_methods_indicators(monkeypatch, noise):
    """detect with the fast least squares and with the pivoted-QR roller-passage fit (refine_period_qr) and
    the two-inverse information matrix, on an inner-race record at 25.6 kHz (0.25 s):
    every type's indicator the same to 1e-6 (relative, or absolute below 1)."""
    fs, n = 25600.0, 6400
    dt = 1 / fs
    st = baseline.Settings()
    h = healthy(n, fs=fs)
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    v = h + impacts("inner_race", n, fs=fs)
    sigma = np.sqrt(np.mean(h**2) / 10.0) if noise == "relative_10dB" else 3.6e-4
    x = v + sigma * np.random.default_rng(8).standard_normal(n)
    new = baseline.detect(x, 1 / dt, KIN, st, base).details["per_type"]

    def old_information(gram, sigma, cb, tolerance):
        return np.linalg.inv(sigma**2 * np.linalg.inv(gram)[1:, 1:])

    monkeypatch.setattr(baseline, "refine_period", harmonics.refine_period_qr)
    monkeypatch.setattr(outer_race, "_information", old_information)  # the outer-race test's module (outer_race.py)
    old = baseline.detect(x, 1 / dt, KIN, st, base).details["per_type"]
    for t in new:
        assert new[t]["indicator"] == pytest.approx(old[t]["indicator"], rel=1e-6, abs=1e-6), t


def test_batched_searches_equal_one_by_one():
    """The outer-race searches stepped together over records (scalar_search.fminbound_many) take scipy's bounded
    Brent steps problem by problem: the same minima bit for bit as separate scipy calls; detect_many,
    and harmonic_tests give each record's detection exactly as alone, clipped or not."""
    from scipy.optimize import minimize_scalar

    from piezobearing.signals.scalar_search import fminbound_many

    rng = np.random.default_rng(9)
    c, w = rng.uniform(-1.0, 2.0, 60), rng.uniform(0.5, 20.0, 60)
    lo = rng.uniform(-1.0, 0.0, 60)
    hi = lo + rng.uniform(0.01, 3.0, 60)
    tol = 1e-5 * (1 + np.arange(60) % 3)
    x, fx = fminbound_many(lambda i, v: np.cos(w[i] * v) + (v - c[i]) ** 2, lo, hi, tol)
    for i in range(60):
        r = minimize_scalar(lambda v, i=i: np.cos(w[i] * v) + (v - c[i]) ** 2, bounds=(lo[i], hi[i]),
                            method="bounded", options={"xatol": tol[i]})
        assert (r.x, r.fun) == (x[i], fx[i])
    n, dt = 2295, 1 / FS
    st = baseline.Settings()
    h = healthy(n)
    base = baseline.Baseline.from_record(h, dt, KIN, st)
    xs = [h + impacts(t, n) + 11.0 * rng.standard_normal(n) for t in ("outer_race", "inner_race")]
    xs.insert(0, h + 11.0 * rng.standard_normal(n))
    xs.append(np.clip(h + 36.0 * rng.standard_normal(n), -60.0, 60.0))  # clipped: the clipped model
    many = baseline.detect_many(xs, FS, KIN, st, base)
    assert many == [baseline.detect(x, FS, KIN, st, base) for x in xs]
    f0 = slipped_frequencies(KIN, SLIP)["bpfo_Hz"]
    window = (KIN["bpfo_Hz"] * 0.97, KIN["bpfo_Hz"])
    many = outer_race.harmonic_tests(np.array(xs[:3]), dt, [f0] * 3, [base] * 3, [11.0] * 3, 0.01, window, 0.05)
    assert many == [outer_race.harmonic_test(x, dt, f0, base, 11.0, 0.01, window, 0.05) for x in xs[:3]]
