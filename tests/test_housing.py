"""Housing mesh and transient FEM: load vectors, assembly, conditions, modes, reduced vs direct solution."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from piezobearing.bearing import lpm
from piezobearing.housing import fem as housing_fem
from piezobearing.housing import transient
from piezobearing.housing.mesh import (
    GROUP_HOUSING,
    GROUP_RING,
    build_housing_mesh,
    mesh_quality,
    nested_dissection_order,
)
from piezobearing.sensor.materials import ALUMINA, CAST_IRON, STEEL, paper_pzt

LEVEL = 0.35  # a coarse mesh: a few thousand DOFs


@pytest.fixture(scope="module")
def geo(paper_config):
    return transient.housing_geometry(paper_config)


@pytest.fixture(scope="module")
def meshes(geo):
    return {case: build_housing_mesh(geo, case == "faulty", LEVEL) for case in ("healthy", "faulty")}


@pytest.fixture(scope="module")
def model(meshes, paper_config):
    return transient.make_model(meshes["healthy"], paper_config)


def _hex_volumes(m):
    """Volumes of the hexahedra by 2x2x2 Gauss quadrature of the trilinear map."""
    p = m.coors[m.conn]
    ref = np.array(
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]]
    )
    g = 1 / np.sqrt(3)
    vol = np.zeros(len(p))
    for a in (-g, g):
        for b in (-g, g):
            for c in (-g, g):
                xi = np.array([a, b, c])
                dn = np.empty((8, 3))
                for k in range(3):
                    others = [i for i in range(3) if i != k]
                    dn[:, k] = ref[:, k] / 8 * np.prod(1 + ref[:, others] * xi[others], axis=1)
                jac = np.einsum("eni,nk->eik", p, dn)
                vol += np.linalg.det(jac)
    return vol


# --- consistent loads -------------------------------------------------------------------


def test_box_weights_reproduce_linear_fields():
    rng = np.random.default_rng(1)
    nodes = np.sort(rng.uniform(0, 10, 30))
    lo = np.array([2.0, 5.5, 7.0])
    hi = np.array([2.3, 5.5, 9.1])
    w = housing_fem.box_weights(nodes, lo, hi)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(w @ nodes, 0.5 * (lo + hi), rtol=1e-12)  # the load's centre
    # a point load is the linear interpolation
    k = np.searchsorted(nodes, 5.5)
    lam = (5.5 - nodes[k - 1]) / (nodes[k] - nodes[k - 1])
    assert w[1, k - 1] == pytest.approx(1 - lam) and w[1, k] == pytest.approx(lam)


def test_box_weights_periodic_wrap():
    period = 2 * np.pi
    nodes = np.linspace(-np.pi, np.pi, 40, endpoint=False)
    w = housing_fem.box_weights(nodes, np.array([np.pi - 0.05]), np.array([np.pi + 0.05]), period=period)[0]
    assert w.sum() == pytest.approx(1.0)
    assert w[0] > 0 and w[-1] > 0  # straddles the seam at +-pi


def test_roller_load_vector_resultant(model):
    """The nodal forces of a roller load Q at psi add up to Q/2 n(psi) in the half model."""
    for psi in (0.0, 0.3, -2.0):
        wy, wz = model.column_loads(np.array([[400.0]]), np.array([[psi]]))
        f = np.zeros(3 * model.mesh.n_nodes)
        f[model.free] = model.load_vectors(wy, wz)[0]
        assert f[1::3].sum() == pytest.approx(200 * np.sin(psi), abs=1e-9)
        assert f[2::3].sum() == pytest.approx(-200 * np.cos(psi), abs=1e-9)


# --- mesh --------------------------------------------------------------------------------


def test_mesh_is_valid_and_holds_the_hole(meshes, geo):
    for m in meshes.values():
        q = mesh_quality(m)
        assert q["min_scaled_jacobian"] > 0.3
        cen = m.coors[m.conn].mean(axis=1)
        a = geo.hole_half_side_m
        in_hole = (np.abs(cen[:, 1]) < a) & (cen[:, 0] < a) & (cen[:, 2] < -geo.ring_outer_radius_m)
        assert not in_hole.any()
        ring = m.group == GROUP_RING
        r = np.hypot(cen[ring, 1], cen[ring, 2])
        assert r.min() > geo.raceway_radius_m and r.max() < geo.ring_outer_radius_m
        assert cen[ring, 0].max() < geo.ring_half_width_m
        assert set(np.unique(m.group)) == {GROUP_RING, GROUP_HOUSING}


def test_defect_removes_its_volume(meshes, geo):
    vh, vf = _hex_volumes(meshes["healthy"]).sum(), _hex_volumes(meshes["faulty"]).sum()
    # a groove w wide (at the raceway), h deep, across half the ring's width
    r0, r1 = geo.raceway_radius_m, geo.raceway_radius_m + geo.defect_depth_m
    expect = geo.defect_half_angle_rad * (r1**2 - r0**2) * geo.ring_half_width_m
    assert vh - vf == pytest.approx(expect, rel=1e-6)
    assert expect == pytest.approx(geo.defect_width_m * geo.defect_depth_m * geo.ring_half_width_m, rel=0.02)


def test_every_outer_race_groove_is_cut(paper_config):
    """Two outer-race grooves (and an inner-race defect, which the ring does not see): both volumes removed."""
    b = dict(paper_config["bearing"])
    b["defects"] = [
        {"type": "outer_race", "width_m": 0.9e-3, "depth_m": 1.0e-3, "angle_deg": 0.0},
        {"type": "inner_race", "width_m": 0.9e-3, "depth_m": 1.0e-3, "angle_deg": 30.0},
        {"type": "outer_race", "width_m": 0.6e-3, "depth_m": 0.5e-3, "angle_deg": 170.0},
    ]
    g = transient.housing_geometry(dict(paper_config, bearing=b))
    assert len(g.grooves) == 2
    vh = _hex_volumes(build_housing_mesh(g, False, LEVEL)).sum()
    m = build_housing_mesh(g, True, LEVEL)
    r0 = g.raceway_radius_m
    expect = sum(0.5 * w / r0 * ((r0 + h) ** 2 - r0**2) * g.ring_half_width_m for _, w, h in g.grooves)
    assert vh - _hex_volumes(m).sum() == pytest.approx(expect, rel=1e-6)
    assert mesh_quality(m)["min_scaled_jacobian"] > 0
    # the raceway loses its columns inside each groove, nowhere else
    for a, w, _ in g.grooves:
        gap = np.abs(np.angle(np.exp(1j * (m.raceway_psi - a))))
        assert gap.min() == pytest.approx(0.5 * w / r0, rel=1e-6)


def test_nested_dissection_is_a_permutation(meshes):
    m = meshes["healthy"]
    order = nested_dissection_order(m)
    np.testing.assert_array_equal(np.sort(order), np.arange(m.n_nodes))


# --- assembly and the model -----------------------------------------------------------------


def test_assembly_mass_and_rigid_motion(meshes):
    m = meshes["healthy"]
    k, mm = housing_fem.assemble_matrices(m, STEEL, CAST_IRON)
    vol = _hex_volumes(m)
    rho = np.where(m.group == GROUP_RING, STEEL.density_kg_per_m3, CAST_IRON.density_kg_per_m3)
    assert mm[0::3][:, 0::3].sum() == pytest.approx(rho @ vol, rel=1e-9)
    for c in range(3):
        u = np.zeros(3 * m.n_nodes)
        u[c::3] = 1e-6
        assert np.abs(k @ u).max() < 1e-9 * np.abs(k).max() * 1e-6
    rot = np.zeros((m.n_nodes, 3))  # small rotation about x
    rot[:, 1], rot[:, 2] = -m.coors[:, 2], m.coors[:, 1]
    assert np.abs(k @ rot.ravel()).max() < 1e-8 * np.abs(k).max()


def test_sensor_stiffness_closed_form():
    pzt = paper_pzt()
    k_open = housing_fem.sensor_stiffness(pzt, 4.7e-3, 3.4e-3, ALUMINA, 3e-3, 1e-3, "open")
    k_short = housing_fem.sensor_stiffness(pzt, 4.7e-3, 3.4e-3, ALUMINA, 3e-3, 1e-3, "short")
    s33 = np.linalg.inv(pzt.c_E_Pa)[2, 2]
    a_pzt, a_tip = np.pi * 4.7e-3**2 / 4, np.pi * 3e-3**2 / 4
    expect = 1 / (1e-3 / (330e9 * a_tip) + 3.4e-3 * s33 / a_pzt)
    assert k_short == pytest.approx(expect, rel=1e-12)
    k33sq = pzt.d33_C_per_N**2 / (s33 * pzt.eps33_T_F_per_m)
    assert 0.4 < k33sq < 0.8  # APC 850 coupling
    assert k_open > k_short
    with pytest.raises(ValueError, match="sensor_electrical"):
        housing_fem.pzt_axial_modulus(pzt, "floating")


def test_static_balance_and_influence_line(model):
    """Reactions balance the load; the sensor takes part of a roller load over it and little far away."""
    wy, wz = model.column_loads(np.array([[500.0]]), np.array([[0.0]]))
    f = model.load_vectors(wy, wz)[0]
    u = model.factor().solve(f)
    np.testing.assert_allclose(model.K @ u, f, atol=1e-9 * np.abs(f).max())
    sensor = model.sensor @ u
    gy, gz, radial = model.influence_line()
    w0 = model.patch_weights(np.array([0.0]))[0]
    assert sensor == pytest.approx(
        -500 * (w0 @ gz), rel=1e-9
    )  # reciprocity: one solve gives every load position
    g0 = float(w0 @ radial)
    assert 0.05 < g0 < 0.9
    far = np.abs(model.mesh.raceway_psi) > np.pi / 2
    assert np.abs(radial[far]).max() < 0.05 * g0
    # the healthy model is symmetric about the load line
    psi = model.mesh.raceway_psi
    mirror = np.interp(-psi, psi, radial, period=2 * np.pi)
    np.testing.assert_allclose(radial, mirror, atol=0.02 * g0)


def test_modes_are_mass_normalised_and_above_nyquist(model):
    modes = housing_fem.compute_modes(model, 4)
    phi = modes.shapes
    np.testing.assert_allclose(phi.T @ (model.M @ phi), np.eye(4), atol=1e-8)
    np.testing.assert_allclose(np.einsum("ij,ij->j", phi, model.K @ phi), modes.omega_rad_s**2, rtol=1e-6)
    assert modes.frequencies_Hz[0] > 1275.0  # the paper's Nyquist frequency


def test_exact_modal_step_against_closed_form():
    """A single mode under a ramp load: the recurrence reproduces the analytic response."""
    w, z, h = 2 * np.pi * 300.0, 0.05, 1e-4
    n = 200
    t = h * np.arange(n)
    f = 1e3 * t  # ramp from rest at static equilibrium (f0 = 0)
    q = housing_fem.modal_response(f[:, None], np.array([w]), np.array([z]), h)[:, 0]
    wd = w * np.sqrt(1 - z * z)
    # q'' + 2 z w q' + w^2 q = a t, q(0) = q'(0) = 0
    a = 1e3
    qp = a / w**2 * (t - 2 * z / w)
    c1 = 2 * z * a / w**3
    c2 = (-a / w**2 + z * w * c1) / wd
    exact = qp + np.exp(-z * w * t) * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t))
    np.testing.assert_allclose(q, exact, atol=1e-9 * np.abs(exact).max())


def test_compiled_modal_recurrence_against_the_loop():
    """The compiled recurrence gives the numbers of the step written with numpy (its einsum form)."""
    rng = np.random.default_rng(2)
    n, nt, h = 7, 400, 1 / 51200
    omega = 2 * np.pi * np.sort(rng.uniform(3e3, 4e4, n))
    zeta = rng.uniform(0.01, 0.05, n)
    f = 100.0 * rng.standard_normal((nt, n))
    a_mat, b_mat = housing_fem._ramp_recurrence(omega, zeta, h)
    x = np.stack([f[0] / omega**2, np.zeros(n)], axis=1)
    q_ref, qd_ref = np.empty((nt, n)), np.zeros((nt, n))
    q_ref[0] = x[:, 0]
    for k in range(nt - 1):
        x = np.einsum("nij,nj->ni", a_mat, x) + np.einsum("nij,nj->ni", b_mat, np.stack([f[k], f[k + 1]], 1))
        q_ref[k + 1], qd_ref[k + 1] = x[:, 0], x[:, 1]
    q, qd = housing_fem.modal_response(f, omega, zeta, h, velocity=True)
    np.testing.assert_allclose(q, q_ref, rtol=1e-12, atol=1e-12 * np.abs(q_ref).max())
    np.testing.assert_allclose(qd, qd_ref, rtol=1e-12, atol=1e-12 * np.abs(qd_ref).max())


def test_reduced_agrees_with_sfepy_direct(paper_config, meshes):
    """Modes + static correction against sfepy's generalized-alpha on the same loads (healthy and faulty)."""
    b = paper_config["bearing"]
    h = paper_config["housing"]
    dt = b["time_step_s"]
    for case in ("healthy", "faulty"):
        p = lpm.LPMParameters.from_config(b, case == "faulty")
        t_out = dt * np.arange(60)
        res = lpm.simulate_lpm(replace(p), -dt, int(62 * b["substeps"]), dt / b["substeps"])
        q = lpm.resample_loads(res.time_s, res.load_N, t_out, dt)
        m = transient.make_model(meshes[case], paper_config)
        wy, wz = m.column_loads(q, p.roller_angles(t_out))
        alpha, beta = housing_fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])
        red = housing_fem.sensor_force_reduced(
            housing_fem.reduced_operators(m, housing_fem.compute_modes(m, 8), alpha, beta), wy, wz, dt
        )
        d = housing_fem.sensor_force_direct(m, wy, wz, dt, alpha, beta, h["rho_inf"])
        rms = np.sqrt(np.mean((d["force_N"] - red["force_N"]) ** 2)) / np.sqrt(np.mean(red["force_N"] ** 2))
        assert rms < 0.01, case
