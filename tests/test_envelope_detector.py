"""The envelope detector, hide and find with known answers: an outer-race impulse train through a resonance in
noise, with the given speed 1.5 % off either way, is found; a healthy machine with strong shaft harmonics,
shaft-rate modulation and mesh sidebands is not called faulty at more than the stated false-alarm rate
(Monte Carlo)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import roots_legendre
from scipy.stats import binom, gamma

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.signals.detectors.null_calibration import healthy_machine

FS = 12_000.0
BEARING = RollingBearing.from_designation("SKF 6205")


def outer_race_impacts(rng: np.random.Generator, bpfo_Hz: float, seconds: float, amplitude: float) -> np.ndarray:
    """Impacts at BPFO with 1 % random jitter of each interval (slip), each ringing a 3.2 kHz resonance."""
    n = int(FS * seconds)
    t = np.arange(400) / FS
    ring = np.exp(-t / 1e-3) * np.sin(2 * np.pi * 3200.0 * t)
    times = np.cumsum(rng.normal(1.0, 0.01, int(seconds * bpfo_Hz) + 2) / bpfo_Hz)
    pulses = np.zeros(n)
    idx = (times[times < seconds] * FS).astype(int)
    pulses[idx] = amplitude * rng.uniform(0.8, 1.2, idx.size)
    return np.convolve(pulses, ring)[:n]


@pytest.mark.parametrize("speed_error", [-0.015, 0.015])
@pytest.mark.parametrize("with_harmonics", [True, False])
def test_outer_race_impulse_train_is_found_with_the_speed_off(speed_error, with_harmonics):
    rng = np.random.default_rng([5, int(speed_error > 0), int(with_harmonics)])
    shaft = 1797.0 / 60.0
    true = BEARING.kinematics(shaft, cage_slip=0.01)
    x = outer_race_impacts(rng, true.bpfo_Hz, 4.0, amplitude=3.0)  # impacts about a third of the noise rms
    x += healthy_machine(rng, shaft, 4.0, FS) if with_harmonics else rng.standard_normal(x.size)
    given = BEARING.kinematics(shaft * (1 + speed_error)).to_dict()  # nominal speed 1.5 % off, no slip
    d = envelope_detector.detect(x, FS, given, envelope_detector.Settings())
    assert d.fault_type == "outer_race", {f: e.margin_dB for f, e in d.families.items()}
    assert d.families["outer_race"].margin_dB > 3.0
    first = d.families["outer_race"].lines[0]
    assert first.label == "1xBPFO" and first.above
    assert first.frequency_Hz == pytest.approx(true.bpfo_Hz, rel=0.005)
    if with_harmonics:  # the shaft rate found from its harmonics, not the given one
        assert d.details["shaft"]["refined"]
        assert d.shaft_rate_Hz == pytest.approx(shaft, rel=1e-3)
    else:
        assert not d.details["shaft"]["refined"]


@pytest.mark.slow
def test_healthy_machine_with_shaft_harmonics_and_sidebands_false_alarms_at_most_at_the_stated_rate():
    """200 healthy records (2 s, shaft 29-30 Hz) at pfa 0.05, and the same records at the default 1e-3."""
    n_records, pfa = 200, 0.05
    loose = envelope_detector.Settings(false_alarm_probability=pfa)
    strict = envelope_detector.Settings()
    alarms_loose = alarms_strict = 0
    for j in range(n_records):
        rng = np.random.default_rng([17, j])
        shaft = rng.uniform(29.0, 30.0)
        x = healthy_machine(rng, shaft, 2.0, FS)
        kin = BEARING.kinematics(shaft * rng.uniform(0.99, 1.01)).to_dict()  # the given speed within 1 %
        alarms_loose += envelope_detector.detect(x, FS, kin, loose).fault_type != "none"
        alarms_strict += envelope_detector.detect(x, FS, kin, strict).fault_type != "none"
    # the count a detector at exactly the stated rate exceeds with probability 0.001
    assert alarms_loose <= binom.ppf(0.999, n_records, pfa), alarms_loose
    assert alarms_strict <= binom.ppf(0.999, n_records, 1e-3), alarms_strict


def test_settings_refuse_what_the_detector_cannot_call():
    with pytest.raises(ValueError, match="family 'cage' is not a call of the detector"):
        envelope_detector.Settings(families=("outer_race", "cage"))
    with pytest.raises(ValueError, match="give a probability in"):
        envelope_detector.Settings(false_alarm_probability=0.0)


def test_null_distribution_of_one_line_matches_the_closed_form():
    """One line, exact floor (a huge Gamma shape): P(max of M Exp(1) > t) = 1 - (1 - e^-t)^M."""
    null = envelope_detector.null_distribution((7,), 1e6)
    for t in (3.0, 6.0, 9.0):
        assert null.p_value(t) == pytest.approx(1 - (1 - np.exp(-t)) ** 7, rel=0.02)
    assert envelope_detector.line_threshold(1e-3, 7) == pytest.approx(-np.log(1 - (1 - 1e-3) ** (1 / 7)), rel=1e-12)


def test_the_null_threshold_beyond_the_grids_reach_is_the_union_bound_and_above_the_exact_quantile():
    """Few floor bins leave the smallest quadrature node's mass beyond any grid: there the threshold is the union
    bound, which is conservative (above the exact quantile wherever the grid reaches both)."""
    null = envelope_detector.null_distribution((3, 3, 3, 5, 5, 5), 2.0)
    assert null.union_bound(1e-3) > null.threshold(1e-3) > 0
    alpha = 0.5 * null.survival[-1]
    assert null.threshold(alpha) == null.union_bound(alpha) > null.x[-1]


@pytest.mark.parametrize("shape", [0.5, 1.0, 2.3, 7.0, 40.0, 300.5])
def test_null_quadrature_nodes_are_scipys_gamma_quantiles(shape):
    """The null distribution's nodes are scipy.stats' gamma quantiles bit for bit, from scipy.special alone."""
    nodes, weights = envelope_detector._gamma_nodes(shape)
    u, w = roots_legendre(envelope_detector._N_QUAD)
    assert np.array_equal(nodes, gamma.ppf(0.5 * (u + 1.0), shape, scale=1.0 / shape))
    assert np.array_equal(weights, 0.5 * w)
