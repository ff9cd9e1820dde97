"""Fault types, slip, speed profile and roller scatter of the bearing model, against closed forms."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest
from scipy.special import gamma

from piezobearing import config
from piezobearing.bearing import lpm as bearing_lpm
from piezobearing.bearing.geometry import kinematic_frequencies


@pytest.fixture(scope="module")
def bcfg(paper_config):
    return paper_config["bearing"]


@pytest.fixture(scope="module")
def base(bcfg):
    return bearing_lpm.LPMParameters.from_config(bcfg, False, seed=7)


def _episodes(active: np.ndarray) -> np.ndarray:
    """Start indices of the runs where ``active`` is True."""
    a = np.r_[False, active]
    return np.flatnonzero(a[1:] & ~a[:-1])


# --- kinematics with slip ------------------------------------------------------


def test_kinematic_frequencies_with_slip(base):
    g, s = base.geometry, 0.015
    fr = 1000 / 60
    k0, ks = kinematic_frequencies(g, fr), kinematic_frequencies(g, fr, s)
    ratio = g.roller_diameter_m / g.pitch_diameter_m
    assert ks.ftf_Hz == pytest.approx((1 - s) * 0.5 * fr * (1 - ratio), rel=1e-14)
    assert ks.bpfo_Hz == pytest.approx(11 * ks.ftf_Hz, rel=1e-14)
    assert ks.bpfo_Hz == pytest.approx(0.985 * 70.833, rel=1e-4)  # 69.77 Hz: 1.06 Hz off the kinematic line
    assert ks.bpfi_Hz == pytest.approx(11 * (fr - ks.ftf_Hz), rel=1e-14)
    assert ks.bpfi_Hz > k0.bpfi_Hz  # the inner ring overtakes a slower cage more often
    assert ks.bsf_Hz == pytest.approx((1 - s) * k0.bsf_Hz, rel=1e-14)
    assert ks.shaft_Hz == k0.shaft_Hz


def test_cage_slip_and_jitter_in_the_motion(base):
    """The simulated cage turns at the slipped FTF on average; the per-passage jitter spreads the passages."""
    p = replace(base, cage_slip=0.015, slip_jitter=0.005)
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz, p.cage_slip)
    t = np.linspace(0.0, 10.0, 200001)
    phi = p.cage_angle(t)
    # mean speed over ~700 passages: within a few sigma/sqrt(n) of the slipped cage
    assert phi[-1] / t[-1] == pytest.approx(2 * np.pi * kin.ftf_Hz, rel=1e-3)
    # passage durations: pitch / ((1 - s_k) omega_0); their spread is the jitter's
    pitch = p.geometry.roller_pitch_rad
    tk = np.interp(pitch * np.arange(1, int(phi[-1] / pitch)), phi, t)
    dur = np.diff(tk)
    assert dur.mean() == pytest.approx(1 / kin.bpfo_Hz, rel=2e-3)
    assert dur.std() / dur.mean() == pytest.approx(0.005 / 0.985, rel=0.15)
    # a passage's slip does not depend on the time grid, only on the seed
    np.testing.assert_allclose(p.cage_angle(t[::7][100:200]), phi[::7][100:200], rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.cage_angle(np.array([-0.3, 0.0, 0.5])), p.cage_angle(np.array([-0.3, 0.0, 0.5])))
    other = replace(p, seed=8).cage_angle(t)
    assert np.abs(other - phi).max() > 0.01 * pitch
    assert p.cage_angle(np.array([0.0]))[0] == 0.0
    # without jitter the cage simply lags
    q = replace(base, cage_slip=0.015)
    np.testing.assert_allclose(q.cage_angle(t), 2 * np.pi * kin.ftf_Hz * t, rtol=1e-12)


def test_speed_ramp_and_tachometer(base):
    p = replace(base, speed_ramp_Hz_per_s=10.0)  # 16.7 -> 26.7 Hz over 1 s
    t = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(p.shaft_speed_at(t), 1000 / 60 + 10 * t)
    np.testing.assert_allclose(np.gradient(p.shaft_angle(t), t)[1:-1], 2 * np.pi * p.shaft_speed_at(t)[1:-1], rtol=1e-9)
    # the cage follows the shaft by the rolling ratio at every speed
    np.testing.assert_allclose(p.cage_angle(t), 0.5 * (1 - p.geometry.diameter_ratio) * p.shaft_angle(t), rtol=1e-12)
    tach = p.tachometer_times(0.0, 1.0, 4)
    np.testing.assert_allclose(p.shaft_angle(tach), 2 * np.pi * np.arange(len(tach)) / 4, atol=1e-9)
    assert len(tach) == int(4 * (1000 / 60 + 5)) + 1  # 21.67 revolutions, 4 pulses each, and t = 0
    assert np.all(np.diff(np.diff(tach)) < 0)  # pulses come faster as the shaft speeds up
    const = base.tachometer_times(0.0, 1.0, 1)
    np.testing.assert_allclose(np.diff(const), 60 / 1000)


# --- Harris's load zone --------------------------------------------------------


def _harris_jr(eps: float) -> float:
    """Harris's radial integral J_r(eps) for line contact (n = 10/9), by quadrature [-]."""
    from scipy.integrate import quad

    psi_l = np.arccos(1 - 2 * eps)
    f = lambda psi: (1 - (1 - np.cos(psi)) / (2 * eps)) ** (10 / 9) * np.cos(psi)  # noqa: E731
    return quad(f, -psi_l, psi_l, epsabs=1e-13)[0] / (2 * np.pi)


