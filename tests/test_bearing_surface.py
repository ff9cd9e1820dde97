"""The healthy bearing's floor (piezobearing.bearing.surface): roughness, waviness, unbalance in the LPM."""

import numpy as np
import pytest

from piezobearing import config
from piezobearing.bearing import lpm, surface


@pytest.fixture(scope="module")
def bearing():
    return dict(config.load()["bearing"])


def test_discrete_spectrum_is_the_exponential_autocorrelation():
    """(1/n) sum P_k = sigma^2, and P_k dx tends to S(f) = 2 sigma^2 beta / (1 + (2 pi f beta)^2) at low f."""
    sigma, beta, dx, n = 0.1e-6, 10.0e-6, 2.5e-6, 2**16
    p = surface.discrete_spectrum(n, dx, sigma, beta)
    assert p.mean() == pytest.approx(sigma**2, rel=1e-9)
    f = np.fft.fftfreq(n, dx)
    low = (np.abs(f) > 0) & (np.abs(f) < 0.05 / dx)
    s = 2 * sigma**2 * beta / (1 + (2 * np.pi * f[low] * beta) ** 2)
    np.testing.assert_allclose(p[low] * dx, s, rtol=0.02)


def test_rough_profile_has_the_requested_rms_and_spectrum():
    """A drawn profile's RMS is sigma (within its sampling error), its mean periodogram the discrete spectrum."""
    sigma, beta, dx, n = 0.2e-6, 10.0e-6, 2.5e-6, 2**15
    p = surface.discrete_spectrum(n, dx, sigma, beta)
    rng = np.random.default_rng(1)
    draws = np.array([surface.rough_profile(n, dx, sigma, beta, rng) for _ in range(40)])
    # 40 profiles of 8200 correlation lengths each: the variance's relative error is about sqrt(2 beta / L / 40)
    assert np.sqrt(np.mean(draws**2)) == pytest.approx(sigma, rel=0.01)
    periodogram = np.mean(np.abs(np.fft.fft(draws, axis=1)) ** 2, axis=0) / n
    # bands of 256 bins: 40 x 256 exponential draws per band, a relative error of about 1 %
    bands = periodogram.reshape(-1, 256).mean(axis=1) / p.reshape(-1, 256).mean(axis=1)
    np.testing.assert_allclose(bands, 1.0, atol=0.05)


def test_contact_filter_is_the_box_average():
    """The filtered profile equals the moving average over 2b, and its variance the filtered spectrum's."""
    sigma, beta, dx, n = 0.1e-6, 10.0e-6, 1.0e-6, 2**14
    h = surface.rough_profile(n, dx, sigma, beta, np.random.default_rng(2))
    b = 20.0e-6  # 2b = 40 samples: an exact box of 41 points has the same sinc to 1/41
    filt = surface.contact_filtered(h, dx, b)
    k = int(round(2 * b / dx))
    box = np.convolve(np.r_[h[-k:], h, h[:k]], np.ones(k) / k, mode="same")[k:-k]
    # the box of k points is centred half a sample off: compare with the average of two shifts
    box = 0.5 * (box + np.roll(box, -1))
    assert np.sqrt(np.mean((filt - box) ** 2)) < 0.05 * np.std(filt)
    p = surface.discrete_spectrum(n, dx, sigma, beta) * np.sinc(2 * b * np.fft.fftfreq(n, dx)) ** 2
    assert np.std(filt) == pytest.approx(np.sqrt(p.mean()), rel=0.05)


def test_contact_half_width_closed_form():
    """b = sqrt(4 Q R / (pi l E*)) with E* = E / (2 (1 - nu^2)): 500 N on 10 mm over R = 5 mm."""
    e_star = 208.0e9 / (2 * (1 - 0.3**2))
    assert surface.contact_half_width_m(500.0, 5e-3, 10e-3) == pytest.approx(
        np.sqrt(4 * 500.0 * 5e-3 / (np.pi * 10e-3 * e_star)), rel=1e-12)


def test_waviness_heights(bearing):
    """A raceway's waviness at angle theta is sum A_n cos(n theta + phi_n)."""
    b = {**bearing, "waviness_orders": [2, 11], "waviness_amplitudes_m": [1e-6, 0.2e-6]}
    p = lpm.LPMParameters.from_config(b, False, seed=3)
    tr = p.surfaces.outer
    theta = np.linspace(-np.pi, np.pi, 101)
    expect = 1e-6 * np.cos(2 * theta + tr.phases_rad[0]) + 0.2e-6 * np.cos(11 * theta + tr.phases_rad[1])
    np.testing.assert_allclose(tr.height_m(theta), expect, rtol=1e-12, atol=1e-18)
    assert tr.profile_m.size == 0


