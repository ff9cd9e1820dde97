"""The bearing: kinematics, contact law, defect geometry and the 4-DOF lumped-parameter model."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from piezobearing.bearing import lpm
from piezobearing.bearing.geometry import BearingGeometry, kinematic_frequencies
from piezobearing.config import ConfigError


@pytest.fixture(scope="module")
def bcfg(paper_config):
    return paper_config["bearing"]


@pytest.fixture(scope="module")
def geo(bcfg):
    return BearingGeometry.from_config(bcfg)


def _params(bcfg, faulty=False, **over):
    p = lpm.LPMParameters.from_config(bcfg, faulty)
    from dataclasses import replace

    if "clearance" in over:
        p = replace(p, geometry=replace(p.geometry, radial_clearance_m=over.pop("clearance")))
    return replace(p, **over)


# --- kinematics ---------------------------------------------------------------


def test_bpfo_matches_paper(geo):
    kin = kinematic_frequencies(geo, 1000 / 60)
    assert kin.bpfo_Hz == pytest.approx(70.8, rel=1e-3)
    # the paper's time step is 1/(36 BPFO) to its 6 digits
    assert 1 / (36 * kin.bpfo_Hz) == pytest.approx(0.392156e-3, abs=1e-9)


def test_kinematic_identities(geo):
    fr = 23.0
    kin = kinematic_frequencies(geo, fr)
    z, g = geo.n_rollers, geo.roller_diameter_m / geo.pitch_diameter_m
    assert kin.bpfo_Hz + kin.bpfi_Hz == pytest.approx(z * fr)
    assert kin.ftf_Hz == pytest.approx(fr / 2 * (1 - g))
    assert kin.bsf_Hz == pytest.approx(geo.pitch_diameter_m / (2 * geo.roller_diameter_m) * fr * (1 - g * g))
    assert set(kin.to_dict()) == {"shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz"}


def test_bad_geometry_names_the_key(bcfg):
    bad = {**bcfg, "pitch_diameter_m": 60e-3}
    with pytest.raises(ValueError, match="pitch_diameter_m"):
        BearingGeometry.from_config(bad)


# --- contact law and defect ---------------------------------------------------


def test_contact_stiffness_is_palmgren_twice():
    l_mm, q = 9.76, 500.0
    delta_mm = 2 * 3.84e-5 * q**0.9 / l_mm**0.8  # two contacts in series, Harris Eq. 6.41
    k = lpm.line_contact_stiffness(l_mm * 1e-3)
    assert k * (delta_mm * 1e-3) ** (10 / 9) == pytest.approx(q, rel=1e-12)


def test_contact_law_slope():
    k = 6e8
    d = np.array([-1e-6, 0.0, 1e-6, 3e-6])
    q, dq = lpm.contact_law(d, k)
    assert q[0] == q[1] == 0.0
    eps = 1e-12
    num = (lpm.contact_law(d + eps, k)[0] - lpm.contact_law(d - eps, k)[0]) / (2 * eps)
    np.testing.assert_allclose(dq[2:], num[2:], rtol=1e-5)


def test_defect_drop_limited_by_roller_radius():
    r, w = 5e-3, 0.9e-3
    d = lpm.Defect(0.0, w, 1e-3)
    expect = r - np.sqrt(r**2 - (w / 2) ** 2)
    assert d.max_drop_m(r) == pytest.approx(expect)
    assert expect == pytest.approx(20.29e-6, rel=1e-3)  # on a flat raceway: tens of um, not the 1 mm depth
    arc = np.linspace(-2 * w, 2 * w, 4001)
    drop = lpm.chord_drop_m(arc, w, 1e-3, r)
    assert drop.max() == pytest.approx(expect, rel=1e-3)
    np.testing.assert_allclose(drop, drop[::-1], atol=1e-12)  # entry and exit flanks mirror each other
    assert np.all(drop[np.abs(arc) >= w / 2] == 0)
    assert lpm.chord_drop_m(np.array([0.0]), w, 5e-6, r)[0] == pytest.approx(5e-6)  # a shallow groove: its depth


def test_concave_and_convex_raceway_drops(geo):
    """The raceway's curvature: against the concave outer race (R = 27 mm) the relative radius is
    1/(1/5 - 1/27) mm = 6.14 mm and the 0.9 mm groove lets the roller sink 16.5 um (not 20.3 um on a
    flat race), the 0.3 mm groove 1.83 um; against the convex inner race (R = 17 mm) 3.86 mm, 26.3 um."""
    r_out, r_in = geo.relative_radius_m("outer"), geo.relative_radius_m("inner")
    assert r_out == pytest.approx(1 / (1 / 5e-3 - 1 / 27e-3), rel=1e-12)
    assert r_out == pytest.approx(6.136e-3, rel=1e-3)
    assert r_in == pytest.approx(1 / (1 / 5e-3 + 1 / 17e-3), rel=1e-12)
    for w, expect in ((0.9e-3, 16.5e-6), (0.3e-3, 1.834e-6)):
        d = lpm.Defect(0.0, w, 1e-3)
        assert d.max_drop_m(r_out) == pytest.approx(expect, rel=2e-3)
        assert d.max_drop_m(r_out) == pytest.approx(w * w / (8 * r_out), rel=2e-3)  # sagitta
    assert lpm.Defect(0.0, 0.9e-3, 1e-3).max_drop_m(r_in) == pytest.approx(26.3e-6, rel=2e-3)
    with pytest.raises(ValueError, match="race"):
        geo.relative_radius_m("cage")
    with pytest.raises(ValueError, match="defect type"):
        lpm.Defect(0.0, 1e-3, 1e-3, "cage")


def _rolling_circle_drop(x_c: np.ndarray, profile_x: np.ndarray, profile_y: np.ndarray, r: float) -> np.ndarray:
    """How far a circle of radius r resting on the surface points (x, y) sinks below y = 0 at x_c: the
    highest centre any point allows, found by brute force over the points (independent of the closed form)."""
    dx = profile_x[None, :] - x_c[:, None]
    reach = np.where(np.abs(dx) < r, profile_y[None, :] + np.sqrt(np.maximum(r * r - dx * dx, 0.0)), -np.inf)
    return r - reach.max(axis=1)


@pytest.mark.parametrize("race", ["outer", "inner"])
def test_rounded_edge_drop_is_the_rolling_circle_over_its_fillets(geo, race):
    """A groove 0.6 mm wide at the surface whose edges are fillets of rho = 0.15 mm, 1 mm deep: the roller's
    drop from the closed form (the centre circles each fillet's centre at R + rho) against a circle of the
    relative radius R rolled over the drawn profile (land, quarter-circle fillet, wall, floor, wall, fillet,
    land), in the unrolled picture of the relative radius."""
    r, w, rho, depth = geo.relative_radius_m(race), 0.6e-3, 0.15e-3, 1e-3
    t = np.linspace(0.0, 0.5 * np.pi, 20001)
    fil_x, fil_y = rho * np.sin(t), -rho + rho * np.cos(t)  # entry fillet: centre (0, -rho), from (0, 0) to (rho, -rho)
    land = np.linspace(-2e-3, 0.0, 4001)
    wall = np.linspace(-rho, -depth, 200)
    floor = np.linspace(rho, w - rho, 400)
    px = np.concatenate([land, fil_x, np.full(wall.size, rho), floor, np.full(wall.size, w - rho), w - fil_x[::-1],
                         w - land[::-1]])
    py = np.concatenate([0 * land, fil_y, wall, np.full(floor.size, -depth), wall[::-1], fil_y[::-1], 0 * land])
    u = np.linspace(-0.1e-3, w + 0.1e-3, 701)
    expect = _rolling_circle_drop(u, px, py, r)
    got = lpm.chord_drop_m(u - 0.5 * w, w, depth, r, rho)
    np.testing.assert_allclose(got, expect, rtol=0, atol=2e-4 * expect.max())
    # the closed form itself: (R + rho) - sqrt((R + rho)^2 - m^2), m the distance to the nearer opening edge
    m = np.minimum(u, w - u)
    inside = (u > 0) & (u < w)
    np.testing.assert_allclose(got[inside], (r + rho) - np.sqrt((r + rho) ** 2 - m[inside] ** 2), rtol=1e-12)
    assert np.all(got[~inside] == 0)
    # shallower than the sharp groove of the same surface width, as deep as the sharp groove of the equivalent width
    d = lpm.Defect(0.0, w, depth, f"{race}_race", edge_radius_m=rho)
    sharp = lpm.Defect(0.0, w, depth, f"{race}_race")
    assert d.max_drop_m(r) == pytest.approx(got.max(), rel=1e-6)
    assert d.max_drop_m(r) < sharp.max_drop_m(r)
    w_eq = d.equivalent_sharp_width_m(r)
    assert w_eq == pytest.approx(w * np.sqrt(r / (r + rho)), rel=2e-3)  # the sagitta's w^2 / (8 R) to first order
    assert lpm.Defect(0.0, w_eq, depth).max_drop_m(r) == pytest.approx(d.max_drop_m(r), rel=1e-12)
    assert sharp.equivalent_sharp_width_m(r) == pytest.approx(w, rel=1e-12)


def test_sharp_edges_are_the_default_and_unchanged(geo, bcfg):
    """Without an edge radius the drop is the sharp-edged chord drop, bit for bit, in the function, the defect and
    the LPM's drops; a config defect without ``edge_radius_m`` reads as sharp, one with it carries it."""
    r, w = geo.relative_radius_m("outer"), 0.9e-3
    arc = np.linspace(-w, w, 2001)
    u = arc + 0.5 * w
    m = np.minimum(u, w - u)
    sharp = np.where((u > 0) & (u < w), np.minimum(r - np.sqrt(np.maximum(r * r - m * m, 0.0)), 1e-3), 0.0)
    assert np.array_equal(lpm.chord_drop_m(arc, w, 1e-3, r), sharp)
    assert np.array_equal(lpm.chord_drop_m(arc, w, 1e-3, r, 0.0), sharp)
    (d,) = lpm.defects_from_config(bcfg)
    assert d.edge_radius_m == 0.0
    rounded = dict(bcfg["defects"][0], edge_radius_m=0.2e-3)
    (dr,) = lpm.defects_from_config({**bcfg, "defects": [rounded]})
    assert dr.edge_radius_m == 0.2e-3
    p = lpm.LPMParameters.from_config(bcfg, True)
    mo = p.motion(np.linspace(0.0, 0.05, 2001))
    explicit = replace(p, defects=(replace(d, edge_radius_m=0.0),))
    assert np.array_equal(p.drops(mo), explicit.drops(mo))
    round_p = replace(p, defects=(dr,))
    # rounded: as long a dip (the surface width), never deeper
    assert np.all(round_p.drops(mo) <= p.drops(mo))
    assert np.array_equal(round_p.drops(mo) > 0, p.drops(mo) > 0)
    with pytest.raises(ValueError, match="edge radius"):
        lpm.Defect(0.0, 0.6e-3, 1e-3, edge_radius_m=0.31e-3)
    too_round = dict(bcfg["defects"][0], edge_radius_m=0.5e-3)  # the groove is 0.9 mm wide: at most 0.45 mm
    with pytest.raises(ConfigError) as e:
        lpm.defects_from_config({**bcfg, "defects": [too_round]})
    msg = str(e.value)
    assert "\n" not in msg and "key 'bearing.defects[0].edge_radius_m'" in msg and "at most half the width" in msg


# --- quasi-static load distribution against Harris -------------------------------


@pytest.mark.parametrize("clearance", [0.0, 20e-6])
@pytest.mark.parametrize("psi0_fraction", [0.0, 0.5])
def test_static_loads_match_harris(bcfg, clearance, psi0_fraction):
    p = _params(bcfg, clearance=clearance)
    g = p.geometry
    psi = g.roller_pitch_rad * (psi0_fraction + np.arange(g.n_rollers))
    zero = np.zeros_like(psi)
    e = lpm.static_offset(np.array([0.0, -500.0]), psi, p.gap_m, zero, p.k_contact)
    _, _, q = lpm.bearing_force(e, psi, p.gap_m, zero, p.k_contact)
    qh, dr = lpm.harris_discrete_loads(500.0, psi, p.gap_m, p.k_contact)
    np.testing.assert_allclose(q, qh, atol=1e-6 * qh.max())
    assert e[0] == pytest.approx(0.0, abs=1e-12)
    assert -e[1] == pytest.approx(dr, rel=1e-9)


@pytest.mark.parametrize("clearance", [0.0, 20e-6])
def test_dynamic_lpm_quasi_static_matches_harris(bcfg, clearance):
    """At a slow speed the integrated loads equal Harris's discrete distribution within 1%."""
    p = _params(bcfg, clearance=clearance, shaft_speed_Hz=0.5)
    g = p.geometry
    # half a roller pitch of cage rotation: passes both symmetric positions
    t_end = 0.5 * g.roller_pitch_rad / p.cage_speed_rad_per_s
    n = 4000
    res = lpm.simulate_lpm(p, 0.0, n, t_end / n)
    for k in (0, n):
        qh, _ = lpm.harris_discrete_loads(500.0, res.psi_rad[k], p.gap_m, p.k_contact)
        assert np.abs(res.load_N[k] - qh).max() < 0.01 * qh.max()
    # in between, against the static 2D equilibrium at the same angles
    for k in (n // 3, 2 * n // 3):
        zero = np.zeros(g.n_rollers)
        e = lpm.static_offset(np.array([0.0, -500.0]), res.psi_rad[k], p.gap_m, zero, p.k_contact)
        q = lpm.bearing_force(e, res.psi_rad[k], p.gap_m, zero, p.k_contact)[2]
        assert np.abs(res.load_N[k] - q).max() < 0.01 * q.max()


def test_clearance_shrinks_the_load_zone(bcfg):
    p0, p1 = _params(bcfg, clearance=0.0), _params(bcfg, clearance=20e-6)
    psi = p0.geometry.roller_pitch_rad * np.arange(11)
    q0, _ = lpm.harris_discrete_loads(500.0, psi, p0.gap_m, p0.k_contact)
    q1, _ = lpm.harris_discrete_loads(500.0, psi, p1.gap_m, p1.k_contact)
    assert (q1 > 0).sum() < (q0 > 0).sum()
    assert q1.max() > q0.max()


# --- dynamics -----------------------------------------------------------------


def test_load_equilibrium_over_a_record(bcfg):
    """Averaged over roller passages the rollers carry the radial load (inertia averages out)."""
    p = _params(bcfg)
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz)
    h = bcfg["time_step_s"] / bcfg["substeps"]
    n = int(round(5 / kin.bpfo_Hz / h))
    res = lpm.simulate_lpm(p, 0.0, n, h)
    fz = np.sum(res.load_N * -np.cos(res.psi_rad), axis=1)
    fy = np.sum(res.load_N * np.sin(res.psi_rad), axis=1)
    assert -fz.mean() == pytest.approx(500.0, rel=2e-3)
    assert abs(fy.mean()) < 1e-3 * 500
    # the pedestal spring carries the load too
    assert -res.pedestal_m[:, 1].mean() * p.pedestal_stiffness_N_per_m == pytest.approx(500.0, rel=2e-3)


def test_defect_impacts_repeat_at_bpfo(bcfg):
    from piezobearing.housing.checks import impact_intervals

    p = _params(bcfg, faulty=True)
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz)
    h = bcfg["time_step_s"] / bcfg["substeps"]
    n = int(round(8 / kin.bpfo_Hz / h))
    res = lpm.simulate_lpm(p, 0.0, n, h)
    iv = impact_intervals(res.time_s, res.load_N.max(axis=1), kin.bpfo_Hz)
    assert len(iv) >= 6
    np.testing.assert_allclose(iv, 1 / kin.bpfo_Hz, rtol=0.01)
    # the healthy bearing has no such impacts: its largest load varies smoothly and far less
    ph = _params(bcfg)
    rh = lpm.simulate_lpm(ph, 0.0, n, h)
    assert np.ptp(rh.load_N.max(axis=1)) < 0.5 * np.ptp(res.load_N.max(axis=1))