@pytest.mark.parametrize("clearance_um", [0.0, 20.0, 60.0])
@pytest.mark.parametrize("load_N", [200.0, 500.0, 2000.0])
def test_load_zone_follows_harris(base, clearance_um, load_N):
    """Many rollers approach Harris's continuous load zone (Harris & Kotzalas Sec. 7.2):
    epsilon = (1 - P_d / (2 delta_r)) / 2, half angle psi_l = arccos(P_d / (2 delta_r)),
    F_r = Z Q_max J_r(epsilon); without clearance epsilon = 1/2 (half the bearing loaded)."""
    z = 720
    psi = 2 * np.pi * np.arange(z) / z
    psi = np.where(psi >= np.pi, psi - 2 * np.pi, psi)
    gap, k = 0.5 * clearance_um * 1e-6, base.k_contact
    e = bearing_lpm.static_offset(np.array([0.0, -load_N]), psi, gap, np.zeros(z), k)
    _, _, q = bearing_lpm.bearing_force(e, psi, gap, np.zeros(z), k)
    delta_r = -e[1]
    eps = 0.5 * (1 - gap / delta_r)  # gap = P_d / 2
    psi_l = np.arccos(gap / delta_r)
    loaded = np.abs(psi[q > 0])
    assert loaded.max() == pytest.approx(psi_l, abs=2 * np.pi / z)
    assert load_N / (z * q.max()) == pytest.approx(_harris_jr(eps), rel=2e-3)
    if clearance_um == 0:
        assert eps == pytest.approx(0.5, abs=1e-12)
    else:
        assert eps < 0.5


def test_harris_integral_closed_form_at_half_load_zone():
    # eps = 1/2: J_r = (1/2pi) int cos^(19/9) = sqrt(pi) Gamma(14/9) / (2 pi Gamma(37/18))
    a = 1 + 10 / 9
    closed = np.sqrt(np.pi) * gamma((a + 1) / 2) / gamma(a / 2 + 1) / (2 * np.pi)
    assert _harris_jr(0.5) == pytest.approx(closed, rel=1e-10)
    assert closed == pytest.approx(0.2448, abs=1e-4)
    # Harris's table (line contact, exponent 1.1 instead of 10/9) gives 0.2453; the same formula with 1.1:
    a = 2.1
    assert np.sqrt(np.pi) * gamma((a + 1) / 2) / gamma(a / 2 + 1) / (2 * np.pi) == pytest.approx(0.2453, abs=1e-4)


def test_load_zone_shrinks_with_clearance_and_grows_with_load(base):
    z = 720
    psi = 2 * np.pi * np.arange(z) / z
    psi = np.where(psi >= np.pi, psi - 2 * np.pi, psi)

    def half_angle(gap, load):
        e = bearing_lpm.static_offset(np.array([0.0, -load]), psi, gap, np.zeros(z), base.k_contact)
        return np.arccos(gap / -e[1])

    assert half_angle(5e-6, 500) > half_angle(20e-6, 500) > half_angle(40e-6, 500)
    assert half_angle(20e-6, 200) < half_angle(20e-6, 500) < half_angle(20e-6, 5000)


