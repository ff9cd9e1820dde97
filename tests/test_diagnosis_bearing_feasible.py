"""The running-bearing diagnosis never stops for want of an equilibrium.

Property tests: operating points and effect sizes drawn across their bounds (the surrogate's tables at every
draw meet their tolerance; records of the dynamic LPM drawn across the rig's plausible range are diagnosed to a
verdict), an infeasible point of the fit is a refused step, not an exception, and a config's defect without
``depth_m`` gets the paper's 1 mm. ``validation/bearing_feasibility.py`` runs the end-to-end draws at a larger
count (docs/validation/bearing_diagnosis.md).
"""

import copy

import numpy as np
import pytest

from piezobearing import config as cfg
from piezobearing.bearing import surrogate as sg
from piezobearing.bearing.geometry import BearingGeometry
from piezobearing.diagnosis.bearing.lpm_records import draw_conditions, lpm_record
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.fitting.least_squares import InfeasibleError, fit
from piezobearing.fitting.params import Param


@pytest.fixture(scope="module")
def geometry(paper_config):
    return BearingGeometry.from_config(paper_config["bearing"])


def test_tables_meet_their_tolerance_across_the_parameters_bounds(geometry):
    """40 draws of load (10 N-50 kN, log-uniform: the radial_load effect's bounds), clearance (-20..200 um: the
    clearance effect's), an outer groove in a third of them (0.1-1.2 mm at any angle) and roller scatter in a
    fifth (2 um): every table balances the load at every phase (the equilibrium's own check)."""
    a = np.linspace(0, 2 * np.pi, 361)
    s = sg.Surrogate(geometry, sg.InfluenceLine(a, np.cos(a).clip(0)), table_points=1024)
    rng = np.random.default_rng(7)
    for _ in range(40):
        load = float(np.exp(rng.uniform(np.log(10.0), np.log(5e4))))
        op = sg.Operating(load, float(rng.uniform(-20e-6, 200e-6)))
        groove = None
        if rng.uniform() < 0.3:
            groove = sg.OuterGroove(float(rng.uniform(-np.pi, np.pi)), float(rng.uniform(0.1e-3, 1.2e-3)), geometry)
        offsets = tuple(rng.normal(0.0, 2e-6, geometry.n_rollers)) if rng.uniform() < 0.2 else None
        t = s.table(op, groove, None if groove is None else groove.key, offsets)
        assert np.all(np.isfinite(t.force)), op
        base = s.table(op, None, None, offsets)
        psi = s.roller_angles(base.phase)
        gaps = 0.0 if offsets is None else np.asarray(offsets)[None, :]
        q = sg.quasi_static_loads(psi, gaps, load, 0.5 * op.radial_clearance_m, s.k_contact, 1e-12, e0_m=base.offset)
        assert np.all(np.abs(np.sum(q * np.cos(psi), 1) - load) <= 1e-9 * load), op


def test_an_infeasible_trial_point_is_a_refused_step():
    """A residual without a solution beyond x = 2 (InfeasibleError): the fit's trust region steps back and
    finds the constrained minimum's side, and a start without a solution goes to the caller."""

    def residual(v):
        if v["x_m"] > 2.0:
            raise InfeasibleError("no solution beyond 2")
        return np.array([v["x_m"] - 3.0, 0.1 * (v["x_m"] - 3.0)])

    res = fit(residual, [Param("x_m", 0.0, -10.0, 10.0)])
    assert 1.5 < res.values["x_m"] <= 2.0
    with pytest.raises(InfeasibleError):
        fit(residual, [Param("x_m", 2.5, -10.0, 10.0)])


def test_defect_without_depth_gets_the_papers_millimetre(tmp_path):
    p = tmp_path / "rig.yaml"
    p.write_text("bearing:\n  defects: [{type: outer_race, width_m: 0.9e-3, angle_deg: 0.0}]\n")
    c = cfg.load(p)
    assert c["bearing"]["defects"] == [{"type": "outer_race", "width_m": 0.9e-3, "angle_deg": 0.0, "depth_m": 1.0e-3}]


@pytest.fixture(scope="module")
def ci_setup(ci_config, ci_influence):
    c = copy.deepcopy(ci_config)
    c["diagnostics"]["max_steps"] = 1
    return c, ci_influence


@pytest.mark.slow
@pytest.mark.parametrize("draw", range(3))
def test_lpm_records_across_the_rigs_range_end_with_a_verdict(ci_setup, draw):
    """Three draws of :func:`~piezobearing.diagnosis.bearing.lpm_records.draw_conditions` (load 100-2000 N, clearance to
    60 um, a groove to 1.2 mm at any angle, slip to 3 %, speed +-3 %, roller scatter to 2 um), 0.5 s records of
    the dynamic LPM at 2550 Hz: the diagnosis ends with a verdict."""
    c, influence = ci_setup
    rig, hidden = draw_conditions(np.random.default_rng([26, draw]), c)
    rec = lpm_record(rig, influence, hidden, 2550.0, 0.5, 30.0, draw)
    d = SUBJECT.diagnose((rec, influence), rig)[1]
    assert d["verdict"] in ("explained", "unexplained"), d["verdict"]
