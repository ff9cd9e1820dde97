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


# --------------------------------------------------------------------------- periodic steady-state start


def triangle(t, period, amp):
    """A triangle wave -amp -> amp -> -amp of period ``period`` [N] (piecewise linear, breaks at t = k T / 2)."""
    ph = (t % period) / period
    return np.where(ph < 0.5, -amp + 4 * amp * ph, 3 * amp - 4 * amp * ph)


def triangle_steady_state(t, period, amp):
    """The RC circuit's periodic steady state for :func:`triangle`, in closed form [V].

    On the rise tau V' + V = G tau s (s = 4 amp / T) relaxes towards G tau s, on the fall towards -G tau s;
    the state repeats (by symmetry V(T/2) = -V(0)) where V(0) = -G tau s tanh(T / (4 tau)).
    """
    s = 4 * amp / period
    v0 = -G * TAU * s * np.tanh(period / (4 * TAU))
    ph = t % period
    rise = G * TAU * s + (v0 - G * TAU * s) * np.exp(-ph / TAU)
    fall = -G * TAU * s + (-v0 + G * TAU * s) * np.exp(-(ph - period / 2) / TAU)
    return np.where(ph < period / 2, rise, fall)


def test_periodic_start_is_the_closed_form_steady_state_from_the_first_sample():
    """A triangle force (piecewise linear with its breaks on samples, so the discretisation is exact): started in
    its periodic steady state the voltage is the closed-form steady state from sample 0 on; started at rest it is
    off by the free decay of the whole swing at first and still by exp(-7.6) of it after 0.1 s (the old skip)."""
    dt, period, amp = 1e-4, 140 * 1e-4, 30.0
    t = np.arange(1200) * dt
    exact = triangle_steady_state(t, period, amp)
    scale = np.abs(exact).max()
    new = rc_voltage(triangle(t, period, amp), dt, G, TAU, period_s=period)
    np.testing.assert_allclose(new, exact, rtol=0, atol=1e-9 * scale)
    old = rc_voltage(triangle(t, period, amp), dt, G, TAU)
    assert np.abs(old - exact)[0] > 0.5 * scale  # at rest: V_0 = 0 against the steady state's V_0
    late = t >= 0.1
    np.testing.assert_allclose((old - exact)[late], -exact[0] * np.exp(-t[late] / TAU), rtol=1e-9)
    assert np.abs(old - exact)[late].max() > 1e-4 * scale


@pytest.mark.parametrize("n_period", [36.0, 144.57])
def test_periodic_start_for_a_sampled_sinusoid(n_period):
    """A sampled cosine: the discrete filter's steady state is A Re(H(z) z^k), H = rc_response (exact). With the
    period on the sample grid (36 steps, the paper's BPFO) the start is exact to rounding; off the grid (144.57
    steps, the 10240 Hz study's) the force between samples is the sinusoid's chord, not periodic, and the start is
    right to ~1e-7 of the swing (6e-8 measured: the chord's deviation from the cosine, weighted by the decay)."""
    from piezobearing.sensor.calibration import rc_response

    dt, amp = 1e-4, 20.0
    f0 = 1.0 / (n_period * dt)
    t = np.arange(1500) * dt
    exact = amp * np.real(rc_response(np.array([f0]), dt, G, TAU)[0] * np.exp(2j * np.pi * f0 * t))
    new = rc_voltage(amp * np.cos(2 * np.pi * f0 * t), dt, G, TAU, period_s=n_period * dt)
    tol = 1e-12 if n_period == round(n_period) else 2e-7
    np.testing.assert_allclose(new, exact, rtol=0, atol=tol * np.abs(exact).max())
    old = rc_voltage(amp * np.cos(2 * np.pi * f0 * t), dt, G, TAU)
    assert np.abs(old - exact).max() > 0.5 * np.abs(exact).max()


def test_periodic_start_keeps_the_state_not_the_voltage():
    """A force that does not repeat (a periodic part plus a step after the first period): the start is the periodic
    steady state of the first period alone (the step comes later), and a period longer than the record is refused."""
    dt, period, amp = 1e-4, 140 * 1e-4, 30.0
    t = np.arange(1200) * dt
    f = triangle(t, period, amp) + np.where(t > 1.5 * period, 5.0, 0.0)
    v = rc_voltage(f, dt, G, TAU, period_s=period)
    assert v[0] == pytest.approx(triangle_steady_state(0.0, period, amp), rel=1e-9)
    with pytest.raises(ValueError, match="period_s"):
        rc_voltage(f, dt, G, TAU, period_s=t.size * dt)
