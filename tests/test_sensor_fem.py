"""Verification of the sensor FEM (sfepy matrices, scipy solves) against closed forms and the RC model."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.constants import epsilon_0

from piezobearing.sensor import fem
from piezobearing.sensor.calibration import SensorCircuit, frequency_response
from piezobearing.sensor.materials import ALUMINA, StressChargeForm, paper_pzt, stress_charge_form
from piezobearing.sensor.mesh import StackGeometry, cross_section, cylinder_mesh, hex_volumes, stack_mesh

PZT = paper_pzt()
MATS = fem.StackMaterials(stress_charge_form(PZT), 7700.0, ALUMINA)
GEO = StackGeometry(bottom_disk_diameter_m=5e-3, top_disk_diameter_m=3e-3)


@pytest.fixture(scope="module")
def stack():
    """The coarse stack (multiplier 1), SS family, assembled once."""
    asm = fem.assemble(stack_mesh(GEO, level=1.0), MATS, order=2)
    return asm, fem.reduce(asm, fem.stack_conditions(GEO.z_interfaces_m, "SS"))


def test_mesh_volumes_are_the_disks_volumes():
    """Area-preserving polygon radii: each disk's meshed volume is pi r^2 h (quarter)."""
    for level in (0.5, 1.0, 2.0):
        m = stack_mesh(GEO, level=level)
        v = hex_volumes(m)
        assert v.min() > 0
        for gid, d, h in ((1, 5e-3, 1e-3), (2, 4.7e-3, 3.4e-3), (3, 3e-3, 1e-3)):
            assert v[m.groups == gid].sum() == pytest.approx(np.pi * d**2 / 4 * h / 4, rel=1e-12)


def test_free_pzt_disk_reproduces_eq3_and_free_capacitance():
    """Free disk, uniform axial load: V = h d33 F / (eps33^T A) and C = eps33^T A / h within 0.5%."""
    r, h = 2.35e-3, 3.4e-3
    asm = fem.assemble(cylinder_mesh(r, h, n_core=2, n_ring=2, n_layers=3), MATS, order=2, load_face="top")
    bc = fem.BoundaryConditions("SS", (("bottom", (2,)),), hot_z_m=0.0, ground_z_m=h)
    rs = fem.reduce(asm, bc)
    circ = SensorCircuit(pzt_diameter_m=2 * r, pzt_height_m=h)
    v_eq3 = h * 400e-12 * 1.0 / (1800 * epsilon_0 * np.pi * r**2)
    assert circ.free_disk_gain_V_per_N == pytest.approx(v_eq3, rel=1e-12)
    assert rs.static_open_voltage_V() == pytest.approx(v_eq3, rel=5e-3)
    c_free = rs.static_capacitance_F / fem.SECTOR_FRACTION
    assert c_free == pytest.approx(circ.pzt_capacitance_F, rel=5e-3)
    # Short circuit: the charge per newton is d33 itself; the blocked capacitance is eps33^S A / h.
    assert float(rs.b @ rs.ks_inv_f) / fem.SECTOR_FRACTION == pytest.approx(400e-12, rel=5e-3)
    assert rs.c0 / fem.SECTOR_FRACTION < c_free


