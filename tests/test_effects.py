"""The effect catalogue and the forward model: registration, closed forms, consistency of response and simulation."""

from __future__ import annotations

import numpy as np
import pytest

from piezobearing.diagnosis.calibration.effects import (
    CATALOGUE,
    EffectError,
    ForceRecord,
    register,
    resolve,
    unregister,
)
from piezobearing.diagnosis.calibration.effects.base import Effect, force_band_Hz
from piezobearing.diagnosis.calibration.effects.channel_delay import fractional_delay
from piezobearing.diagnosis.calibration.effects.reference_lag import lead
from piezobearing.diagnosis.calibration.model import ForwardModel, model_from_specs
from piezobearing.diagnosis.calibration.presses import PressProtocol, press_force, synthesize
from piezobearing.fitting.units import SUFFIXES
from piezobearing.sensor.calibration import SensorCircuit, circuit_voltage, rc_response

REQUIRED = {
    "channel_delay",
    "ac_coupling",
    "reference_lag",
    "d33_nonlinearity",
    "mains_pickup",
    "baseline_drift",
    "extra_capacitance",
}
#: A non-neutral value of every effect (those of the recovery tests in test_diagnostics.py).
ON = {
    "channel_delay": {"delay_s": 0.015},
    "ac_coupling": {"corner_Hz": 0.5},
    "reference_lag": {"lag_tau_s": 0.010},
    "d33_nonlinearity": {"beta_per_N": 1.5e-3},
    "mains_pickup": {"mains_frequency_Hz": 50.03, "mains_h1_cos_V": 0.012, "mains_h1_sin_V": -0.016},
    "baseline_drift": {"drift_p1_V": 0.02},
    "extra_capacitance": {"extra_capacitance_F": 100e-12},
}


@pytest.fixture(scope="module")
def record(paper_config) -> ForceRecord:
    p = PressProtocol.from_config(paper_config["synthesis"])
    t, f = press_force(p, np.random.default_rng(1))
    return ForceRecord(t, f + np.random.default_rng(2).normal(0, p.force_noise_N, t.size))


@pytest.fixture(scope="module")
def circuit() -> SensorCircuit:
    return SensorCircuit()


def test_catalogue_has_the_issue_identifiers_each_documented():
    assert REQUIRED <= set(CATALOGUE)
    for name, e in CATALOGUE.items():
        assert e.name == name
        assert e.title and len(e.physics) > 80, name
        assert type(e).__module__.startswith("piezobearing.diagnosis.calibration.effects."), name


def test_every_parameter_has_a_unit_suffix_bounds_and_a_neutral_default(record):
    names = []
    for e in CATALOGUE.values():
        for p in e.params(record):
            names.append(p.name)
            assert p.name.endswith(SUFFIXES), p.name
            assert p.lower < p.upper and p.lower <= p.default <= p.upper, p.name
            assert not p.log or p.lower > 0, p.name
            assert p.description, p.name
    assert len(names) == len(set(names)), "parameter names must be unique across the catalogue"


def test_unknown_or_repeated_effect_is_a_one_line_error_naming_the_key():
    with pytest.raises(EffectError, match=r"model\.effects\[1\]: unknown effect 'ringing'.*catalogue has"):
        resolve(["channel_delay", "ringing"])
    with pytest.raises(EffectError, match=r"listed twice"):
        resolve(["mains_pickup", "mains_pickup"])


def test_unknown_or_out_of_range_hidden_parameter_names_the_key(record, circuit):
    with pytest.raises(
        EffectError, match=r"synthesis\.hidden_effects\[0\]\.params\.delay_ms: unknown parameter"
    ):
        model_from_specs(circuit, [{"name": "channel_delay", "params": {"delay_ms": 15}}], record)
    with pytest.raises(EffectError, match=r"outside"):
        model_from_specs(circuit, [{"name": "channel_delay", "params": {"delay_s": 5.0}}], record)


