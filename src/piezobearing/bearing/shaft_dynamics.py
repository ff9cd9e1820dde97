r"""The shaft's inertia on its rollers: the 4-DOF dynamics on the quasi-static surrogate's kinematics.

The quasi-static surrogate (:mod:`.surrogate`) holds the rings in equilibrium at every instant. A running
bearing carries the shaft's mass m_s on its rollers, with the pedestal (outer ring and housing: m_p, k_p, c_p)
and the damping c_b between them: after each edge of a groove the shaft rings at its mode on the rollers
(sqrt(k_c / m_s) / 2 pi for a contact stiffness k_c, 2.6 kHz for the paper's rig), and a defect that unloads a
roller faster than the shaft follows changes the neighbours' loads less than in equilibrium. The dynamic rung
integrates the LPM's equations (:func:`.lpm.simulate_lpm`),

.. math::
    m_s \ddot u_s + c_b(\dot u_s - \dot u_p) = F - \sum_j Q_j n_j, \qquad
    m_p \ddot u_p - c_b(\dot u_s - \dot u_p) + c_p \dot u_p + k_p u_p = \sum_j Q_j n_j,

.. math::  Q_j = K \langle (u_s - u_p) \cdot n_j - P_d/2 - d_j(t) \rangle^{10/9}, \qquad F_s = \sum_j Q_j\, g(\psi_j),

with the compiled Newmark kernel (:func:`.lpm_kernel.newmark_lpm`) on a grid of :func:`steps_per_sample`
steps per DAQ sample, driven by the roller angles psi_j(t) and the drops d_j(t) the surrogate's chain computes
(its cage phase, slip, tachometer, defects and roller offsets); F_s is averaged over each sample window as the
DAQ does. The linearised alternative (the quasi-static state plus a linear correction with the contact
stiffness at the quasi-static loads) misses the contacts that open during the ring, and with them most of the
error this rung exists to remove: ``benchmarks/bench_shaft_dynamics.py`` measures both against the LPM at a
finer step.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .lpm import contact_law, line_contact_stiffness, shaft_pedestal_matrices
from .lpm_kernel import newmark_lpm
from .surrogate import NoEquilibriumError, quasi_static_loads

#: Integration steps per period of the shaft's mode on its rollers (:func:`modes_Hz`) of the diagnosis's search: 16
#: keeps the box-averaged sensor force within 0.12-0.42 % (rms) of the LPM at a 2.7 us step on the paper's rig (12:
#: 0.2-0.8 %, 24: 0.06-0.2 %; benchmarks/bench_shaft_dynamics.py --accuracy), enough to choose the model and find its
#: basin; the final refit (:data:`FINAL_STEPS_PER_PERIOD`) gives the values and intervals. Chosen for the search's cost
#: (two thirds of 24's); 12 ends a 0.9 mm groove with a 40 um clearance in another basin (docs/validation/
#: bearing_diagnosis.md); the config's ``bearing_diagnosis.dynamic_steps_per_period``.
STEPS_PER_PERIOD = 16
#: Steps per period of the final refit of a selected dynamic model and its intervals: 48 keeps the force within
#: 0.05 % of that LPM, and a 0.6 mm groove's width interval holds the LPM's hidden width where the search's step misses it
#: (docs/validation/bearing_diagnosis.md); the config's ``bearing_diagnosis.dynamic_final_steps_per_period``.
FINAL_STEPS_PER_PERIOD = 48
#: Newton tolerance of the kernel's step on the displacement [m] (the LPM's).
TOL_M = 1e-16


@dataclass(frozen=True)
class ShaftDynamics:
    """The masses, stiffness and damping of the dynamic rung (the LPM's keys of the config's ``bearing``).

    Parameters
    ----------
    shaft_mass_kg : float
        m_s, the mass of shaft and inner ring this bearing carries radially [kg].
    bearing_damping_N_s_per_m : float
        c_b, viscous damping between shaft and pedestal (the contacts' and the lubricant's) [N s/m].
    pedestal_mass_kg, pedestal_stiffness_N_per_m, pedestal_damping_N_s_per_m : float
        m_p, k_p, c_p: outer ring and housing on the ground [kg, N/m, N s/m].
    """

    shaft_mass_kg: float
    bearing_damping_N_s_per_m: float
    pedestal_mass_kg: float
    pedestal_stiffness_N_per_m: float
    pedestal_damping_N_s_per_m: float

    @classmethod
    def from_config(cls, bearing: dict) -> "ShaftDynamics":
        """From the ``bearing`` section (the LPM's keys)."""
        return cls(float(bearing["shaft_mass_kg"]), float(bearing["bearing_damping_N_s_per_m"]),
                   float(bearing["pedestal_mass_kg"]), float(bearing["pedestal_stiffness_N_per_m"]),
                   float(bearing["pedestal_damping_N_s_per_m"]))

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass, damping and linear stiffness of (y_s, z_s, y_p, z_p) (:func:`.lpm.shaft_pedestal_matrices`)."""
        return shaft_pedestal_matrices(self.shaft_mass_kg, self.pedestal_mass_kg, self.bearing_damping_N_s_per_m,
                                       self.pedestal_damping_N_s_per_m, self.pedestal_stiffness_N_per_m)


def modes_Hz(k_contact_N_per_m: float, m_s: float, m_p: float, k_p: float) -> tuple[float, float]:
    """Undamped natural frequencies of shaft and pedestal along one direction [Hz], lower first.

    The eigenvalues of [[k, -k], [-k, k + k_p]] against diag(m_s, m_p), k the contact stiffness along it; the
    lower is the shaft's on its rollers (sqrt(k / m_s) / 2 pi for a rigid pedestal).
    """
    k = k_contact_N_per_m
    a, b, c = m_s * m_p, -(k * m_p + (k + k_p) * m_s), k * k_p
    disc = np.sqrt(max(b * b - 4 * a * c, 0.0))
    w2 = sorted([(-b - disc) / (2 * a), (-b + disc) / (2 * a)])
    return tuple(float(np.sqrt(max(x, 0.0)) / (2 * np.pi)) for x in w2)


def contact_stiffness_N_per_m(radial_load_N: float, psi_rad: np.ndarray, gap_m: float, roller_length_m: float) -> float:
    """The rollers' contact stiffness along the load at the static equilibrium with rollers at ``psi_rad`` (Z,):
    sum_j dQ_j/d delta_j cos^2 psi_j [N/m]."""
    k = line_contact_stiffness(roller_length_m)
    e = equilibrium(psi_rad, np.zeros(psi_rad.size), radial_load_N, gap_m, k)
    _, dq = contact_law(e[0] * np.sin(psi_rad) - e[1] * np.cos(psi_rad) - gap_m, k)
    return float(np.sum(dq * np.cos(psi_rad) ** 2))


@lru_cache(maxsize=64)
def shaft_mode(dyn: ShaftDynamics, radial_load_N: float, radial_clearance_m: float, roller_length_m: float,
               n_rollers: int) -> tuple[float, float]:
    """The shaft's mode on its rollers along the load [Hz] and its damping ratio c_b / (2 sqrt(k m_s)) [-], the
    contact stiffness averaged over the two symmetric roller positions (a roller at the bottom, and half a pitch
    on); cached (a fit asks at every evaluation)."""
    pitch = 2 * np.pi / n_rollers
    ks = [contact_stiffness_N_per_m(radial_load_N, a + pitch * np.arange(n_rollers), 0.5 * radial_clearance_m,
                                    roller_length_m) for a in (0.0, 0.5 * pitch)]
    k = float(np.mean(ks))
    f = modes_Hz(k, dyn.shaft_mass_kg, dyn.pedestal_mass_kg, dyn.pedestal_stiffness_N_per_m)[0]
    return f, dyn.bearing_damping_N_s_per_m / (2.0 * np.sqrt(k * dyn.shaft_mass_kg))


def equilibrium(psi_rad: np.ndarray, extra_gap_m: np.ndarray, radial_load_N: float, gap_m: float,
                k_contact: float) -> np.ndarray:
    """The shaft's static offset (y, z) [m] with rollers at ``psi_rad`` (Z,) and extra gaps (Z,): the surrogate's
    Newton's method (:func:`.surrogate.quasi_static_loads`, from any start; no equilibrium raises
    :class:`.surrogate.NoEquilibriumError`, a refused step of a fit)."""
    _, e = quasi_static_loads(np.asarray(psi_rad)[None, :], np.asarray(extra_gap_m)[None, :], radial_load_N, gap_m,
                              k_contact, 1e-12, return_offset=True)
    return e[0]


def steps_per_sample(mode_Hz: float, dt_s: float, per_period: int = STEPS_PER_PERIOD) -> int:
    """Integration steps per DAQ sample: ``per_period`` per period of the shaft's mode, at least 1."""
    return max(int(np.ceil(per_period * mode_Hz * dt_s)), 1)


