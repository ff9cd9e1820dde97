"""The piezoceramic library: 6mm symmetry of every entry, and closed forms per material in the FEM.

For each ceramic: a free disk under a uniform axial load gives Eq. 3, V = h d33 F / (eps33^T A), and the
free capacitance eps33^T A / h. A slender rod of length L poled along its axis, electrodes on its ends,
one end on a mirror plane (u_z = 0, free to contract: half of a free-free rod of length 2L): D3 is
uniform along it, so open circuit is D = 0 and f_a = 1 / (4 L sqrt(rho s33^D)), s33^D = s33^E (1 - k33^2);
shorted, the first resonance f_r solves IEEE Std 176-1987's length-extensional relation
k33^2 = (pi/2)(f_r/f_a) tan((pi/2)(f_a - f_r)/f_a). All within 0.5%.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from piezobearing.sensor import fem
from piezobearing.sensor.materials import (
    ALUMINA,
    PIEZO_MATERIALS,
    paper_pzt,
    piezo_material,
    pzt_from_config,
    stress_charge_form,
    symmetry_report,
)
from piezobearing.sensor.mesh import cylinder_mesh

KEYS = sorted(PIEZO_MATERIALS)


def test_library_has_the_ceramics_the_design_needs_with_sources():
    assert {"apc850_paper", "pzt5a", "pzt4", "pzt8", "pzt5h"} <= set(KEYS)
    for key in KEYS:
        m = PIEZO_MATERIALS[key]
        assert m.source, key
        assert m.quality_factor_source, key
        assert 7000 < m.density_kg_per_m3 < 8000
    with pytest.raises(KeyError, match="known"):
        piezo_material("apc851")


@pytest.mark.parametrize("key", KEYS)
def test_every_ceramic_has_6mm_symmetry(key):
    rep = symmetry_report(piezo_material(key))
    assert all(v["holds"] for v in rep.values()), {k: v for k, v in rep.items() if not v["holds"]}


def test_symmetry_check_finds_the_papers_c66_typo():
    rep = symmetry_report(paper_pzt(c66_rule="paper"))
    assert [k for k, v in rep.items() if not v["holds"]] == ["c66=(c11-c12)/2"]


def test_hard_and_soft_order_of_the_charge_constant_and_permittivity():
    """Soft PZT-5H > PZT-5A ~ APC 850 > hard PZT-4 > PZT-8 in d33 and eps33^T (the Navy types' ranking)."""
    d33 = {k: piezo_material(k).d33_C_per_N for k in KEYS}
    eps = {k: piezo_material(k).eps33_T_F_per_m for k in KEYS}
    assert d33["pzt5h"] > d33["apc850_paper"] > d33["pzt4"] > d33["pzt8"]
    assert eps["pzt5h"] > eps["pzt5a"] > eps["pzt4"] > eps["pzt8"]


def test_config_picks_the_material_and_overrides_only_what_is_set(paper_config):
    s = {**paper_config["sensor"], "material": "pzt4", "d33_C_per_N": None, "eps33_T_rel": None}
    s["pzt_density_kg_per_m3"] = None
    assert pzt_from_config(s).d33_C_per_N == PIEZO_MATERIALS["pzt4"].d33_C_per_N
    assert pzt_from_config(s).density_kg_per_m3 == 7500.0
    s["d33_C_per_N"] = 300e-12
    pzt = pzt_from_config(s)
    assert pzt.d33_C_per_N == 300e-12 and pzt.d_C_per_N[2, 0] == PIEZO_MATERIALS["pzt4"].d_C_per_N[2, 0]


def test_hard_ceramics_have_the_larger_mechanical_q():
    """Hard PZT-8 > PZT-4 (acceptor-doped, low loss) >> soft PZT-5A ~ APC 850 > PZT-5H (the Navy types' ranking)."""
    q = {k: piezo_material(k).mechanical_quality_factor for k in KEYS}
    assert q["pzt8"] > q["pzt4"] > 5 * q["apc850_paper"]
    assert q["apc850_paper"] >= q["pzt5a"] > q["pzt5h"]


@pytest.mark.parametrize("key", KEYS)
def test_the_fems_damping_is_the_ceramics_own_q_unless_the_config_sets_one(paper_config, key):
    """sensor_fem.mechanical_quality_factor null (the paper config): damping ratio 1/(2 Qm) of the ceramic;
    a number replaces it for every ceramic. The paper's design keeps exactly the 1/160 of its former Qm = 80."""
    import copy

    from piezobearing.sensor.analysis import SensorFemParams

    cfg = copy.deepcopy(paper_config)
    cfg["sensor"]["material"] = key
    assert cfg["sensor_fem"]["mechanical_quality_factor"] is None
    zeta = SensorFemParams.from_config(cfg).damping_ratio
    assert zeta == 1.0 / (2.0 * piezo_material(key).mechanical_quality_factor)
    if key == "apc850_paper":
        assert zeta == 1.0 / 160.0
    cfg["sensor_fem"]["mechanical_quality_factor"] = 40.0
    assert SensorFemParams.from_config(cfg).damping_ratio == 1.0 / 80.0


def _mats(key):
    pzt = piezo_material(key)
    return pzt, fem.StackMaterials(stress_charge_form(pzt), pzt.density_kg_per_m3, ALUMINA)


@pytest.mark.parametrize("key", KEYS)
def test_free_disk_static_sensitivity_and_capacitance(key):
    """Free disk (only the bottom face held axially), uniform 1 N: Eq. 3 and eps33^T A / h within 0.5%."""
    pzt, mats = _mats(key)
    r, h = 2.35e-3, 3.4e-3
    asm = fem.assemble(cylinder_mesh(r, h, n_core=2, n_ring=2, n_layers=3), mats, order=2, load_face="top")
    rs = fem.reduce(asm, fem.BoundaryConditions("SS", (("bottom", (2,)),), hot_z_m=0.0, ground_z_m=h))
    area = np.pi * r**2
    v_eq3 = h * pzt.d33_C_per_N / (pzt.eps33_T_F_per_m * area)
    assert rs.static_open_voltage_V() == pytest.approx(v_eq3, rel=5e-3)
    assert rs.static_capacitance_F / fem.SECTOR_FRACTION == pytest.approx(
        pzt.eps33_T_F_per_m * area / h, rel=5e-3
    )


def rod_frequencies_Hz(pzt, length_m: float) -> tuple[float, float]:
    """(f_r shorted, f_a open) of the first length-extensional mode of a 33 rod, one end on a mirror plane."""
    s33_e = np.linalg.inv(pzt.c_E_Pa)[2, 2]
    k2 = pzt.d33_C_per_N**2 / (s33_e * pzt.eps33_T_F_per_m)
    f_a = 1 / (4 * length_m * np.sqrt(pzt.density_kg_per_m3 * s33_e * (1 - k2)))
    x = brentq(lambda x: np.pi / 2 * x * np.tan(np.pi / 2 * (1 - x)) - k2, 1e-9, 1 - 1e-12)
    return x * f_a, f_a


def test_rod_closed_form_limits():
    """No coupling: f_r = f_a = 1/(4 L sqrt(rho s33^E)); the IEEE relation gives f_r below f_a otherwise."""
    pzt = piezo_material("pzt4")
    f_r, f_a = rod_frequencies_Hz(pzt, 10e-3)
    assert f_r < f_a
    weak = replace(pzt, d_C_per_N=1e-4 * pzt.d_C_per_N)
    f_r, f_a = rod_frequencies_Hz(weak, 10e-3)
    bare = 1 / (4 * 10e-3 * np.sqrt(pzt.density_kg_per_m3 * np.linalg.inv(pzt.c_E_Pa)[2, 2]))
    assert f_r == pytest.approx(bare, rel=1e-6) and f_a == pytest.approx(bare, rel=1e-6)


@pytest.mark.parametrize("key", KEYS)
def test_rod_first_longitudinal_frequency_short_and_open(key):
    """Rod r/L = 0.05 (one end u_z = 0, end electrodes): f_r shorted and f_a open within 0.5%."""
    pzt, mats = _mats(key)
    r, length = 0.5e-3, 10e-3
    asm = fem.assemble(cylinder_mesh(r, length, n_core=1, n_ring=1, n_layers=16), mats, order=2)
    rs = fem.reduce(asm, fem.BoundaryConditions("SS", (("top", (2,)),), hot_z_m=0.0, ground_z_m=length))
    for circuit, exact in zip(("short", "open"), rod_frequencies_Hz(pzt, length), strict=True):
        m = fem.modes(rs, 3, circuit)
        labels = [fem.label_mode(rs, m.shapes[:, k])[0] for k in range(3)]
        assert m.frequency_Hz[labels.index("axial")] == pytest.approx(exact, rel=5e-3), circuit
