"""The running bearing's dynamic rung (``shaft_dynamics``) and the diagnosis's safety rules.

- the shaft on its rollers rings at sqrt(k / m) / 2 pi and decays at zeta = c / (2 sqrt(k m)) after a small step
  of one roller's gap (the closed form of a single-DOF oscillator, k the rollers' tangent stiffness);
- the rung's box-averaged sensor force against the LPM integrated at a 4x finer step, where the quasi-static
  chain is far off (a groove 20 deg from the sensor);
- with the shaft's mass 0 the chain is the quasi-static one;
- a groove 20 deg from the sensor hidden with the shaft's dynamics is found at its angle, the rung accepted;
- without the rung, the same record names the outer race from its lines instead of "no fault";
- a defect whose width interval holds zero, or whose angle interval spans the circle, is not identified.
"""

import copy
from types import SimpleNamespace

import numpy as np
import pytest

from piezobearing.bearing.geometry import BearingGeometry
from piezobearing.bearing.shaft_dynamics import ShaftDynamics, contact_stiffness_N_per_m, sensor_force
from piezobearing.diagnosis.bearing import chain, lpm_records
from piezobearing.diagnosis.bearing.rung import unidentified_defects
from piezobearing.diagnosis.bearing.subject import SUBJECT, rig_from_config, synthesise
from piezobearing.stages.bearing_diagnosis import influence_from_config

GROOVE_20DEG = {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35}


@pytest.fixture(scope="module")
def setup(ci_config):
    c = copy.deepcopy(ci_config)
    c["bearing_diagnosis"].update(synthetic_duration_s=0.5, synthetic_sample_rate_Hz=2550.0)
    return c, influence_from_config(c)


