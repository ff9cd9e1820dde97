"""The joint dynamic search: the operating point and each defect type fitted together with the shaft's dynamics.

Hide and find on records of the dynamic LPM (``validation/bearing_feasibility.py``'s draws: light loads in wide
clearances, where the quasi-static chain cannot hold the record), and the search's own pieces on records of the
chain it fits (those prove only the search).
"""

import copy
import os

import numpy as np
import pytest

from piezobearing.diagnosis.bearing import joint
from piezobearing.diagnosis.bearing.effects import CATALOGUE
from piezobearing.diagnosis.bearing.floor import floor_prepass
from piezobearing.diagnosis.bearing.lpm_records import draw_conditions, lpm_record
from piezobearing.diagnosis.bearing.model import BearingModel
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.diagnosis.engine import diagnose
from piezobearing.diagnosis.settings import DiagnosticsSettings
from piezobearing.numerics.threads import single_blas_thread

#: The hide-and-find runs of the whole joint search: 2-4 CPU minutes each (the search costs 29-248 s on a 0.5 s record),
#: so they run with the docs' expensive commands, not in the default suite.
EXPENSIVE = pytest.mark.skipif(os.environ.get("PIEZOBEARING_EXPENSIVE") != "1",
                               reason="the whole joint search, minutes of CPU: PIEZOBEARING_EXPENSIVE=1")


@pytest.fixture(scope="module")
def setup(paper_config, paper_influence):
    c = copy.deepcopy(paper_config)
    c["diagnostics"]["max_steps"] = 1
    return c, paper_influence


def quasi_static(setup, draw: int, duration_s: float):
    """A feasibility draw's record (``duration_s`` at 2550 Hz, 30 dB) and its quasi-static first ranking."""
    c, influence = setup
    rig, hidden = draw_conditions(np.random.default_rng([26, draw]), copy.deepcopy(c))
    rec = lpm_record(rig, influence, hidden, 2550.0, duration_s, 30.0, draw)
    st = DiagnosticsSettings.from_config(c["diagnostics"])
    fits: dict = {}
    p = floor_prepass(SUBJECT.problem((rec, influence), rig), st, None, None, fits)
    return diagnose(p, st, None, fits.get("baseline"), intervals=False), st, hidden


def test_kinematics_gives_a_moving_defect_the_slip_the_healthy_fit_took_as_speed():
    """A healthy fit with the shaft 2 % slow: an inner groove and a roller's pit also start with the shaft at the
    rig file's speed and the cage 2 % slipping (the same cage speed); an outer groove, or a fit already with slip,
    keep the fit's own kinematics."""
    m = BearingModel((CATALOGUE["shaft_speed"], CATALOGUE["shaft_dynamics"]))
    vals = {"speed_deviation_ratio": -0.02}
    assert joint.kinematics("inner_race_defect", m, vals) == [
        {"cage_slip_ratio": 0.0}, {"speed_deviation_ratio": 0.0, "cage_slip_ratio": 0.02}]
    assert len(joint.kinematics("rolling_element_defect", m, vals)) == 2
    assert joint.kinematics("outer_race_defect", m, vals) == [{}]
    assert joint.kinematics("inner_race_defect", m.with_effect(CATALOGUE["cage_slip"]), vals) == [{}]
    assert joint.kinematics("inner_race_defect", m, {"speed_deviation_ratio": 0.01}) == [{}]


@pytest.mark.slow
@pytest.mark.expensive
@EXPENSIVE
def test_an_inner_groove_the_quasi_static_search_misses_is_found_with_the_dynamics(setup):
    """Draw 2 of validation/bearing_feasibility.py: a 0.99 mm inner groove at 3.06 rad, 310 N in 30 um with 2.4 %
    cage slip (the quasi-static chain leaves 3.1 sigma at the truth, the first ranking ends ``fault: none``). The
    joint search ranks the inner race first, accepted over the dynamic healthy model and identified, the groove
    within 0.01 rad of its angle and its width within 15 % (the fit ends with the load share at its bound, a load
    and share the record trades: the width's Jacobian interval does not hold the hidden width; the validation page
    says so), and the floor measured again on its residual below the floor the search started from."""
    d, st, hidden = quasi_static(setup, 2, 0.5)
    with single_blas_thread():
        fits, e = joint.joint_search(d, st)
    assert e["best"] == "inner_race_defect", e["ranked"]
    assert e["accepted"]
    t = (e["with_roller_scatter"] or e)["types"]["inner_race_defect"]
    angle = np.angle(np.exp(1j * (t["values"]["inner_defect_angle_rad"] - hidden["inner_defect_angle_rad"])))
    assert abs(angle) < 0.01
    assert t["values"]["inner_defect_width_m"] == pytest.approx(hidden["inner_defect_width_m"], rel=0.15)
    assert fits["floor"].voltage_noise_V < 0.8 * d.floor.voltage_noise_V


@pytest.mark.slow
@pytest.mark.expensive
@EXPENSIVE
def test_a_healthy_dynamic_record_far_off_its_rig_file_stays_healthy(setup):
    """Draw 1 of validation/bearing_feasibility.py: a healthy bearing at 739 N in 46 um with 1.5 % slip, the rig file
    at 698 N in 32 um (the quasi-static chain leaves 1.19 sigma at the truth). Without the rollers' scatter a
    roller's pit explains 19 % of the dynamic healthy model's misfit; with it the healthy model falls to the floor and
    no type passes the selection rule: the joint search accepts none and the answer stays ``none``."""
    d, st, _ = quasi_static(setup, 1, 0.5)
    with single_blas_thread():
        dj, e = joint.joint_rung(d, d.problem, st)
    assert not e["accepted"] and not e["replaced"], e["why"]
    assert e["with_roller_scatter"] is not None
    assert not any(t["passes_rule"] for t in e["with_roller_scatter"]["types"].values())
    assert SUBJECT.answer(dj)["fault"]["type"] == "none"