def test_adding_an_effect_is_one_registration(record, circuit):
    class Gain(Effect):
        name = "test_gain"
        title = "a gain"
        physics = "test"

        def params(self, record):
            from piezobearing.fitting.params import Param

            return [Param("test_gain_factor_V", 1.0, 0.5, 2.0)]

        def voltage(self, v, values, record):
            return v * values["test_gain_factor_V"]

    register(Gain())
    try:
        m = ForwardModel.build(circuit, ["test_gain"])
        vals = {**m.defaults(record), "test_gain_factor_V": 1.5}
        base = ForwardModel(circuit).simulate(vals, record)
        np.testing.assert_allclose(m.simulate(vals, record), 1.5 * base, rtol=1e-12)
    finally:
        unregister("test_gain")
    assert "test_gain" not in CATALOGUE


def test_neutral_defaults_reproduce_the_baseline(record, circuit):
    """Every effect at its default is (nearly) switched off: within 1e-4 of the signal's rms."""
    base = ForwardModel(circuit)
    vb = base.simulate(base.defaults(record), record)
    for name in CATALOGUE:
        m = ForwardModel.build(circuit, [name])
        v = m.simulate(m.defaults(record), record)
        assert np.sqrt(np.mean((v - vb) ** 2)) < 1e-4 * np.sqrt(np.mean(vb**2)), name


def test_baseline_model_is_the_calibration_circuit(record, circuit):
    """The baseline is calibration.circuit_voltage (Eq. 6); it starts at rest at the median of the first 10 ms
    instead of the first noisy sample, which only changes a transient decaying with tau = RC."""
    m = ForwardModel(circuit)
    v = m.simulate(m.defaults(record), record)
    ref = circuit_voltage(record.force_N, record.dt_s, circuit)
    first = record.force_N[0] - np.median(record.force_N[:10])
    decay = circuit.open_circuit_gain_V_per_N * abs(first) * np.exp(-record.time_s / circuit.tau_s)
    assert np.all(np.abs(v - ref) <= 1.01 * decay + 1e-12)


def test_rc_response_is_the_exact_discrete_filter_and_tends_to_eq6():
    dt, tau, g = 1e-3, 13e-3, 1.53
    n = 4096
    x = np.zeros(n)
    x[5] = 1.0  # a unit force sample (piecewise linear: a triangle) after rest
    from piezobearing.sensor.calibration import rc_voltage

    h = rc_voltage(x, dt, g, tau)
    f = np.fft.rfftfreq(n, dt)
    got = np.fft.rfft(h) * np.exp(2j * np.pi * f * dt * 5)
    np.testing.assert_allclose(got, rc_response(f, dt, g, tau), atol=1e-9)
    low = f < 5
    jwt = 2j * np.pi * f[low] * tau
    np.testing.assert_allclose(rc_response(f[low], dt, g, tau), g * jwt / (1 + jwt), rtol=0.02)


