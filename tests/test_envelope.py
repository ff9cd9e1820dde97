"""Envelope methods: pre-whitening, (squared) envelope spectra, the fast kurtogram, against closed forms; the shaft's and the
supply's rates from their harmonics."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft

from piezobearing.signals import envelope, fault_bands
from piezobearing.signals.detectors import envelope as envelope_detector

FS = 12_000.0


def _am_record(m: float, fm_Hz: float, fc_Hz: float, seconds: float = 2.0) -> tuple[np.ndarray, float]:
    t = np.arange(int(FS * seconds)) / FS
    return (1.0 + m * np.cos(2 * np.pi * fm_Hz * t)) * np.cos(2 * np.pi * fc_Hz * t), 1.0 / FS


def test_prewhitening_sets_every_bin_to_unit_magnitude_and_keeps_the_phase():
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.standard_normal(4096)) + 5.0 * np.sin(2 * np.pi * 0.05 * np.arange(4096))
    w = envelope.prewhiten(x)
    spectrum_x, spectrum_w = np.fft.rfft(x - x.mean()), np.fft.rfft(w)
    np.testing.assert_allclose(np.abs(spectrum_w[1:]), 1.0, rtol=1e-9)
    np.testing.assert_allclose(np.angle(spectrum_w[1:] / spectrum_x[1:]), 0.0, atol=1e-9)


def test_envelope_and_squared_envelope_of_a_tone_modulation_match_the_closed_form():
    """(1 + m cos wt)^2 = 1 + m^2/2 + 2m cos wt + m^2/2 cos 2wt: the SES has 2m at fm and m^2/2 at 2 fm."""
    m, fm = 0.3, 50.0
    x, dt = _am_record(m, fm, 3000.0)
    band = (2500.0, 3500.0)
    env = envelope.envelope_spectrum(x, dt, band)
    ses = envelope.envelope_spectrum(x, dt, band, squared=True)
    i1, i2 = int(round(fm / env.resolution_Hz)), int(round(2 * fm / env.resolution_Hz))
    gain = envelope.band_gain(np.array([3000.0]), FS, band, 4)[0]  # |H|^2 at the carrier
    assert env.amplitude_V[i1] == pytest.approx(m * gain, rel=2e-3)
    assert ses.amplitude_V[i1] == pytest.approx(2 * m * gain**2, rel=2e-3)
    assert ses.amplitude_V[i2] == pytest.approx(m**2 / 2 * gain**2, rel=2e-3)


def test_hann_window_keeps_the_amplitude_of_a_line_on_a_bin():
    m, fm = 0.2, 40.0
    x, dt = _am_record(m, fm, 2000.0)
    band = (1500.0, 2500.0)
    rect = envelope.envelope_spectrum(x, dt, band)
    hann = envelope.envelope_spectrum(x, dt, band, window="hann")
    i = int(round(fm / rect.resolution_Hz))
    assert hann.amplitude_V[i] == pytest.approx(rect.amplitude_V[i], rel=1e-3)
    with pytest.raises(ValueError, match="window 'flat' unknown"):
        envelope.envelope_spectrum(x, dt, band, window="flat")


def test_tree_bands_follow_the_one_third_binary_tree():
    bands = envelope.tree_bands(FS, 3.0)
    levels = sorted({round(b[0], 3) for b in bands})
    assert levels == [0.0, 1.0, 1.585, 2.0, 2.585, 3.0]
    for level in levels:
        row = [b for b in bands if round(b[0], 3) == level]
        assert len(row) == int(round(2**level))  # 1, 2, 3, 4, 6, 8 bands
        assert row[0][1] == 0.0 and row[-1][2] == pytest.approx(FS / 2)  # each level tiles [0, Nyquist]


def test_fast_kurtogram_finds_the_resonance_of_an_impulse_train_and_is_near_zero_on_noise():
    rng = np.random.default_rng(7)
    n = int(FS * 4)
    t = np.arange(400) / FS
    ring = np.exp(-600.0 * t) * np.sin(2 * np.pi * 4200.0 * t)  # a 4.2 kHz resonance
    pulses = np.zeros(n)
    pulses[(np.arange(0, 4.0, 1 / 87.3) * FS).astype(int)] = 1.0
    x = np.convolve(pulses, ring)[:n] + 0.3 * rng.standard_normal(n)  # noise dominates away from the resonance
    kg = envelope.fast_kurtogram(x, 1 / FS, min_bandwidth_Hz=300.0)
    low, high = kg.best_band_Hz
    assert low < 4200.0 < high
    assert kg.kurtosis.max() > 1.0
    noise = envelope.fast_kurtogram(rng.standard_normal(n), 1 / FS, min_bandwidth_Hz=300.0)
    assert np.all(np.abs(noise.kurtosis) < 0.5)


def test_fast_kurtogram_leaves_out_bands_below_the_lowest_edge():
    x = np.random.default_rng(3).standard_normal(20_000)
    kg = envelope.fast_kurtogram(x, 1 / FS, min_bandwidth_Hz=500.0, min_low_Hz=400.0)
    assert kg.low_Hz.min() >= 400.0
    with pytest.raises(ValueError, match="not below Nyquist"):
        envelope.fast_kurtogram(x, 1 / FS, min_bandwidth_Hz=7000.0)


def test_an_envelope_spectrum_from_the_record_s_transform_given_is_the_one_computed():
    x, dt = _am_record(0.3, 50.0, 3000.0, seconds=1.37)  # 16,440 samples: two bands read on one transform
    spectrum = scipy.fft.rfft(x)
    for band in ((2500.0, 3500.0), (1000.0, 5000.0)):
        own = envelope.envelope_spectrum(x, dt, band, window="hann", squared=True)
        given = envelope.envelope_spectrum(x, dt, band, window="hann", squared=True, spectrum=spectrum)
        np.testing.assert_allclose(given.amplitude_V, own.amplitude_V, rtol=1e-12, atol=0.0)


def _harmonics(f_Hz: float, n: int, seconds: float = 10.0, noise: float = 0.05) -> tuple[np.ndarray, float]:
    """n harmonics k f of unit amplitude in white noise, 12 kHz."""
    t = np.arange(int(FS * seconds)) / FS
    x = sum(np.cos(2 * np.pi * k * f_Hz * t + 0.3 * k) for k in range(1, n + 1))
    return x + noise * np.random.default_rng(2).standard_normal(t.size), 1.0 / FS


def test_the_shaft_rate_is_refined_from_its_harmonics_alike_with_the_ratio_spectrum_given_or_not():
    """A shaft at 29.35 Hz given as 29.0 Hz +- 2 %: refined to within a bin over its highest harmonic (0.1 Hz / 10),
    the same from the record's harmonic-ratio spectrum passed in; a supply at 50 Hz found in the same spectrum."""
    x, dt = _harmonics(29.35, 10)
    shaft = fault_bands.refine_shaft_rate(x, dt, 29.0, 0.02)
    assert shaft.refined and shaft.harmonics == tuple(range(1, 11))
    assert shaft.shaft_Hz == pytest.approx(29.35, abs=0.1 / 10)
    ratio = fault_bands.harmonic_ratio(x, dt)
    given = fault_bands.refine_shaft_rate(x, dt, 29.0, 0.02, ratio=ratio)
    assert given.harmonics == shaft.harmonics and given.refined
    assert given.shaft_Hz == pytest.approx(shaft.shaft_Hz, rel=1e-12)
    assert given.tolerance == pytest.approx(shaft.tolerance, rel=1e-12)
    mains, _ = _harmonics(50.0, 8)
    found = envelope_detector.electrical_rate(mains, dt, (50.0, 60.0))
    assert found is not None and found.shaft_Hz == pytest.approx(50.0, abs=0.01)
    given = envelope_detector.electrical_rate(mains, dt, (50.0, 60.0), fault_bands.harmonic_ratio(mains, dt))
    assert given is not None and given.shaft_Hz == pytest.approx(found.shaft_Hz, rel=1e-12)
