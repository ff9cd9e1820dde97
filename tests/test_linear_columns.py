"""The fit's exact Jacobian columns of parameters the voltage is linear in (a drift's spline, the mains
amplitudes): the same as scipy's 2-point differences to their rounding, the other columns scipy's own."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize._numdiff import approx_derivative

from piezobearing.diagnosis.calibration.effects import CATALOGUE, ForceRecord
from piezobearing.diagnosis.calibration.effects.baseline_drift import BaselineDrift
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.diagnosis.calibration.subject import calibration_problem
from piezobearing.diagnosis.fit import likelihood_residual
from piezobearing.diagnosis.settings import DiagnosticsSettings
from piezobearing.fitting.least_squares import _fun_and_jacobian
from piezobearing.sensor.calibration import detect_impulses
from piezobearing.stages.calibration import nominal_circuit

START = {"mains_frequency_Hz": 50.02, "mains_h1_cos_V": 0.01, "drift_p1_V": 0.003, "drift_kink_s": 5.0,
         "drift_k1_V": 0.01}


@pytest.mark.parametrize("effect", [CATALOGUE["mains_pickup"], BaselineDrift(2), BaselineDrift(1, kink=True)],
                         ids=["mains_pickup", "drift_2_knots", "drift_kink"])
def test_linear_columns_are_the_finite_differences_without_their_rounding(ci_config, effect):
    c = ci_config
    m = synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"],
                   [{"name": "mains_pickup", "params": dict(CATALOGUE["mains_pickup"].example)}])
    rec, v = ForceRecord(m.time_s, m.force_N), m.voltage_V
    st = DiagnosticsSettings.from_config(c["diagnostics"])
    imps = detect_impulses(m.force_N, v, rec.dt_s, 0.2, 0.8)
    p = calibration_problem(rec, v, nominal_circuit(c, c["calibration"]["initial_resistance_ohm"]), [], st, imps)
    model = p.baseline.with_effect(effect)
    fn = likelihood_residual(model, rec, v, p.floor)
    free = [q for q in model.params(rec, START) if q.vary]

    def unpack(u):
        return {q.name: q.to_physical(x) for q, x in zip(free, u, strict=True)}

    lo = np.array([q.to_internal(q.lower) for q in free])
    hi = np.array([q.to_internal(q.upper) for q in free])
    u0 = np.array([q.to_internal(q.value) for q in free])
    fun, jac = _fun_and_jacobian(fn, free, unpack, lo, hi)
    exact = jac(u0)
    fd = approx_derivative(fun, u0, method="2-point", f0=fun(u0), bounds=(lo, hi))
    linear = {n for names, _, _ in model.linear_basis(START, rec) for n in names}
    assert linear and linear < {q.name for q in free}
    for i, q in enumerate(free):
        if q.name in linear:  # measured: within 1.4e-5 of the largest entry (the differences' rounding)
            assert np.max(np.abs(exact[:, i] - fd[:, i])) < 1e-4 * np.max(np.abs(fd[:, i])), q.name
        else:
            assert np.array_equal(exact[:, i], fd[:, i]), q.name