@pytest.mark.parametrize("name", ["channel_delay", "ac_coupling", "reference_lag", "extra_capacitance"])
def test_response_is_the_fft_of_the_simulated_impulse_response(name, record, circuit):
    """For the linear effects, model.response (used for the noise floor) equals the simulation's transfer."""
    m = ForwardModel.build(circuit, [name])
    vals = {**m.defaults(record), **ON[name]}
    n = record.n
    imp = np.zeros(n)
    imp[n // 2] = 1.0
    h = m.simulate(vals, record, imp)
    f = record.freq_Hz
    got = np.fft.rfft(h) * np.exp(2j * np.pi * f * record.dt_s * (n // 2))
    want = m.response(vals, record)
    err = np.abs(got - want)[f < 0.4 * record.sample_rate_Hz]
    assert err.max() < 2e-3 * np.abs(want).max(), (name, err.max())


def test_fractional_delay_shifts_a_band_limited_signal():
    t = np.arange(2000) * 1e-3
    x = np.sin(2 * np.pi * 3.0 * t) * np.exp(-(((t - 1.0) / 0.2) ** 2))
    d = 12.4  # samples
    y = fractional_delay(x, d)
    ts = t - d * 1e-3
    want = np.sin(2 * np.pi * 3.0 * ts) * np.exp(-(((ts - 1.0) / 0.2) ** 2))
    np.testing.assert_allclose(y, want, atol=1e-6)
    np.testing.assert_allclose(fractional_delay(x, 5.0)[5:], x[:-5], atol=1e-10)


def test_reference_lag_undoes_a_first_order_lag_within_the_force_band(record):
    """A smooth force through the exact lag tau dy/dt + y = F, then the model's lead, returns F."""
    from scipy.signal import lfilter

    p = PressProtocol(25.0, 1000.0, 13, (5.0, 15.0), (0.36, 0.5), (0.4, 0.6), 0.15, 0.005, 0.002)
    t, f = press_force(p, np.random.default_rng(3))
    dt, a = 1e-3, np.exp(-0.1)
    lagged = lfilter([1 - a], [1, -a], f)  # y_k = a y_k-1 + (1 - a) F_k: a lag of tau = a dt / (1 - a)
    tau = a * dt / (1 - a)  # 9.5 ms
    rec = ForceRecord(t, lagged + np.random.default_rng(4).normal(0, 0.005, t.size))
    fs = rec.sample_rate_Hz
    from piezobearing.diagnosis.calibration.effects.base import fd_filter

    led = fd_filter(lagged, lambda k: lead(k * fs, tau, force_band_Hz(rec)), 400)
    assert np.sqrt(np.mean((led - f) ** 2)) < 1e-3 * np.sqrt(np.mean(f**2))
    assert 3.0 < force_band_Hz(rec) < 40.0


def test_extra_capacitance_changes_gain_and_time_constant(circuit):
    m = ForwardModel.build(circuit, ["extra_capacitance"])
    c = m.fitted_circuit({"resistance_ohm": 50e6, "extra_capacitance_F": 100e-12})
    c0 = circuit.capacitance_F
    assert c.open_circuit_gain_V_per_N == pytest.approx(circuit.d33_C_per_N / (c0 + 100e-12), rel=1e-12)
    assert c.tau_s == pytest.approx(50e6 * (c0 + 100e-12), rel=1e-12)


def test_d33_nonlinearity_scales_the_charge_as_f_plus_beta_f2(record, circuit):
    """With R large (open circuit) the voltage follows d33 (F + beta F^2) / C."""
    m = ForwardModel.build(circuit, ["d33_nonlinearity"])
    t = np.arange(2000) * 1e-3
    f = 10.0 * 0.5 * (1 - np.cos(np.pi * np.clip(t, 0, 1)))
    rec = ForceRecord(t, f)
    v = m.simulate({"resistance_ohm": 1e16, "beta_per_N": 2e-3}, rec)  # tau = 2.6e6 s: open circuit
    g = circuit.open_circuit_gain_V_per_N
    np.testing.assert_allclose(v[-1], g * (10 + 2e-3 * 100), rtol=1e-4)


def test_additive_effects_closed_forms(record, circuit):
    m = ForwardModel.build(circuit, ["mains_pickup", "baseline_drift"])
    vals = {**m.defaults(record), **ON["mains_pickup"], "drift_p0_V": 0.003, "drift_p1_V": 0.02}
    zero = ForceRecord(record.time_s, np.zeros(record.n))
    v = m.simulate(vals, zero)
    t = record.time_s
    x = 2 * t / t[-1] - 1
    want = 0.012 * np.cos(2 * np.pi * 50.03 * t) - 0.016 * np.sin(2 * np.pi * 50.03 * t) + 0.003 + 0.02 * x
    np.testing.assert_allclose(v, want, atol=1e-12)


def test_mains_harmonics_above_nyquist_are_left_out():
    slow = ForceRecord(np.arange(1000) / 500.0, np.zeros(1000))
    names = [p.name for p in CATALOGUE["mains_pickup"].params(slow)]
    assert "mains_h3_cos_V" in names and "mains_h5_cos_V" not in names


def test_synthesis_puts_the_forward_model_into_the_voltage(paper_config, circuit):
    """Hidden effects: the synthetic voltage is exactly the forward model driven by the true force."""
    c = paper_config
    p = PressProtocol.from_config(c["synthesis"])
    specs = [
        {"name": "channel_delay", "params": {"delay_s": 0.015}},
        {"name": "baseline_drift", "params": {}},
    ]
    noiseless = PressProtocol(**{**p.__dict__, "force_noise_N": 0.0, "voltage_noise_V": 0.0})
    m = synthesize(noiseless, circuit, 5, specs)
    rec = ForceRecord(m.time_s, m.force_N)
    model, vals = model_from_specs(circuit, specs, rec)
    np.testing.assert_allclose(m.voltage_V, model.simulate(vals, rec), atol=1e-12)
    plain = synthesize(noiseless, circuit, 5)
    assert np.sqrt(np.mean((m.voltage_V - plain.voltage_V) ** 2)) > 0.01  # the delay is in there
    with pytest.raises(EffectError, match=r"synthesis\.hidden_effects\[0\]: unknown effect"):
        synthesize(noiseless, circuit, 5, [{"name": "ringing"}])


def test_channel_delay_summary_names_the_direction():
    """A negative fitted delay means the voltage comes before the force; the summary must not say 'after'."""
    from piezobearing.diagnosis.calibration.effects.channel_delay import EFFECT

    assert EFFECT.summary({"delay_s": 0.015}) == "delay = 15.00 ms (voltage after force)"
    assert EFFECT.summary({"delay_s": -0.008}) == "delay = -8.00 ms (voltage before force)"


def test_a_parameter_needs_a_registered_unit_suffix_and_reports_in_its_unit():
    from piezobearing.fitting.params import Param, ParamError
    from piezobearing.fitting.units import format_value

    with pytest.raises(ParamError, match=r"parameter 'gain'.*unit suffix"):
        Param("gain", 1.0)
    with pytest.raises(ParamError, match="lower > 0"):
        Param("corner_Hz", 1.0, 0.0, 10.0, log=True)
    p = Param("delay_s", 0.0, -0.1, 0.1, scale=1e-3)
    assert p.with_value(0.5).value == 0.1  # a start outside the bounds is clipped into them
    assert format_value("delay_s", 0.015) == "15 ms"
    assert format_value("resistance_ohm", 5.0e7) == "50 MOhm"
    assert format_value("beta_per_N", 0.01) == "0.01 1/N"


def test_noise_envelope_is_the_product_of_the_effects_gains_on_the_force_noise(record, circuit):
    """d33_nonlinearity carries the force noise with 1 + 2 beta F(t), sensitivity_drift with g(t): together their
    product; linear, time-invariant effects (a delay, mains) have none, and a neutral value switches it off."""
    from piezobearing.diagnosis.calibration.effects.base import denoised_force
    from piezobearing.diagnosis.calibration.effects.sensitivity_drift import gain

    lti, v = model_from_specs(
        circuit, [{"name": "channel_delay", "params": ON["channel_delay"]}, {"name": "mains_pickup"}], record
    )
    assert lti.noise_envelope(v, record) is None
    specs = [
        {"name": "d33_nonlinearity", "params": {"beta_per_N": 5e-3}},
        {"name": "sensitivity_drift", "params": {"sensitivity_slope_per_s": 2e-3}},
    ]
    m, v = model_from_specs(circuit, specs, record)
    a = m.noise_envelope(v, record)
    expect = (1 + 2 * 5e-3 * denoised_force(record)) * gain(v, record, record.n)
    assert a.shape == (record.n,) and np.allclose(a, expect)
    assert a[np.argmax(denoised_force(record))] > 1.05  # louder at the largest press
    off, v0 = model_from_specs(circuit, [{"name": "d33_nonlinearity"}], record)
    assert off.noise_envelope(v0, record) is None
