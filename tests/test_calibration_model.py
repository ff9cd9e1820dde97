"""Closed-form checks of the RC model of Eq. 5-6 and its exact discretisation."""

import numpy as np
import pytest

from piezobearing.sensor.calibration import SensorCircuit, circuit_voltage, frequency_response, rc_voltage

G, TAU = 1.5, 0.013  # gain [V/N], time constant [s]


def test_ramp_response_is_exact_at_samples():
    # F = s t  =>  V(t) = G s tau (1 - exp(-t/tau)), exact for piecewise-linear force.
    dt, s = 1e-3, 20.0
    t = np.arange(500) * dt
    v = rc_voltage(s * t, dt, G, TAU)
    np.testing.assert_allclose(v, G * s * TAU * (1 - np.exp(-t / TAU)), rtol=1e-12, atol=1e-15)


def test_ramp_response_does_not_depend_on_step():
    # Exactness means a coarse clock gives the same values at shared times.
    s = 10.0
    fine = rc_voltage(s * np.arange(1001) * 1e-4, 1e-4, G, TAU)
    coarse = rc_voltage(s * np.arange(101) * 1e-3, 1e-3, G, TAU)
    np.testing.assert_allclose(coarse, fine[::10], rtol=1e-12)


def test_step_response_decays_with_tau():
    # A unit step reached over one sample (a ramp of one step), then held:
    # V(h) = G tau/h (1 - e^{-h/tau}), then V decays as e^{-(t-h)/tau}.
    dt = 1e-4
    f = np.ones(2000)
    f[0] = 0.0
    v = rc_voltage(f, dt, G, TAU)
    t = np.arange(f.size) * dt
    v1 = G * TAU / dt * (1 - np.exp(-dt / TAU))
    np.testing.assert_allclose(v[1:], v1 * np.exp(-(t[1:] - dt) / TAU), rtol=1e-10)
    assert v1 == pytest.approx(G, rel=dt / TAU)  # a fast step reaches the open-circuit gain


@pytest.mark.parametrize("freq", [1.0, 12.2, 30.0, 100.0])
def test_sinusoidal_steady_state_gain(freq):
    # |V/F| = G omega tau / sqrt(1 + (omega tau)^2) once the transient has decayed.
    dt = 1e-5
    t = np.arange(int(round((40 * TAU + 3 / freq) / dt))) * dt
    v = rc_voltage(np.sin(2 * np.pi * freq * t), dt, G, TAU)
    tail = t > t[-1] - 2 / freq
    wt = 2 * np.pi * freq * TAU
    expected = G * wt / np.sqrt(1 + wt**2)
    assert np.abs(v[tail]).max() == pytest.approx(expected, rel=2e-4)
    circuit = SensorCircuit(resistance_ohm=TAU / SensorCircuit().capacitance_F)
    assert abs(frequency_response([freq], circuit)[0]) == pytest.approx(
        circuit.open_circuit_gain_V_per_N * wt / np.sqrt(1 + wt**2), rel=1e-12
    )


def test_paper_constants():
    c = SensorCircuit()
    # Cp = 1800 eps0 pi (2.35 mm)^2 / 3.4 mm = 81.33 pF; Eq. 3 gain h d33/(eps A) = d33/Cp
    assert c.pzt_capacitance_F == pytest.approx(81.33e-12, rel=1e-3)
    assert c.cable_capacitance_F == pytest.approx(180e-12)
    assert c.tau_s == pytest.approx(50e6 * 261.33e-12, rel=1e-3)
    assert c.free_disk_gain_V_per_N == pytest.approx(400e-12 / 81.33e-12, rel=1e-3)
    # open circuit (R -> infinity): the voltage follows the force, V = (d33/C) F
    big = c.with_resistance(1e15)
    f = np.sin(np.linspace(0, 3, 300)) ** 2
    leak = c.open_circuit_gain_V_per_N * f.max() * 0.3 / big.tau_s  # discharge over the 0.3 s record
    np.testing.assert_allclose(circuit_voltage(f, 1e-3, big), c.open_circuit_gain_V_per_N * f, atol=leak)