def test_trapezoidal_rule_agrees_with_radau(bcfg):
    """The fixed-step implicit integrator against scipy's adaptive Radau over a defect passage.

    At the default step (T/36 = 10.9 us) the largest load error, at the
    defect's exit, is below 2% of the peak load, and it falls as h^2.

    The reference at rtol 1e-7, atol 1e-13 m (12k right-hand sides; rtol 1e-9,
    atol 1e-15 m takes 36k, 3x the CPU) is within 1.9e-5 N of the
    rtol-1e-9 one, 1.5e-5 of the smallest error measured here (1.3 N at h/2):
    both give errors[0] = 1.06% of the peak and the ratio 4.0146, so the check
    is as strict as before.
    """
    p = _params(bcfg, faulty=True, start_angle_rad=-0.012)
    h = bcfg["time_step_s"] / bcfg["substeps"]
    n = 240  # 2.6 ms: the roller at -0.012 rad crosses the defect at 0
    fun, jac = lpm.lpm_rhs(p)
    errors = []
    for div in (1, 2):
        res = lpm.simulate_lpm(p, 0.0, n * div, h / div)
        if div == 1:
            y0 = np.r_[res.shaft_m[0], res.pedestal_m[0], np.zeros(4)]
            sol = solve_ivp(
                fun,
                (0, n * h),
                y0,
                method="Radau",
                jac=jac,
                rtol=1e-7,
                atol=1e-13,
                t_eval=res.time_s,
                max_step=h,
            )
            assert sol.success
            e = sol.y[:2] - sol.y[2:4]
            delta = lpm.roller_deflections(e.T, res.psi_rad, p.gap_m, p.drops(p.motion(res.time_s)))
            q_ref = lpm.contact_law(delta, p.k_contact)[0]
            assert res.load_N[:, 0].min() == 0.0  # the roller unloads in the defect
        errors.append(np.abs(res.load_N[::div] - q_ref).max())
    assert errors[0] < 0.02 * q_ref.max()
    assert 3.0 < errors[0] / errors[1] < 5.0  # second order


