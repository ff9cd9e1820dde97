"""Material data and the strain-charge to stress-charge conversion (paper Eq. 7-9, Table I)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.constants import epsilon_0

from piezobearing.sensor.materials import (
    ALUMINA,
    paper_pzt,
    stress_charge_form,
    to_sfepy_voigt,
    transverse_isotropy_report,
)


def test_voigt_permutation_swaps_the_shear_pairs():
    """Datasheet 11 22 33 23 13 12 -> sfepy 11 22 33 12 13 23: only 23 and 12 trade places."""
    c = np.arange(36, dtype=float).reshape(6, 6)
    s = to_sfepy_voigt(c)
    ds_of_sfepy = [0, 1, 2, 5, 4, 3]
    for i in range(6):
        for j in range(6):
            assert s[i, j] == c[ds_of_sfepy[i], ds_of_sfepy[j]]
    d = np.arange(18, dtype=float).reshape(3, 6)
    e = to_sfepy_voigt(d)
    assert np.array_equal(e[:, 3], d[:, 5]) and np.array_equal(e[:, 5], d[:, 3])
    assert np.array_equal(e[:, :3], d[:, :3]) and np.array_equal(e[:, 4], d[:, 4])
    with pytest.raises(ValueError, match="Voigt"):
        to_sfepy_voigt(np.zeros((3, 3)))


def test_paper_pzt_in_sfepy_order_puts_c66_and_d15_where_sfepy_expects_them():
    pzt = paper_pzt(c66_rule="paper")
    sc = stress_charge_form(pzt)
    assert sc.c_E_Pa[3, 3] == pytest.approx(2.12e11)  # sfepy 12 = datasheet 66
    assert sc.c_E_Pa[5, 5] == pytest.approx(0.23e11)  # sfepy 23 = datasheet 44
    # d15 couples E1 to the 13 shear (same slot in both orders), d24 E2 to 23 (sfepy slot 5).
    assert sc.e_C_per_m2[0, 4] == pytest.approx(590e-12 * 0.23e11)
    assert sc.e_C_per_m2[1, 5] == pytest.approx(590e-12 * 0.23e11)
    assert sc.e_C_per_m2[1, 3] == 0.0


def test_e33_and_eps33S_by_hand():
    """e33 = 2 d31 c13 + d33 c33; eps33^S = eps33^T - (2 d31 e31 + d33 e33), e31 = d31 (c11 + c12) + d33 c13."""
    pzt = paper_pzt()
    sc = stress_charge_form(pzt)
    d31, d33 = -175e-12, 400e-12
    c11, c12, c13, c33 = 1.47e11, 1.05e11, 0.93e11, 1.13e11
    e33 = 2 * d31 * c13 + d33 * c33
    e31 = d31 * (c11 + c12) + d33 * c13
    assert e33 == pytest.approx(12.65, rel=1e-12)
    assert e31 == pytest.approx(-6.90, rel=1e-12)
    assert sc.e_C_per_m2[2, 2] == pytest.approx(e33, rel=1e-12)
    assert sc.e_C_per_m2[2, 0] == pytest.approx(e31, rel=1e-12)
    eps33s = 1800 * epsilon_0 - (2 * d31 * e31 + d33 * e33)
    assert sc.eps_S_F_per_m[2, 2] == pytest.approx(eps33s, rel=1e-12)
    assert sc.eps_S_F_per_m[2, 2] / epsilon_0 == pytest.approx(955.8, abs=0.5)
    # Off-diagonal permittivity stays zero; eps11^S = eps11^T - d15 e15.
    assert sc.eps_S_F_per_m[0, 0] == pytest.approx(1800 * epsilon_0 - 590e-12 * 590e-12 * 0.23e11, rel=1e-12)
    assert np.count_nonzero(sc.eps_S_F_per_m - np.diag(np.diag(sc.eps_S_F_per_m))) == 0


def test_transverse_isotropy_report_flags_the_papers_c66():
    rep = transverse_isotropy_report(paper_pzt(c66_rule="paper").c_E_Pa)
    c66 = rep["c66=(c11-c12)/2"]
    assert not c66["holds"]
    assert c66["lhs"] == pytest.approx(2.12e11) and c66["rhs"] == pytest.approx(0.21e11)
    assert all(rep[k]["holds"] for k in ("c11=c22", "c13=c23", "c44=c55", "symmetric"))
    assert all(v["holds"] for v in transverse_isotropy_report(paper_pzt().c_E_Pa).values())


def test_the_paper_d_and_eps_have_the_6mm_pattern():
    """A ceramic poled along 3 has d31 = d32, d15 = d24, eps11 = eps22 and nothing else."""
    pzt = paper_pzt()
    d = pzt.d_C_per_N
    assert d[2, 0] == d[2, 1] and d[0, 4] == d[1, 3]
    mask = np.zeros_like(d, dtype=bool)
    mask[2, :3] = mask[0, 4] = mask[1, 3] = True
    assert np.all(d[~mask] == 0)
    assert pzt.eps_T_F_per_m[0, 0] == pzt.eps_T_F_per_m[1, 1]


def test_stress_charge_rejects_inconsistent_data():
    pzt = paper_pzt()
    bad = type(pzt)(pzt.name, pzt.c_E_Pa, 10 * pzt.d_C_per_N, pzt.eps_T_F_per_m)
    with pytest.raises(ValueError, match="positive definite"):
        stress_charge_form(bad)
    with pytest.raises(ValueError, match="c66_rule"):
        paper_pzt(c66_rule="typo")


def test_density_and_alumina_table_I():
    assert paper_pzt().density_kg_per_m3 == 7700.0  # APC 850 datasheet; the paper gives none
    lam, mu = ALUMINA.lame
    c = ALUMINA.stiffness_voigt()
    # Uniaxial stress recovers E and nu of Table I.
    s = np.linalg.inv(c)
    assert 1 / s[0, 0] == pytest.approx(330e9) and -s[0, 1] / s[0, 0] == pytest.approx(0.22)
    assert mu == pytest.approx(330e9 / (2 * 1.22))


def test_materials_from_config_follow_the_config(paper_config):
    # The sensor FEM and the housing's sensor spring build the PZT and alumina from the config, the same way.
    from piezobearing.sensor.materials import ALUMINA, alumina_from_config, pzt_from_config

    s = {**paper_config["sensor"], "d33_C_per_N": 300e-12, "eps33_T_rel": 1500.0}
    pzt = pzt_from_config(s)
    assert pzt.d33_C_per_N == 300e-12
    assert pzt.eps33_T_F_per_m == 1500.0 * epsilon_0
    assert pzt.d_C_per_N[2, 0] == -175e-12  # the rest stays the paper's
    assert alumina_from_config(paper_config["sensor_fem"]) == ALUMINA.__class__(
        "alumina", ALUMINA.young_Pa, ALUMINA.poisson, ALUMINA.density_kg_per_m3
    )
