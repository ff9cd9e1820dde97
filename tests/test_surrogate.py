"""The quasi-static surrogate of the bearing chain: load distribution x influence line.

Checked against Harris's discrete load distribution, the LPM's static solver, its own fine
sampling, and the full LPM (with inertia) through the same influence line.
"""

import numpy as np
import pytest

from piezobearing.bearing import lpm
from piezobearing.bearing import surrogate as sg
from piezobearing.bearing.geometry import BearingGeometry


@pytest.fixture(scope="module")
def setup(paper_config):
    b = paper_config["bearing"]
    geo = BearingGeometry.from_config(b)
    # a smooth stand-in of the housing's influence line: 0.24 N/N over the sensor, falling off over ~25 deg
    a = np.linspace(-np.pi, np.pi, 721)
    infl = sg.InfluenceLine(a, 0.24 * np.exp(-0.5 * (a / 0.3) ** 2) + 0.01 * np.cos(a))
    return b, geo, infl


def test_loads_equal_harris_and_the_lpm_static_solver(setup):
    b, geo, _ = setup
    k = lpm.line_contact_stiffness(geo.roller_length_m)
    gap = b["radial_clearance_m"] / 2
    pitch = geo.roller_pitch_rad
    for phi in (0.0, 0.5 * pitch):  # symmetric positions: Harris applies
        psi = phi + pitch * np.arange(geo.n_rollers)
        q = sg.quasi_static_loads(psi[None], 0.0, 500.0, gap, k)[0]
        qh, _ = lpm.harris_discrete_loads(500.0, psi, gap, k)
        assert np.abs(q - qh).max() < 1e-8 * qh.max()
    rng = np.random.default_rng(3)
    phis = rng.uniform(0, pitch, 7)
    psi = phis[:, None] + pitch * np.arange(geo.n_rollers)
    drop = sg.outer_race_drop(psi, 0.02, 0.9e-3, geo)
    q = sg.quasi_static_loads(psi, drop, 500.0, gap, k)
    for i in range(len(phis)):
        e = lpm.static_offset(np.array([0.0, -500.0]), psi[i], gap, drop[i], k)
        _, _, qr = lpm.bearing_force(e, psi[i], gap, drop[i], k)
        np.testing.assert_allclose(q[i], qr, atol=1e-6)
    # the loads carry the radial load
    assert np.allclose(np.sum(q * np.cos(psi), 1), 500.0, rtol=1e-9)


def test_box_average_is_the_mean_over_each_sample(setup):
    b, geo, infl = setup
    s = sg.Surrogate(geo, infl)
    op = sg.Operating(500.0, b["radial_clearance_m"])
    t = np.arange(60) / 2550.0
    ph = sg.cage_phase(t, 1000 / 60, geo, 0.3)
    avg = s.box_average(sg.phase_edges(ph), op)
    edges = sg.phase_edges(ph)
    fine = np.concatenate([np.linspace(a, c, 41) for a, c in zip(edges[:-1], edges[1:], strict=True)])
    f, _ = s.sensor_force_at(fine, op)
    ref = np.trapezoid(f.reshape(60, 41), dx=1 / 40, axis=1)
    assert np.abs(avg - ref).max() < 1e-4 * np.ptp(ref)


@pytest.mark.parametrize("faulty, tol", [(False, 0.02), (True, 0.16)])
def test_surrogate_against_the_lpm_through_the_same_influence_line(setup, faulty, tol):
    """The LPM has the shaft's inertia (its ~2 kHz mode rings after a defect), the surrogate does not.

    Through this narrow stand-in line (measured: 1.3% healthy, 13% with the 0.9 mm defect, of the
    force's standard deviation); through the housing FEM's line 0.4% and 5.6% (docs/theory/bearing_housing.md).
    """
    b, geo, infl = setup
    p = lpm.LPMParameters.from_config(b, faulty)
    dt = b["time_step_s"]
    h = dt / b["substeps"]
    n_out = 150
    t_out = dt * np.arange(n_out)
    res = lpm.simulate_lpm(p, -0.02 - dt, int(np.ceil((t_out[-1] + dt + 0.02 + dt) / h)), h)
    q = lpm.resample_loads(res.time_s, res.load_N, t_out, dt, "average")
    # the reference averages Q_j g(psi_j) over each step, as the housing stage does through its patch loads
    fine_f = np.sum(res.load_N * infl(res.psi_rad), 1)
    ref = lpm.resample_loads(res.time_s, fine_f[:, None], t_out, dt, "average")[:, 0]
    assert q.shape == (n_out, geo.n_rollers)
    s = sg.Surrogate(geo, infl)
    op = sg.Operating(b["radial_load_N"], b["radial_clearance_m"])
    drop, key = None, None
    if faulty:
        (d,) = p.defects  # the LPM's groove on the concave outer raceway
        drop, key = (lambda psi: sg.outer_race_drop(psi, d.angle_rad, d.width_m, geo)), d
    ph = sg.cage_phase(t_out, p.shaft_speed_Hz, geo, p.start_angle_rad)
    got = s.box_average(sg.phase_edges(ph), op, drop, key)
    err = np.std(got - ref) / np.std(ref)
    assert err < tol, err


