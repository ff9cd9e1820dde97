"""The calibration chain recovers what the synthetic experiment put in."""

import numpy as np
import pytest

from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.sensor import calibration
from piezobearing.sensor.lowfreq import asymptote_onset_Hz, lowfreq_sensitivity
from piezobearing.stages.calibration import nominal_circuit


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_resistance_recovered_within_2_percent_and_ci_contains_truth(paper_config, seed):
    c = paper_config
    truth = c["synthesis"]["resistance_ohm"]
    circuit = nominal_circuit(c)
    m = synthesize(PressProtocol.from_config(c["synthesis"]), circuit, seed)
    res = calibration.fit_resistance(m.force_N, m.voltage_V, m.dt_s, circuit, initial_ohm=10e6)
    r = res.values["resistance_ohm"]
    assert r == pytest.approx(truth, rel=0.02)
    lo, hi = res.ci95["resistance_ohm"]
    assert lo < truth < hi


@pytest.mark.parametrize("truth", [5e6, 50e6, 500e6])
def test_resistance_recovered_over_decades(paper_config, truth):
    c = paper_config
    circuit = nominal_circuit(c, truth)
    m = synthesize(PressProtocol.from_config(c["synthesis"]), circuit, 11)
    res = calibration.fit_resistance(m.force_N, m.voltage_V, m.dt_s, circuit, initial_ohm=10e6)
    assert res.values["resistance_ohm"] == pytest.approx(truth, rel=0.05)


def test_impulse_sensitivity_near_paper_by_construction(paper_record, paper_config):
    # The synthetic presses were chosen to land near 74.4 mV/N (see diagnosis/calibration/presses.py); 5% tolerance.
    c = paper_config["calibration"]
    m = paper_record
    imps = calibration.detect_impulses(
        m.force_N, m.voltage_V, m.dt_s, c["min_prominence_fraction"], c["min_separation_s"]
    )
    assert len(imps) == paper_config["synthesis"]["n_impulses"]
    s = calibration.sensitivity_summary(imps, m.time_s)
    assert s["sensitivity_V_per_N"] == pytest.approx(74.4e-3, rel=0.05)
    lo, hi = s["sensitivity_ci95_V_per_N"]
    assert lo < s["sensitivity_V_per_N"] < hi


def test_noise_free_sensitivity_matches_slope_estimate(paper_config):
    # Without noise, each impulse's peak voltage is close to G tau pi F/(2 T_r), the estimate in diagnosis/calibration/presses.py.
    circuit = nominal_circuit(paper_config)
    dt, rise = 1e-4, 0.42
    from piezobearing.diagnosis.calibration.presses import press_pulse

    t = np.arange(0, 2.0, dt)
    f = press_pulse(t, 0.8, 10.0, rise, 0.5)
    v = calibration.circuit_voltage(f, dt, circuit)
    estimate = circuit.open_circuit_gain_V_per_N * circuit.tau_s * np.pi / (2 * rise)
    assert v.max() / 10.0 == pytest.approx(estimate, rel=0.03)


def test_lowfreq_linearity_onset_with_paper_constants(paper_config):
    circuit = nominal_circuit(paper_config, 50e6)
    lf = lowfreq_sensitivity([1, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100], circuit, 0.05)
    assert lf.linear_from_Hz == 30.0
    wt = 2 * np.pi * 30 * circuit.tau_s
    assert lf.reference_sensitivity_V_per_N == pytest.approx(
        circuit.open_circuit_gain_V_per_N * wt / np.sqrt(1 + wt**2), rel=1e-12
    )
    f95 = asymptote_onset_Hz(circuit, 0.05)
    s95 = abs(calibration.frequency_response([f95], circuit)[0]) / circuit.open_circuit_gain_V_per_N
    assert s95 == pytest.approx(0.95, rel=1e-12)