def test_surfaces_are_seeded_per_realisation(bearing):
    """The same seed and realisation draw the same surfaces; another realisation or case other ones."""
    b = {**bearing, "roughness_rms_m": 0.1e-6}
    a = lpm.LPMParameters.from_config(b, False, seed=7, realisation=2).surfaces
    same = lpm.LPMParameters.from_config(b, False, seed=7, realisation=2).surfaces
    other = lpm.LPMParameters.from_config(b, False, seed=7, realisation=3).surfaces
    faulty = lpm.LPMParameters.from_config(b, True, seed=7, realisation=2).surfaces
    np.testing.assert_array_equal(a.outer.profile_m, same.outer.profile_m)
    assert not np.allclose(a.outer.profile_m, other.outer.profile_m)
    assert not np.allclose(a.outer.profile_m, faulty.outer.profile_m)


def test_off_is_the_ideal_bearing(bearing):
    """Every source at zero: no surfaces drawn, the same run as the ideal bearing's to the bit (one code path)."""
    p = lpm.LPMParameters.from_config(bearing, True, seed=7)
    assert p.surfaces is None
    ideal = lpm.LPMParameters(**{**p.__dict__, "surfaces": None})
    r1 = lpm.simulate_lpm(p, -0.005, 2000, 1e-5)
    r0 = lpm.simulate_lpm(ideal, -0.005, 2000, 1e-5)
    np.testing.assert_array_equal(r1.load_N, r0.load_N)


def test_roughness_loads_the_rollers(bearing):
    """Roughness changes the roller loads by about dQ/d delta times the filtered height of a loaded roller."""
    b = {**bearing, "roughness_rms_m": 0.1e-6}
    p = lpm.LPMParameters.from_config(b, False, seed=7)
    smooth = lpm.LPMParameters(**{**p.__dict__, "surfaces": None})
    r1 = lpm.simulate_lpm(p, -0.005, 5000, 1e-5)
    r0 = lpm.simulate_lpm(smooth, -0.005, 5000, 1e-5)
    dq = r1.load_N - r0.load_N
    loaded = r0.load_N > 100.0
    assert 0.5 < np.std(dq[loaded]) < 50.0  # newtons: (10/9) Q / delta ~ 1e8 N/m times tens of nm


def test_unbalance_force_reaches_the_rollers(bearing):
    """U omega^2 at the shaft frequency: far below the shaft's resonance on its rollers (~2 kHz) the rollers'
    resultant gains a component turning with the shaft of amplitude U omega^2 (within 1 %), in its phase."""
    u = 1.0e-3  # kg m: 11 N at 1000 rpm, well above the integration's noise
    b = {**bearing, "unbalance_kg_m": u}
    p = lpm.LPMParameters.from_config(b, False, seed=7)
    plain = lpm.LPMParameters(**{**p.__dict__, "surfaces": None})
    n = int(round(0.14 / 1e-5))  # two revolutions after 0.02 s of settling
    r1 = lpm.simulate_lpm(p, -0.02, n, 1e-5)
    r0 = lpm.simulate_lpm(plain, -0.02, n, 1e-5)

    def resultant(r):
        return (r.load_N * np.sin(r.psi_rad)).sum(1) - 1j * (r.load_N * np.cos(r.psi_rad)).sum(1)

    keep = (r1.time_s >= 0) & (r1.time_s < 2.0 / p.shaft_speed_Hz)
    d = (resultant(r1) - resultant(r0))[keep]
    angle = p.shaft_angle(r1.time_s[keep]) + p.surfaces.unbalance_phase_rad
    # the force U w^2 (sin a, -cos a) is -1j U w^2 exp(1j a) as y + 1j z: its turning component
    c = np.mean(d * np.exp(-1j * angle))
    scale = u * (2 * np.pi * p.shaft_speed_Hz) ** 2
    assert abs(c - (-1j * scale)) < 0.01 * scale


def test_roughness_heights_interpolate_the_periodic_grid(bearing):
    """A track's roughness between grid points is the linear interpolation of its periodic profile (np.interp
    with the period), at angles beyond one turn and negative ones too."""
    b = {**bearing, "roughness_rms_m": 0.1e-6}
    tr = lpm.LPMParameters.from_config(b, False, seed=5).surfaces.outer
    n = tr.profile_m.size
    x = np.arange(n) * (tr.circumference_m / n)
    theta = np.random.default_rng(0).uniform(-7.0, 13.0, 5000)
    theta[:3] = (0.0, 2 * np.pi, -2 * np.pi * (n - 1) / n)  # a grid point, the period, the last point
    s = np.mod(theta, 2 * np.pi) * (tr.circumference_m / (2 * np.pi))
    expect = np.interp(s, x, tr.profile_m, period=tr.circumference_m)
    np.testing.assert_allclose(tr.height_m(theta), expect, rtol=1e-9, atol=1e-9 * np.std(tr.profile_m))