# --- fault types -----------------------------------------------------------------


def test_outer_race_defect_anywhere(base):
    """A fixed groove at 40 deg: every roller sinks when its angle passes 40 deg, by the concave drop."""
    d = bearing_lpm.Defect(np.radians(40.0), 0.9e-3, 1e-3, "outer_race")
    p = replace(base, defects=(d,))
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz)
    t = np.linspace(0, 1, 400001)
    mo = p.motion(t)
    drop = p.drops(mo)
    assert drop.max() == pytest.approx(d.max_drop_m(p.geometry.relative_radius_m("outer")), rel=1e-3)
    assert np.all(np.abs(mo.psi_rad[drop > 0] - np.radians(40.0)) < 0.45e-3 / 27e-3 + 1e-9)
    n = len(_episodes(drop.max(axis=1) > 0))
    assert abs(n - kin.bpfo_Hz * 1.0) <= 1


def test_inner_race_defect_turns_with_the_shaft_and_is_loaded_only_in_the_load_zone(bcfg, base):
    d = bearing_lpm.Defect(0.0, 0.9e-3, 1e-3, "inner_race")
    p = replace(base, defects=(d,))
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz)
    t = np.linspace(0, 1, 400001)
    mo = p.motion(t)
    drop = p.drops(mo)
    # the rollers meet the turning groove at BPFI
    assert abs(len(_episodes(drop.max(axis=1) > 0)) - kin.bpfi_Hz) <= 1
    assert drop.max() == pytest.approx(26.3e-6, rel=2e-3)  # convex inner race
    # where the groove is when it meets a roller: at the shaft's angle
    hit = drop.max(axis=1) > 0
    gap_to_groove = np.abs(np.angle(np.exp(1j * (mo.psi_rad - mo.shaft_angle_rad[:, None])))).min(axis=1)
    assert gap_to_groove[hit].max() < 0.45e-3 / 17e-3 + 1e-9
    # dynamics over one shaft revolution: the loads change only while the groove is in the load zone
    h = bcfg["time_step_s"] / bcfg["substeps"]
    n = int(round(1 / p.shaft_speed_Hz / h))
    rf, rh = bearing_lpm.simulate_lpm(p, 0.0, n, h), bearing_lpm.simulate_lpm(base, 0.0, n, h)
    diff = np.abs(rf.load_N - rh.load_N).max(axis=1)
    where = np.angle(np.exp(1j * (d.angle_rad + p.shaft_angle(rf.time_s))))
    assert diff[np.abs(where) < np.radians(30)].max() > 50.0  # the roller under the load sinks: tens of newtons
    assert diff[np.abs(where) > np.radians(120)].max() < 0.02 * diff.max()  # out of the load zone: nothing