@pytest.mark.parametrize("method", ["compiled", "numpy"])
def test_shaft_on_one_roller_off_the_load_line_is_solved(setup, method):
    """Wide clearance, one roller 4 urad off the load line: the shaft has no stiffness across that roller, the
    potential is linear along it, and the shaft slides to the next roller (3.7 um here), which takes the
    sideways force (F_r sin psi / sin pitch = 4 mN). Both force balances hold to the tolerance."""
    _, geo, _ = setup
    k = lpm.line_contact_stiffness(geo.roller_length_m)
    psi = 4.3e-6 + geo.roller_pitch_rad * np.arange(geo.n_rollers)
    q = sg.quasi_static_loads(psi[None], 0.0, 505.0, 34e-6, k, 1e-12, method=method)[0]
    assert np.count_nonzero(q) == 2
    assert abs(np.sum(q * np.cos(psi)) - 505.0) < 1e-11 * 505.0
    assert abs(np.sum(q * np.sin(psi))) < 1e-11 * 505.0
    expected = 505.0 * np.sin(4.3e-6) / np.sin(geo.roller_pitch_rad)
    assert np.sort(q)[-2] == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("load_N, clearance_m", [(11.8, 20e-6), (13.9, 134e-6), (16.0, 192e-6), (500.0, 40e-6),
                                                  (500.0, -8e-6), (232.8, -19.2e-6)])
def test_healthy_table_has_an_equilibrium_at_light_loads_wide_clearances_and_preloads(setup, load_N, clearance_m):
    """Light loads with any clearance put the shaft on one roller a few microradians off the load line at a few
    table phases, where the contact stiffness has nothing across that roller (a regularised Newton step creeps
    12 nm where the shaft slides 3 um); a preload deeper than a roller's deflection under the load (clearance
    below -6.8 um at 500 N) has its equilibrium within a deflection of the centre. Every phase of the table
    balances the load, from the cold start and from a nearby table's offsets."""
    _, geo, infl = setup
    s = sg.Surrogate(geo, infl)
    for scale in (1.0, 1.004):
        t = s.table(sg.Operating(load_N * scale, clearance_m * scale))
        psi = s.roller_angles(t.phase)
        q = sg.quasi_static_loads(psi, 0.0, load_N * scale, 0.5 * clearance_m * scale, s.k_contact, 1e-12,
                                  e0_m=t.offset)
        assert np.all(np.abs(np.sum(q * np.cos(psi), 1) - load_N * scale) < 1e-9 * load_N)


def test_groove_aligned_table_equals_a_fine_uniform_one(setup):
    """The outer groove's table on nodes aligned with the groove against a uniform grid 16 times finer
    than the healthy table (the drop as a plain function): box averages of a record agree to 1e-4 of
    the groove's dip (the uniform grid's own error, its kinks off the grid: 4e-5 for the 0.1 mm groove),
    for a narrow, a medium and a wide groove."""
    b, geo, infl = setup
    op = sg.Operating(500.0, b["radial_clearance_m"])
    t = np.arange(2000) / 2550.0
    edges = sg.phase_edges(sg.cage_phase(t, 1000 / 60, geo, 0.3))
    healthy = sg.Surrogate(geo, infl).box_average(edges, op)
    for width, angle in ((0.1e-3, 0.05), (0.6e-3, 0.15), (3e-3, -0.5)):
        groove = sg.OuterGroove(angle, width, geo)
        aligned = sg.Surrogate(geo, infl).box_average(edges, op, groove, groove.key)
        uniform = sg.Surrogate(geo, infl).box_average(edges, op, lambda psi, g=groove: g(psi), ("plain", width, angle))
        dip = np.abs(uniform - healthy).max()
        assert dip > 0
        assert np.abs(aligned - uniform).max() < 1e-4 * dip, (width, np.abs(aligned - uniform).max() / dip)


def test_compiled_equilibrium_matches_the_numpy_loop(setup):
    """The numba kernel runs the numpy reference's Newton iteration row by row: the same loads to 1e-12 of F_r
    and offsets to 1e-9 of the largest offset (measured: 1.5e-15 of F_r; the C library's pow and hypot against
    numpy's SIMD ones, which differ by CPU), from the cold start and from given starts, with grooves and
    rollers lifted."""
    _, geo, _ = setup
    k = lpm.line_contact_stiffness(geo.roller_length_m)
    rng = np.random.default_rng(5)
    z = geo.n_rollers
    for tol in (1e-12, 1e-9, 1e-7):
        n = 300
        psi = rng.uniform(0, 2 * np.pi, n)[:, None] + geo.roller_pitch_rad * np.arange(z)
        drop = np.where(rng.random((n, z)) < 0.15, rng.uniform(0, 30e-6, (n, z)), 0.0)
        f_r, gap = rng.uniform(100.0, 3000.0), rng.uniform(5e-6, 40e-6)
        qn, en = sg.quasi_static_loads(psi, drop, f_r, gap, k, tol, return_offset=True, method="numpy")
        qc, ec = sg.quasi_static_loads(psi, drop, f_r, gap, k, tol, return_offset=True)
        assert np.abs(qc - qn).max() < 1e-12 * f_r
        assert np.abs(ec - en).max() < 1e-9 * np.abs(en).max()
        # from given starts (a table's offsets next to a defect's)
        e0 = en + rng.normal(0, 1e-6, en.shape)
        qn = sg.quasi_static_loads(psi, drop, f_r, gap, k, tol, e0_m=e0, method="numpy")
        qc = sg.quasi_static_loads(psi, drop, f_r, gap, k, tol, e0_m=e0)
        assert np.abs(qc - qn).max() < 1e-12 * f_r
    with pytest.raises(ValueError, match="method"):
        sg.quasi_static_loads(psi, 0.0, 500.0, gap, k, method="fortran")
