"""Material data of the paper and the one conversion the FEM needs.

Every constant here comes from the paper (Table I, Eq. 7-9) unless its
docstring says otherwise. Voigt orders:

* datasheet / paper order: 11 22 33 23 13 12 (Eq. 8 has d15 on row 5 and
  d24 on row 4, which is this order);
* sfepy order: 11 22 33 12 13 23.

The conversion between them lives in :func:`to_sfepy_voigt` and nowhere else.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.constants import epsilon_0  # vacuum permittivity [F/m], CODATA

#: Permutation that takes a datasheet-ordered Voigt index to sfepy's order.
#: sfepy position k holds datasheet component ``_DATASHEET_TO_SFEPY[k]``.
_DATASHEET_TO_SFEPY = np.array([0, 1, 2, 5, 4, 3])


@dataclass(frozen=True)
class IsotropicMaterial:
    """Linear elastic isotropic solid.

    Parameters
    ----------
    name : str
    young_Pa : float
        Young's modulus E [Pa].
    poisson : float
        Poisson's ratio nu [-].
    density_kg_per_m3 : float
        Mass density rho [kg/m^3].
    """

    name: str
    young_Pa: float
    poisson: float
    density_kg_per_m3: float

    @property
    def lame(self) -> tuple[float, float]:
        """Lamé constants (lambda, mu) [Pa]."""
        e, nu = self.young_Pa, self.poisson
        lam = e * nu / ((1 + nu) * (1 - 2 * nu))
        mu = e / (2 * (1 + nu))
        return lam, mu

    def stiffness_voigt(self) -> np.ndarray:
        """6x6 stiffness [Pa]; the same in every Voigt order."""
        lam, mu = self.lame
        c = np.zeros((6, 6))
        c[:3, :3] = lam
        c[np.arange(3), np.arange(3)] += 2 * mu
        c[np.arange(3, 6), np.arange(3, 6)] = mu
        return c


@dataclass(frozen=True)
class PiezoMaterial:
    """Poled piezoceramic in strain-charge form, datasheet Voigt order.

    Parameters
    ----------
    name : str
    c_E_Pa : ndarray (6, 6)
        Stiffness at constant electric field [Pa], order 11 22 33 23 13 12.
    d_C_per_N : ndarray (3, 6)
        Piezoelectric charge constants d_ip [C/N], same order.
    eps_T_F_per_m : ndarray (3, 3)
        Permittivity at constant stress [F/m].
    density_kg_per_m3 : float
        Mass density [kg/m^3].
    mechanical_quality_factor : float
        The ceramic's mechanical quality factor Qm [-]: the small-signal value of its table, measured at the
        resonance of a free, poled sample. With ``sensor_fem.mechanical_quality_factor: null`` it sets the
        FEM's modal damping ratio 1/(2 Qm).
    source : str
        Where the constants come from.
    quality_factor_source : str
        Where Qm comes from, or that the constants' source gives none.
    """

    name: str
    c_E_Pa: np.ndarray = field(repr=False)
    d_C_per_N: np.ndarray = field(repr=False)
    eps_T_F_per_m: np.ndarray = field(repr=False)
    density_kg_per_m3: float = 7700.0
    mechanical_quality_factor: float = 80.0
    source: str = ""
    quality_factor_source: str = ""

    @property
    def d33_C_per_N(self) -> float:
        return float(self.d_C_per_N[2, 2])

    @property
    def eps33_T_F_per_m(self) -> float:
        return float(self.eps_T_F_per_m[2, 2])

    @property
    def eps33_T_rel(self) -> float:
        """eps33^T / eps0 [-], to 9 significant digits (datasheets give at most 4; this undoes the
        last-bit rounding of eps0 x eps_rel / eps0)."""
        return float(f"{self.eps33_T_F_per_m / epsilon_0:.9g}")


def to_sfepy_voigt(a: np.ndarray) -> np.ndarray:
    """Reorder the Voigt axes of ``a`` from datasheet to sfepy order.

    Works on a 6x6 stiffness (both axes) and on a 3x6 coupling matrix (last
    axis). Shear components keep their engineering-strain scaling, which is
    the same in both conventions.
    """
    a = np.asarray(a, dtype=float)
    p = _DATASHEET_TO_SFEPY
    if a.shape == (6, 6):
        return a[np.ix_(p, p)]
    if a.shape == (3, 6):
        return a[:, p]
    raise ValueError(f"expected a (6, 6) or (3, 6) Voigt array, got {a.shape}")


@dataclass(frozen=True)
class StressChargeForm:
    """Piezoelectric constants in stress-charge form, sfepy Voigt order.

    ``c_E_Pa`` (6, 6), ``e_C_per_m2`` (3, 6), ``eps_S_F_per_m`` (3, 3).
    """

    c_E_Pa: np.ndarray
    e_C_per_m2: np.ndarray
    eps_S_F_per_m: np.ndarray


def stress_charge_form(pzt: PiezoMaterial) -> StressChargeForm:
    """Convert strain-charge data (d, eps^T, c^E) to stress-charge (e, eps^S).

    .. math::  e = d\\,c^E, \\qquad \\varepsilon^S = \\varepsilon^T - d\\,c^E d^T

    The products are formed in the datasheet order and the result is then
    reordered once to sfepy's order with :func:`to_sfepy_voigt`.
    """
    c, d = pzt.c_E_Pa, pzt.d_C_per_N
    e = d @ c
    eps_s = pzt.eps_T_F_per_m - d @ c @ d.T
    if np.any(np.linalg.eigvalsh(eps_s) <= 0):
        raise ValueError(f"{pzt.name}: eps^S is not positive definite; check d, c^E and eps^T")
    return StressChargeForm(to_sfepy_voigt(c), to_sfepy_voigt(e), eps_s)


def transverse_isotropy_report(c_E_Pa: np.ndarray, rtol: float = 0.02) -> dict:
    """Check a datasheet-ordered stiffness for the symmetry of a poled ceramic.

    A ceramic poled along 3 is transversely isotropic (class 6mm): c11 = c22,
    c13 = c23, c44 = c55 and c66 = (c11 - c12) / 2. Returns each relation with
    both sides and whether it holds within ``rtol``.
    """
    c = np.asarray(c_E_Pa, dtype=float)
    rel = {
        "c11=c22": (c[0, 0], c[1, 1]),
        "c13=c23": (c[0, 2], c[1, 2]),
        "c44=c55": (c[3, 3], c[4, 4]),
        "c66=(c11-c12)/2": (c[5, 5], 0.5 * (c[0, 0] - c[0, 1])),
        "symmetric": (float(np.abs(c - c.T).max()), 0.0),
    }
    out = {}
    for name, (lhs, rhs) in rel.items():
        scale = max(abs(lhs), abs(rhs), 1e-30) if name != "symmetric" else np.abs(c).max()
        out[name] = {"lhs": float(lhs), "rhs": float(rhs), "holds": bool(abs(lhs - rhs) <= rtol * scale)}
    return out


def symmetry_report(pzt: PiezoMaterial, rtol: float = 0.02) -> dict:
    """Every relation a ceramic poled along 3 (class 6mm, C6v) must satisfy, checked on ``pzt``.

    The stiffness relations of :func:`transverse_isotropy_report`, and
    d31 = d32, d15 = d24, eps11 = eps22 with every other d_ip and eps_ik
    zero; c^E positive definite and eps^S (:func:`stress_charge_form`)
    positive definite. Each entry: ``lhs``, ``rhs``, ``holds``.
    """
    out = transverse_isotropy_report(pzt.c_E_Pa, rtol)
    d, eps = pzt.d_C_per_N, pzt.eps_T_F_per_m
    mask = np.zeros_like(d, dtype=bool)
    mask[2, :3] = mask[0, 4] = mask[1, 3] = True
    scale = np.abs(d).max()
    rel = {
        "d31=d32": (d[2, 0], d[2, 1], scale),
        "d15=d24": (d[0, 4], d[1, 3], scale),
        "d: zeros elsewhere": (float(np.abs(d[~mask]).max()), 0.0, scale),
        "eps11=eps22": (eps[0, 0], eps[1, 1], eps[0, 0]),
        "eps: diagonal": (float(np.abs(eps - np.diag(np.diag(eps))).max()), 0.0, eps[0, 0]),
    }
    for name, (lhs, rhs, sc) in rel.items():
        out[name] = {"lhs": float(lhs), "rhs": float(rhs), "holds": bool(abs(lhs - rhs) <= rtol * sc)}
    lam_c = float(np.linalg.eigvalsh(pzt.c_E_Pa).min())
    eps_s = pzt.eps_T_F_per_m - pzt.d_C_per_N @ pzt.c_E_Pa @ pzt.d_C_per_N.T
    lam_e = float(np.linalg.eigvalsh(eps_s).min())
    out["c^E positive definite"] = {"lhs": lam_c, "rhs": 0.0, "holds": lam_c > 0}
    out["eps^S positive definite"] = {"lhs": lam_e, "rhs": 0.0, "holds": lam_e > 0}
    return out


def paper_pzt(c66_rule: str = "isotropy", density_kg_per_m3: float = 7700.0) -> PiezoMaterial:
    """APC 850 as printed in the paper, Eq. 7-9.

    Parameters
    ----------
    c66_rule : {"isotropy", "paper"}
        The paper prints c66 = 2.12e11 Pa, ten times (c11 - c12)/2 = 0.21e11 Pa,
        which a poled ceramic must have (see :func:`transverse_isotropy_report`).
        ``"isotropy"`` (default) uses (c11 - c12)/2, reading the printed value
        as a misplaced decimal point; ``"paper"`` keeps 2.12e11 Pa as printed.
        c66 only enters in-plane shear, which an axial load hardly excites.
    density_kg_per_m3 : float
        The paper gives no density; 7700 kg/m^3 is the APC 850 datasheet value
        (APC International, "Physical and piezoelectric properties of APC
        materials").

    Notes
    -----
    Eq. 7 writes eps0 as 8.85e-12 F/m; we use scipy's epsilon_0
    (8.8541878128e-12 F/m), a 0.05% difference.
    """
    c = 1e11 * np.array(
        [
            [1.47, 1.05, 0.93, 0, 0, 0],
            [1.05, 1.47, 0.93, 0, 0, 0],
            [0.93, 0.93, 1.13, 0, 0, 0],
            [0, 0, 0, 0.23, 0, 0],
            [0, 0, 0, 0, 0.23, 0],
            [0, 0, 0, 0, 0, 2.12],
        ]
    )
    if c66_rule == "isotropy":
        c[5, 5] = 0.5 * (c[0, 0] - c[0, 1])
    elif c66_rule != "paper":
        raise ValueError(f"c66_rule must be 'isotropy' or 'paper', got {c66_rule!r}")
    d = 1e-12 * np.array(
        [
            [0, 0, 0, 0, 590, 0],
            [0, 0, 0, 590, 0, 0],
            [-175, -175, 400, 0, 0, 0],
        ]
    )
    eps_t = 1800 * epsilon_0 * np.eye(3)
    return PiezoMaterial(
        "APC 850",
        c,
        d,
        eps_t,
        density_kg_per_m3,
        80.0,
        "the paper, Eq. 7-9; density and Qm = 80 from APC International, 'Physical and piezoelectric "
        "properties of APC materials' (APC 850)",
        "the paper gives no Qm; Qm = 80 is APC International's sheet value for APC 850 ('Physical and "
        "piezoelectric properties of APC materials')",
    )


# --------------------------------------------------------------------------- the library


def _strain_charge(name, s11, s12, s13, s33, s44, d31, d33, d15, eps11_rel, eps33_rel, density, qm, source,
                   qm_source):
    """A 6mm ceramic from its strain-charge constants (s^E in 1e-12 m^2/N, d in 1e-12 C/N, eps^T / eps0)
    and its Qm (``qm_source`` says where Qm comes from).

    s66 = 2 (s11 - s12) is the 6mm relation; the stiffness is c^E = (s^E)^-1.
    """
    s = np.zeros((6, 6))
    s[:3, :3] = [[s11, s12, s13], [s12, s11, s13], [s13, s13, s33]]
    s[3, 3] = s[4, 4] = s44
    s[5, 5] = 2 * (s11 - s12)
    d = np.zeros((3, 6))
    d[2, :3] = [d31, d31, d33]
    d[0, 4] = d[1, 3] = d15
    eps = np.diag([eps11_rel, eps11_rel, eps33_rel]) * epsilon_0
    return PiezoMaterial(name, np.linalg.inv(1e-12 * s), 1e-12 * d, eps, density, qm, source, qm_source)


def _library() -> dict:
    """Every ceramic of :data:`PIEZO_MATERIALS` (built once at import)."""
    berlincourt = (
        "Berlincourt, Curran and Jaffe, 'Piezoelectric and piezomagnetic materials', in Physical "
        "Acoustics vol. I-A (Academic Press, 1964); the same table in Sherman and Butler, 'Transducers "
        "and Arrays for Underwater Sound' (Springer, 2007), App. A.5"
    )

    def qm_berlincourt(qm: float) -> str:
        return (f"Qm = {qm:g}: the Navy type's small-signal Qm of a free sample as listed with these constants by "
                "Berlincourt, Krueger and Near, 'Properties of Morgan Electro Ceramic ceramics' (Morgan "
                "Electro Ceramics, Technical Publication TP-226); a bonded, clamped stack is damped more")

    return {
        "apc850_paper": paper_pzt(),
        "pzt5a": _strain_charge(
            "PZT-5A (Navy Type II; APC 850 class)",
            16.4, -5.74, -7.22, 18.8, 47.5, -171.0, 374.0, 584.0, 1730.0, 1700.0, 7750.0, 75.0,
            berlincourt + "; also Erturk and Inman, 'Piezoelectric Energy Harvesting' (Wiley, 2011), Table E.1",
            qm_berlincourt(75.0),
        ),
        "pzt4": _strain_charge(
            "PZT-4 (Navy Type I, hard; APC 841 class)",
            12.3, -4.05, -5.31, 15.5, 39.0, -123.0, 289.0, 496.0, 1475.0, 1300.0, 7500.0, 500.0,
            berlincourt, qm_berlincourt(500.0),
        ),
        "pzt8": _strain_charge(
            "PZT-8 (Navy Type III, hard; APC 880 class)",
            11.5, -3.7, -4.8, 13.5, 31.9, -97.0, 225.0, 330.0, 1290.0, 1000.0, 7600.0, 1000.0,
            berlincourt, qm_berlincourt(1000.0),
        ),
        "pzt5h": _strain_charge(
            "PZT-5H (Navy Type VI, soft; APC 855 class)",
            16.5, -4.78, -8.45, 20.7, 43.5, -274.0, 593.0, 741.0, 3130.0, 3400.0, 7500.0, 65.0,
            berlincourt + "; also Erturk and Inman, 'Piezoelectric Energy Harvesting' (Wiley, 2011), Table E.1",
            qm_berlincourt(65.0),
        ),
    }


def piezo_material(key: str, c66_rule: str = "isotropy") -> PiezoMaterial:
    """The ceramic ``key`` of :data:`PIEZO_MATERIALS` (``c66_rule`` applies to ``apc850_paper`` only)."""
    if key not in PIEZO_MATERIALS:
        raise KeyError(f"PZT material '{key}' is unknown; known: {', '.join(PIEZO_MATERIALS)}")
    if key == "apc850_paper":
        return paper_pzt(c66_rule=c66_rule)
    return PIEZO_MATERIALS[key]


def pzt_from_config(sensor: dict) -> PiezoMaterial:
    """The PZT of the validated ``sensor`` config section.

    The ceramic ``sensor.material`` of the library; ``d33_C_per_N``,
    ``eps33_T_rel`` and ``pzt_density_kg_per_m3`` replace its values where
    they are not null (a calibrated disk of that ceramic).
    """
    pzt = piezo_material(sensor.get("material", "apc850_paper"), sensor["c66_rule"])
    if sensor.get("pzt_density_kg_per_m3") is not None:
        pzt = replace(pzt, density_kg_per_m3=sensor["pzt_density_kg_per_m3"])
    d = pzt.d_C_per_N.copy()
    if sensor.get("d33_C_per_N") is not None:
        d[2, 2] = sensor["d33_C_per_N"]
    eps = pzt.eps_T_F_per_m.copy()
    if sensor.get("eps33_T_rel") is not None:
        eps[2, 2] = sensor["eps33_T_rel"] * epsilon_0
    return replace(pzt, d_C_per_N=d, eps_T_F_per_m=eps)


def alumina_from_config(sensor_fem: dict) -> IsotropicMaterial:
    """The alumina of the validated ``sensor_fem`` config section (Table I by default)."""
    return IsotropicMaterial(
        "alumina",
        sensor_fem["alumina_young_Pa"],
        sensor_fem["alumina_poisson"],
        sensor_fem["alumina_density_kg_per_m3"],
    )


def adhesive_from_config(sensor_fem: dict) -> IsotropicMaterial:
    """The bond layer's material of the validated ``sensor_fem`` config section."""
    return IsotropicMaterial(
        "adhesive",
        sensor_fem["adhesive_young_Pa"],
        sensor_fem["adhesive_poisson"],
        sensor_fem["adhesive_density_kg_per_m3"],
    )


#: Table I of the paper.
CAST_IRON = IsotropicMaterial("cast iron (housing)", 110e9, 0.28, 7200.0)
STEEL = IsotropicMaterial("steel (outer ring)", 200e9, 0.30, 7800.0)
ALUMINA = IsotropicMaterial("alumina (sensor protection disks)", 330e9, 0.22, 3900.0)

#: A cured, unfilled two-part structural epoxy: E = 3.0 GPa, nu = 0.35, rho = 1200 kg/m^3. Nominal values
#: (not one product's datasheet): such epoxies lie at E = 2-4 GPa, nu = 0.33-0.40, rho = 1100-1300 kg/m^3.
EPOXY = IsotropicMaterial("epoxy adhesive (nominal)", 3.0e9, 0.35, 1200.0)

#: The piezoceramics by config key (``sensor.material``); see :func:`_library` for each source.
PIEZO_MATERIALS = _library()
