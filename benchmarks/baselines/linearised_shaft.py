"""The shaft's dynamics linearised about the quasi-static state: the method the dynamic rung
(:mod:`piezobearing.bearing.shaft_dynamics`, the 4-DOF dynamics with contacts that open) was chosen over, kept as
the baseline of ``benchmarks/bench_shaft_dynamics.py``.

About the surrogate's quasi-static offset e_qs(t), the rollers' resultant is F - K_c(t) (e - e_qs) with the
contact stiffness K_c = sum_j dQ_j/d delta_j n_j n_j^T at the quasi-static loads (dQ/d delta = 10/9 K^0.9 Q^0.1);
shaft and pedestal then obey a linear system with a stiffness that changes from step to step, integrated by the
Newmark (trapezoidal) rule, and the sensor force changes by G . (e - e_qs), G = sum_j dQ_j/d delta_j g_j n_j. A
contact that opens during the ring stays linear here: that is what this method misses.
"""

from __future__ import annotations

import numpy as np

from piezobearing.bearing.lpm import contact_law
from piezobearing.bearing.shaft_dynamics import ShaftDynamics
from piezobearing.bearing.surrogate import quasi_static_loads


def linear_state(psi: np.ndarray, drop: np.ndarray, load_N: float, clearance_m: float, k_contact: float,
                 influence) -> np.ndarray:
    """e_qs (y, z), K_c (yy, yz, zz) and G (y, z) at each row of roller angles (n, Z) with extra gaps (n, Z)."""
    q, e = quasi_static_loads(psi, drop, load_N, 0.5 * clearance_m, k_contact, 1e-9, return_offset=True)
    dq = (10.0 / 9.0) * k_contact**0.9 * np.power(np.maximum(q, 0.0), 0.1)
    s, c, g = np.sin(psi), -np.cos(psi), influence(psi)
    return np.stack([e[:, 0], e[:, 1], np.sum(dq * s * s, 1), np.sum(dq * s * c, 1), np.sum(dq * c * c, 1),
                     np.sum(dq * g * s, 1), np.sum(dq * g * c, 1)], 1)


def sensor_force(psi: np.ndarray, drop: np.ndarray, load_N: float, clearance_m: float, k_contact: float, influence,
                 dyn: ShaftDynamics, step_s: float) -> np.ndarray:
    """The quasi-static sensor force plus the linearised dynamics' change at every step [N] (a numpy loop)."""
    st = linear_state(psi, drop, load_N, clearance_m, k_contact, influence)
    q = contact_law(st[:, :1] * np.sin(psi) - st[:, 1:2] * np.cos(psi) - 0.5 * clearance_m - drop, k_contact)[0]
    f_qs = np.sum(q * influence(psi), 1)
    m, c, k_lin = dyn.matrices()
    h, beta, gamma = step_s, 0.25, 0.5
    a0, a1 = 1 / (beta * h * h), gamma / (beta * h)
    u = np.array([st[0, 0], st[0, 1], 0.0, 0.0])
    v, a = np.zeros(4), np.zeros(4)
    e = np.empty((psi.shape[0], 2))
    e[0] = st[0, :2]
    for n in range(1, psi.shape[0]):
        kc = np.array([[st[n, 2], st[n, 3]], [st[n, 3], st[n, 4]]])
        kt = k_lin + np.block([[kc, -kc], [-kc, kc]])
        f = kc @ st[n, :2]
        rhs = np.r_[f, -f] + m @ (a0 * u + a0 * h * v + (0.5 / beta - 1) * a) + c @ (
            a1 * u + (gamma / beta - 1) * v + h * (0.5 * gamma / beta - 1) * a)
        x = np.linalg.solve(a0 * m + a1 * c + kt, rhs)
        an = a0 * (x - u) - a0 * h * v - (0.5 / beta - 1) * a
        v = v + h * ((1 - gamma) * a + gamma * an)
        a, u = an, x
        e[n] = u[:2] - u[2:]
    return f_qs + st[:, 5] * (e[:, 0] - st[:, 0]) + st[:, 6] * (e[:, 1] - st[:, 1])