def test_load_vector_is_the_consistent_uniform_traction(stack):
    """sfepy's facet load against independent integrals of 1, x, x^2, xy, y^2 over the polygonal face."""
    asm, _ = stack
    f = asm.load.reshape(-1, 3)
    assert f[:, :2] == pytest.approx(0.0, abs=1e-15)
    assert f[:, 2].sum() == pytest.approx(fem.SECTOR_FRACTION, rel=1e-12)
    bottom = asm.u_coors[:, 2] < 1e-12
    assert np.all(f[~bottom, 2] == 0)
    # Independent face integrals on the O-grid quads (bilinear map, 3x3 Gauss).
    r_b = GEO.bottom_disk_diameter_m / 2
    pts, quads, qrad = cross_section(sorted(GEO.radii_m), 2, [2, 2, 1], 3.0, [1.5e-3, 2.35e-3])
    quads = quads[qrad <= r_b * (1 + 1e-9)]
    g, w = np.polynomial.legendre.leggauss(3)
    moments = {k: 0.0 for k in ("1", "x", "xx", "xy", "yy")}
    for q in quads:
        xy = pts[q]
        for a, wa in zip(g, w, strict=True):
            for b, wb in zip(g, w, strict=True):
                n = 0.25 * np.array(
                    [(1 - a) * (1 - b), (1 + a) * (1 - b), (1 + a) * (1 + b), (1 - a) * (1 + b)]
                )
                dn = 0.25 * np.array(
                    [[-(1 - b), -(1 - a)], [(1 - b), -(1 + a)], [(1 + b), (1 + a)], [-(1 + b), (1 - a)]]
                )
                x, y = n @ xy
                jac = abs(np.linalg.det(xy.T @ dn)) * wa * wb
                for k, val in (("1", 1), ("x", x), ("xx", x * x), ("xy", x * y), ("yy", y * y)):
                    moments[k] += val * jac
    area = moments["1"]
    assert area == pytest.approx(np.pi * r_b**2 / 4, rel=1e-12)
    x, y = asm.u_coors[:, 0], asm.u_coors[:, 1]
    for k, field in (("x", x), ("xx", x * x), ("xy", x * y), ("yy", y * y)):
        assert f[:, 2] @ field == pytest.approx(fem.SECTOR_FRACTION * moments[k] / area, rel=1e-9)


def test_clamped_free_rod_first_longitudinal_frequency():
    """Slender alumina rod, top clamped: f1 = sqrt(E / rho) / (4 L) within 0.5%."""
    r, length = 0.5e-3, 10e-3
    inert = StressChargeForm(ALUMINA.stiffness_voigt(), np.zeros((3, 6)), 1e-9 * np.eye(3))
    mats = fem.StackMaterials(inert, ALUMINA.density_kg_per_m3, ALUMINA)
    asm = fem.assemble(cylinder_mesh(r, length, n_core=1, n_ring=1, n_layers=16), mats, order=2)
    rs = fem.reduce(asm, fem.BoundaryConditions("SS", (("top", (0, 1, 2)),), hot_z_m=0.0, ground_z_m=length))
    m = fem.modes(rs, 3, "short")
    labels = [fem.label_mode(rs, m.shapes[:, k])[0] for k in range(3)]
    f1 = m.frequency_Hz[labels.index("axial")]
    exact = np.sqrt(ALUMINA.young_Pa / ALUMINA.density_kg_per_m3) / (4 * length)
    assert f1 == pytest.approx(exact, rel=5e-3)


def test_reduced_harmonic_model_matches_direct_solves(stack):
    """Modal reduction + rank-one circuit update against direct complex solves (undamped). The full system is
    factorised once per frequency for both circuits (``direct_voltages_per_force``: the open circuit from the
    measuring circuit's factors by the exact Sherman-Morrison update of the electrode's entry; equal to a
    factorisation per circuit to 4.4e-15 relative, benchmarks/bench_sensor_fem.py)."""
    _, rs = stack
    model = fem.reduced_model(rs, fem.modes(rs, 12, "short"), damping_ratio=0.0)
    circuit = fem.MeasuringCircuit(50e6, 180e-12)
    for f in (1.0, 30.0, 1e3, 4.5e4, 1.0e5, 1.3e5):
        for c, direct in zip((circuit, None), fem.direct_voltages_per_force(rs, f, [circuit, None]), strict=True):
            assert model.voltage_per_force(f, c)[0] == pytest.approx(direct, rel=1e-5)