def test_compiled_kernel_matches_the_python_loop(bcfg):
    """The numba kernel runs the reference loop's algorithm: same loads, same Newton iterations.

    Over two defect passages of the faulty bearing (the contacts open and close, the
    roller drops into the groove) the loads and the shaft displacement agree to 1e-9 of
    their peaks. The tolerance is relative because numba compiles for the host CPU (FMA,
    vector width): the two paths differ in the last bits, by different amounts on
    different CPUs.
    """
    p = _params(bcfg, faulty=True, start_angle_rad=-0.3)
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz)
    h = bcfg["time_step_s"] / bcfg["substeps"]
    n = int(round(2 / kin.bpfo_Hz / h))
    rc = lpm.simulate_lpm(p, 0.0, n, h, method="compiled")
    rp = lpm.simulate_lpm(p, 0.0, n, h, method="python")
    assert rp.load_N.max() > 0 and (rc.load_N == 0).any()
    np.testing.assert_allclose(rc.load_N, rp.load_N, rtol=0, atol=1e-9 * rp.load_N.max())
    np.testing.assert_allclose(rc.shaft_m, rp.shaft_m, rtol=0, atol=1e-9 * np.abs(rp.shaft_m).max())
    assert abs(rc.newton_iterations - rp.newton_iterations) <= n // 1000 + 1
    with pytest.raises(ValueError, match="method"):
        lpm.simulate_lpm(p, 0.0, 2, h, method="fortran")


def test_average_resampling_keeps_the_impulse():
    t = np.linspace(0, 0.01, 10001)
    q = np.where(np.abs(t - 0.005) < 0.2e-3, 100.0, 0.0)[:, None]
    dt = 0.39e-3
    t_out = np.arange(0.001, 0.009, dt)
    avg = lpm.resample_loads(t, q, t_out, dt, "average")
    smp = lpm.resample_loads(t, q, t_out, dt, "sample")
    assert avg.sum() * dt == pytest.approx(100.0 * 0.4e-3, rel=0.01)
    np.testing.assert_allclose(smp[:, 0], np.interp(t_out, t, q[:, 0]))
    with pytest.raises(ValueError, match="resample"):
        lpm.resample_loads(t, q, t_out, dt, "nearest")