def test_shaft_rings_at_its_closed_form_frequency_and_decay(ci_config):
    """A roller at the bottom (the stiffness along the load decoupled), a rigid pedestal: after one roller's gap
    grows by 1 nm the sensor force (g = cos psi: the rollers' vertical resultant) rings at sqrt(k/m)/2 pi and
    its peaks decay by exp(-zeta omega t)."""
    b = ci_config["bearing"]
    geo = BearingGeometry.from_config(b)
    z, load, gap = geo.n_rollers, 500.0, 0.5 * geo.radial_clearance_m
    psi0 = 2 * np.pi / z * np.arange(z)
    k = contact_stiffness_N_per_m(load, psi0, gap, geo.roller_length_m)
    m, c = 1.0, 300.0
    dyn = ShaftDynamics(m, c, 1.0, 1e14, 0.0)
    f_n, zeta = np.sqrt(k / m) / (2 * np.pi), c / (2 * np.sqrt(k * m))
    h = 1.0 / (200 * f_n)
    n = int(40 / f_n / h)
    extra = np.zeros((n, z))
    extra[n // 10:, 0] = 1e-9
    force = sensor_force(np.tile(psi0, (n, 1)), extra, load, geo.radial_clearance_m, geo.roller_length_m,
                         np.cos, dyn, h)
    x = force[n // 10 + 1:] - load  # with g = cos psi the static sensor force is the load
    t = h * np.arange(x.size)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    crossings = t[up] - x[up] * h / (x[up + 1] - x[up])
    np.testing.assert_allclose(1.0 / np.mean(np.diff(crossings)), f_n * np.sqrt(1 - zeta**2), rtol=2e-3)
    peaks = [np.max(np.abs(x[(t >= a) & (t < a + 1 / f_n)])) for a in (2 / f_n, 12 / f_n)]
    np.testing.assert_allclose(np.log(peaks[0] / peaks[1]) / (10 / f_n), zeta * 2 * np.pi * f_n, rtol=0.05)


def _forces(c, influence, hidden, mass):
    fs = 2550.0
    t = np.arange(int(0.25 * fs)) / fs
    rig = rig_from_config(c, influence, t)
    values = {"start_phase_rad": np.radians(c["bearing_diagnosis"]["synthetic_start_phase_deg"]),
              "shaft_speed_Hz": c["bearing"]["shaft_speed_rpm"] / 60.0, **hidden}
    if mass is not None:
        values["shaft_mass_kg"] = mass
    return rig, t, chain.sensor_force(rig, values)[0][rig.n_pre:]


def test_rung_follows_the_lpm_where_the_quasi_static_chain_does_not(setup, monkeypatch):
    """The box-averaged sensor force of the rung within 1.5 % (rms) of the LPM at a 4x finer step than its
    records' (a groove 20 deg from the sensor, where the quasi-static chain is over 5 % off); measured 0.67 % and
    10 % on the paper's mesh (benchmarks/bench_shaft_dynamics.py)."""
    c, influence = setup
    monkeypatch.setattr(lpm_records, "MAX_STEP_S", lpm_records.MAX_STEP_S / 4)
    rig, t, qs = _forces(c, influence, GROOVE_20DEG, None)
    dyn = _forces(c, influence, GROOVE_20DEG, c["bearing"]["shaft_mass_kg"])[2]
    ref = lpm_records.lpm_sensor_force(c, influence, GROOVE_20DEG, t)
    ref = ref - ref.mean()

    def err(f):
        return np.sqrt(np.mean((f - f.mean() - ref) ** 2) / np.mean(ref**2))

    assert err(dyn) < 0.015, err(dyn)
    assert err(qs) > 0.05, err(qs)


def test_zero_shaft_mass_is_the_quasi_static_chain(setup):
    c, influence = setup
    a = _forces(c, influence, GROOVE_20DEG, None)[2]
    b = _forces(c, influence, GROOVE_20DEG, 0.0)[2]
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=0)


def _record(c, influence, seed=11):
    hidden = [{"name": "outer_race_defect", "params": GROOVE_20DEG},
              {"name": "shaft_dynamics", "params": {"shaft_mass_kg": 1.0, "bearing_damping_N_s_per_m": 1.5e3}}]
    return synthesise(c, seed, hidden, influence)


def test_groove_20deg_with_the_shafts_dynamics_is_found_at_its_angle(setup):
    """Hide and find: the quasi-static search leaves it unexplained; the rung places and sizes it."""
    c, influence = setup
    d = SUBJECT.diagnose((_record(c, influence), influence), copy.deepcopy(c))[1]
    r = d["dynamic_rung"]
    assert r["tried"] and r["accepted"], r
    assert d["selected"][-1] == "shaft_dynamics" and "outer_race_defect" in d["selected"]
    assert d["verdict"] == "explained", d["unexplained"]
    f = d["fault"]
    assert f["type"] == "outer_race" and f["source"] == "model"
    assert abs(f["params"]["outer_defect_angle_rad"] - 0.35) < 0.05
    lo, hi = f["ci95"]["outer_defect_width_m"]
    assert lo <= 0.6e-3 <= hi and hi - lo < 0.06e-3
    base, quasi_static, dynamic, floor = (row["nrmse"] for row in r["ladder"])
    assert base >= quasi_static > dynamic and dynamic < 1.1 * floor
    assert d["final"]["params"]["shaft_mass_kg"] == 1.0  # held: the mode is above the record's Nyquist
    for key in ("baseline", "configured", "ranking", "selected", "steps", "final", "verdict", "unexplained",
                "identifiability", "model_rate", "noise_floor"):
        assert key in d


def test_without_the_rung_the_fault_is_named_from_its_lines(setup):
    """``dynamic_rung: off``: the quasi-static search selects no defect for the 20 deg groove, and the answer is the
    outer race named from its lines, never 'none'."""
    c, influence = setup
    c = copy.deepcopy(c)
    c["bearing_diagnosis"]["dynamic_rung"] = "off"
    d = SUBJECT.diagnose((_record(c, influence), influence), c)[1]
    assert not d["dynamic_rung"]["tried"]
    f = d["fault"]
    if "outer_race_defect" in d["selected"]:
        pytest.skip(f"the quasi-static search selected a groove here: {f['statement']}")
    assert f["type"] == "outer_race" and f["source"] == "lines", f
    assert "shaft_dynamics" in f["statement"]


def _diag(selected, ci95):
    return SimpleNamespace(selected=selected, final=SimpleNamespace(result=SimpleNamespace(ci95=ci95)))


def test_a_defect_the_record_cannot_pin_down_is_not_identified():
    ok = {"outer_defect_width_m": [0.5e-3, 0.7e-3], "outer_defect_angle_rad": [0.1, 0.2],
          "radial_clearance_m": [30e-6, 200e-6]}
    assert unidentified_defects(_diag(["outer_race_defect", "clearance"], ok)) == []
    zero = {**ok, "outer_defect_width_m": [-5.3e-3, 6.2e-3]}
    assert unidentified_defects(_diag(["outer_race_defect"], zero))[0]["reason"].endswith("holds zero")
    circle = {**ok, "outer_defect_angle_rad": [-17.0, 17.0]}
    assert unidentified_defects(_diag(["outer_race_defect"], circle))[0]["reason"].endswith("spans the circle")
    missing = {"inner_defect_width_m": None, "inner_defect_angle_rad": [0.1, 0.2]}
    assert unidentified_defects(_diag(["inner_race_defect"], missing))[0]["effect"] == "inner_race_defect"