def test_rolling_element_flat_strikes_both_races_at_twice_bsf(bcfg, base):
    """A flat on roller 0 meets the outer and the inner race in turn: 2 BSF impacts, alternately the
    concave (16.5 um) and the convex (26.3 um) drop; only roller 0; felt only in the load zone (FTF)."""
    d = bearing_lpm.Defect(0.0, 0.9e-3, 1e-3, "rolling_element")
    p = replace(base, defects=(d,))
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz)
    t = np.linspace(0, 2, 800001)
    mo = p.motion(t)
    drop = p.drops(mo)
    assert np.all(drop[:, 1:] == 0)
    starts = _episodes(drop[:, 0] > 0)
    assert abs(len(starts) - 2 * kin.bsf_Hz * 2.0) <= 1
    ends = _episodes(drop[::-1, 0] > 0)[::-1]
    peaks = np.array([drop[s : len(t) - e, 0].max() for s, e in zip(starts, ends, strict=False)])
    outer, inner = (d.max_drop_m(p.geometry.relative_radius_m(r)) for r in ("outer", "inner"))
    # (the profile is a cusp at the centre: sampled every 5.5 um of roller surface, peaks within 1.5%)
    np.testing.assert_allclose(np.sort(peaks)[: len(peaks) // 2], outer, rtol=1.5e-2)
    np.testing.assert_allclose(np.sort(peaks)[-(len(peaks) // 2) :], inner, rtol=1.5e-2)
    # dynamics over one cage revolution: roller 0 loses load at its strikes inside the load zone only
    h = bcfg["time_step_s"] / bcfg["substeps"]
    n = int(round(1 / kin.ftf_Hz / h))
    rf, rh = bearing_lpm.simulate_lpm(p, 0.0, n, h), bearing_lpm.simulate_lpm(base, 0.0, n, h)
    dq = rh.load_N[:, 0] - rf.load_N[:, 0]
    in_zone = np.abs(rf.psi_rad[:, 0]) < np.radians(45)
    strike = p.drops(p.motion(rf.time_s))[:, 0] > 0.5 * outer
    assert (strike & in_zone).any() and (strike & ~in_zone & (np.abs(rf.psi_rad[:, 0]) > np.radians(100))).any()
    assert dq[strike & in_zone].max() > 100.0
    assert np.abs(dq[strike & (np.abs(rf.psi_rad[:, 0]) > np.radians(100))]).max() < 1.0


def test_flat_on_any_roller_is_roller_0_turned_by_its_pitch(bcfg, base):
    """With equal rollers, a flat on roller j is the flat on roller 0 with the start angle moved by j
    pitches (the rollers are interchangeable); the config's ``roller`` picks it."""
    j = 4
    b = {**bcfg, "defects": [{"type": "rolling_element", "width_m": 0.9e-3, "depth_m": 1e-3, "angle_deg": 20.0,
                              "roller": j}]}
    p = bearing_lpm.LPMParameters.from_config(b, True, seed=7)
    assert p.defects[0].roller == j
    q = replace(p, defects=(replace(p.defects[0], roller=0),),
                start_angle_rad=p.start_angle_rad + j * p.geometry.roller_pitch_rad)
    t = np.linspace(0, 0.5, 20001)
    dp, dq = p.drops(p.motion(t)), q.drops(q.motion(t))
    assert (dp[:, j] > 0).any() and not np.delete(dp, j, axis=1).any()
    np.testing.assert_array_equal(dp[:, j], dq[:, 0])
    np.testing.assert_allclose(p.motion(t).psi_rad[:, j], q.motion(t).psi_rad[:, 0], atol=1e-12)


def test_several_defects_superpose(base):
    defects = (
        bearing_lpm.Defect(0.0, 0.9e-3, 1e-3, "outer_race"),
        bearing_lpm.Defect(1.0, 0.6e-3, 1e-3, "inner_race"),
        bearing_lpm.Defect(0.5, 0.3e-3, 1e-3, "rolling_element"),
    )
    t = np.linspace(-0.05, 0.5, 20001)
    mo = base.motion(t)
    total = replace(base, defects=defects).drops(mo)
    each = sum(replace(base, defects=(d,)).drops(mo) for d in defects)
    np.testing.assert_array_equal(total, each)
    assert all((replace(base, defects=(d,)).drops(mo) > 0).any() for d in defects)


# --- roller diameters, config ------------------------------------------------------


def test_roller_diameter_scatter_from_the_seed(bcfg):
    b = {**bcfg, "roller_diameter_scatter_m": 0.5e-6}
    p = bearing_lpm.LPMParameters.from_config(b, True, seed=3)
    dev = np.array(p.roller_diameter_deviation_m)
    assert dev.shape == (11,) and 0.2e-6 < dev.std() < 1.0e-6
    deviation = p.roller_diameter_deviation_m
    assert bearing_lpm.LPMParameters.from_config(b, False, seed=3).roller_diameter_deviation_m == deviation
    assert bearing_lpm.LPMParameters.from_config(b, True, seed=4).roller_diameter_deviation_m != deviation
    assert bearing_lpm.LPMParameters.from_config(bcfg, True, seed=3).roller_diameter_deviation_m == ()
    # a larger roller at the bottom carries more than its nominal share
    psi = p.roller_angles(np.array([0.0]))[0]
    off = p.contact_offsets(p.motion(np.array([0.0])))[0]
    big = np.zeros(11)
    big[0] = -2e-6
    q_nom = bearing_lpm.bearing_force(
        bearing_lpm.static_offset(np.array([0, -500.0]), psi, p.gap_m, 0 * off, p.k_contact),
        psi, p.gap_m, 0 * off, p.k_contact)[2]
    q_big = bearing_lpm.bearing_force(
        bearing_lpm.static_offset(np.array([0, -500.0]), psi, p.gap_m, big, p.k_contact),
        psi, p.gap_m, big, p.k_contact)[2]
    assert q_big[0] > q_nom[0] * 1.05


def test_defects_from_config_and_schema(paper_config):
    b = paper_config["bearing"]
    (d,) = bearing_lpm.defects_from_config(b)
    assert (d.kind, d.width_m, d.depth_m, d.angle_rad) == ("outer_race", 0.9e-3, 1.0e-3, 0.0)  # the paper
    assert bearing_lpm.LPMParameters.from_config(b, False).defects == ()
    assert bearing_lpm.LPMParameters.from_config({**b, "defects": []}, True).defects == ()
    c = copy.deepcopy(paper_config)
    c["bearing"]["defects"] = [{"type": "cage", "width_m": 1e-3, "depth_m": 1e-3, "angle_deg": 0.0}]
    with pytest.raises(config.ConfigError) as e:
        config.validate(c, source="my.yaml")
    assert "bearing.defects" in str(e.value) and "\n" not in str(e.value)


def test_bearing_lpm_stage_with_slip_tachometer_and_two_defects(ci_config, tmp_path):
    """The stage's outputs for a rig-like case: kinematic lines without and with slip, the tachometer,
    one entry per defect with its drop and impact rate."""
    import json

    from piezobearing.stages import bearing as bearing_stages

    c = copy.deepcopy(ci_config)
    b = c["bearing"]
    b.update(duration_s=0.2, settle_s=0.01, cage_slip=0.015, slip_jitter=0.003, tachometer_pulses_per_rev=1)
    b["defects"] = [
        {"type": "outer_race", "width_m": 0.9e-3, "depth_m": 1.0e-3, "angle_deg": 0.0},
        {"type": "rolling_element", "width_m": 0.6e-3, "depth_m": 1.0e-3, "angle_deg": 30.0},
    ]
    c = config.validate(c)
    npz = {k: tmp_path / f"contact_{k}.npz" for k in bearing_stages.CASES}
    bearing_stages.bearing_lpm(tmp_path / "kin.json", npz, {k: tmp_path / f"cf_{k}.csv" for k in bearing_stages.CASES},
                               tmp_path / "l.json", c)
    kin = json.loads((tmp_path / "kin.json").read_text())
    assert kin["bpfo_Hz"] == pytest.approx(70.833, rel=1e-4)  # the kinematic line, as signals.fault_bands expects
    assert kin["with_slip"]["bpfo_Hz"] == pytest.approx(0.985 * kin["bpfo_Hz"], rel=1e-12)
    assert kin["cage_slip"] == 0.015 and kin["defect_types"] == ["outer_race", "rolling_element"]
    tach = np.load(npz["faulty"])["tachometer_time_s"]
    np.testing.assert_allclose(np.diff(tach), 60 / 1000, rtol=1e-12)
    np.testing.assert_array_equal(kin["tachometer_time_s"], tach)  # where a user reads the kinematics
    assert kin["tachometer_pulses_per_rev"] == 1
    lpm = json.loads((tmp_path / "l.json").read_text())
    d0, d1 = lpm["faulty"]["defects"]
    assert d0["max_drop_m"] == pytest.approx(16.5e-6, rel=2e-3) and d0["max_drop_flat_raceway_m"] > d0["max_drop_m"]
    assert d1["impact_rate_Hz"] == pytest.approx(2 * kin["with_slip"]["bsf_Hz"], rel=1e-12)
    assert lpm["faulty"]["impact_frequency_Hz"] == pytest.approx(kin["with_slip"]["bpfo_Hz"], rel=0.02)
    # the same seed gives both cases the same cage: the healthy and faulty roller angles agree
    h, f = np.load(npz["healthy"]), np.load(npz["faulty"])
    np.testing.assert_array_equal(h["angle_rad"], f["angle_rad"])