def test_low_frequency_response_is_the_rc_model(stack):
    """Below 1 kHz the FEM with the circuit is the calibration's RC model with the FEM's d33_eff and C.

    With the paper's d33 and Cp (calibration stage) it agrees within 8%: the stack's effective charge
    constant is 370 pC/N (the alumina disks restrain the PZT faces) and its capacitance 77 pF (vs 81 pF).
    """
    _, rs = stack
    model = fem.reduced_model(rs, fem.modes(rs, 12, "short"), damping_ratio=0.0)
    r, c_cable = 50e6, 180e-12
    f = np.geomspace(0.1, 1e3, 30)
    h_fem = model.voltage_per_force(f, fem.MeasuringCircuit(r, c_cable))
    c_total = model.static_capacitance_F + c_cable
    jwt = 2j * np.pi * f * r * c_total
    h_rc_fem = model.charge_per_force_C_per_N / c_total * jwt / (1 + jwt)
    np.testing.assert_allclose(h_fem, h_rc_fem, rtol=2e-4)
    h_rc = frequency_response(f, SensorCircuit(resistance_ohm=r))
    np.testing.assert_allclose(np.abs(h_fem), np.abs(h_rc), rtol=0.08)
    assert np.abs(np.angle(h_fem) - np.angle(h_rc)).max() < np.radians(1.0)


def test_symmetry_families(stack):
    """SA and AS are mirror images (same frequencies); only the SS family couples to the electrode."""
    asm, rs_ss = stack
    fa = {}
    for fam in ("SA", "AS", "AA"):
        rs = fem.reduce(asm, fem.stack_conditions(GEO.z_interfaces_m, fam))
        assert not rs.electrode_active
        fa[fam] = fem.modes(rs, 3, "short").frequency_Hz
        np.testing.assert_allclose(fem.modes(rs, 3, "open").frequency_Hz, fa[fam], rtol=1e-9)
    np.testing.assert_allclose(fa["SA"], fa["AS"], rtol=1e-7)
    short = fem.modes(rs_ss, 2, "short").frequency_Hz
    opened = fem.modes(rs_ss, 2, "open").frequency_Hz
    assert opened[0] > 1.1 * short[0]


def test_modes_are_bit_identical_from_call_to_call(stack):
    """Fixed ARPACK start vector and sign convention: the same system gives the same bits (reproducible runs)."""
    asm, _ = stack
    # two new systems (one answers repeated requests from its own earlier solve): each solved anew
    rs, again = (fem.reduce(asm, fem.stack_conditions(GEO.z_interfaces_m, "SS")) for _ in range(2))
    for circuit in ("short", "open"):
        a, b = fem.modes(rs, 4, circuit), fem.modes(again, 4, circuit)
        assert np.array_equal(a.frequency_Hz, b.frequency_Hz)
        assert np.array_equal(a.shapes, b.shapes)
        cols = np.arange(a.shapes.shape[1])
        assert np.all(a.shapes[np.abs(a.shapes).argmax(axis=0), cols] > 0)
        np.testing.assert_allclose(a.shapes.T @ (rs.M @ a.shapes), np.eye(len(cols)), atol=1e-8)


def test_paper_placement_gives_the_papers_first_resonance(stack):
    """The first axial mode with the 3 mm disk clamped is within 2% of the paper's 121 kHz (coarse mesh)."""
    _, rs = stack
    m = fem.modes(rs, 3, "short")
    labels = [fem.label_mode(rs, m.shapes[:, k])[0] for k in range(3)]
    assert labels[0] == "axial"
    assert m.frequency_Hz[0] == pytest.approx(1.21e5, rel=0.02)


def test_fewer_modes_come_from_the_larger_solve_and_agree_with_their_own_solve(stack):
    """A system answers a request for fewer modes than it solved already from that solve (sensor_modal asks its SS
    system for 8, 5, 12, 3 and 2 modes): the lowest n of a larger shift-invert solve are the n lowest modes, the
    same as a solve for n alone to ARPACK's tolerance."""
    asm, _ = stack
    conditions = fem.stack_conditions(GEO.z_interfaces_m, "SS")
    for circuit in ("short", "open"):
        rs = fem.reduce(asm, conditions)
        big = fem.modes(rs, 6, circuit)
        small = fem.modes(rs, 3, circuit)  # from the 6-mode solve
        alone = fem.modes(fem.reduce(asm, conditions), 3, circuit)
        assert np.array_equal(small.frequency_Hz, big.frequency_Hz[:3])
        np.testing.assert_allclose(small.frequency_Hz, alone.frequency_Hz, rtol=1e-9)
        np.testing.assert_allclose(np.abs(small.shapes.T @ (rs.M @ alone.shapes)), np.eye(3), atol=1e-6)