def sensor_force(psi_rad: np.ndarray, extra_gap_m: np.ndarray, radial_load_N: float, radial_clearance_m: float,
                 roller_length_m: float, influence, dyn: ShaftDynamics, step_s: float,
                 normals: tuple[np.ndarray, np.ndarray] | None = None,
                 influence_at: np.ndarray | None = None) -> np.ndarray:
    """The sensor force F_s [N] at every step of a uniform grid, the system starting at rest in static equilibrium.

    Parameters
    ----------
    psi_rad, extra_gap_m : ndarray (n, Z)
        Roller angles from the load direction [rad] and each roller's gap beyond P_d / 2 (defect drops, smaller
        rollers) [m] at the steps.
    radial_load_N, radial_clearance_m, roller_length_m : float
        F_r [N], P_d [m], l [m].
    influence : callable
        g(psi) [N/N] (:class:`.surrogate.InfluenceLine`).
    dyn : ShaftDynamics
    step_s : float
        The grid's step [s].
    normals : (ndarray, ndarray), optional
        sin psi and -cos psi (n, Z) where the caller holds them.
    influence_at : ndarray (n, Z), optional
        g(psi) where the caller holds it.
    """
    m, c, k = dyn.matrices()
    kc = line_contact_stiffness(roller_length_m)
    gap = 0.5 * radial_clearance_m
    n = psi_rad.shape[0]
    fext = np.zeros((n, 4))
    fext[:, 1] = -radial_load_N
    e0 = equilibrium(psi_rad[0], extra_gap_m[0], radial_load_N, gap, kc)
    up0 = fext[0, :2] / dyn.pedestal_stiffness_N_per_m
    u0 = np.r_[up0 + e0, up0]
    sn, cn = (np.sin(psi_rad), -np.cos(psi_rad)) if normals is None else normals
    sn, cn = np.ascontiguousarray(sn), np.ascontiguousarray(cn)
    _, q, _, failed = newmark_lpm(sn, cn, np.ascontiguousarray(gap + extra_gap_m), m, c, k, fext, u0, step_s, kc,
                                  TOL_M, 50)
    if failed >= 0:
        raise NoEquilibriumError(f"shaft dynamics: Newton's method did not converge at step {failed} of {n}")
    return np.sum(q * (influence(psi_rad) if influence_at is None else influence_at), axis=1)
