"""Compiled time-stepping kernel of the 4-DOF lumped-parameter model (numba).

The same Newmark (trapezoidal) step and Newton iteration as the reference
loop in :func:`piezobearing.bearing.lpm.simulate_lpm` (``method="python"``),
written as scalar loops so that numba compiles them: the reference loop
spends its time in numpy's per-call overhead on arrays of 4 and 11 entries.
Everything the kinematics decides (roller angles, defect drops, roller
clearances) is computed beforehand as arrays over the time grid; the kernel
only solves the dynamics. ``cache=True`` keeps the compiled code in
``__pycache__`` so that only the first process of an installation compiles.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _solve4(a, b):  # pragma: no cover - compiled
    """Solve the 4x4 system a x = b by Gaussian elimination with partial pivoting (a, b overwritten)."""
    n = 4
    for k in range(n):
        p = k
        amax = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > amax:
                amax = abs(a[i, k])
                p = i
        if p != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            for j in range(k, n):
                a[i, j] -= f * a[k, j]
            b[i] -= f * b[k]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= a[i, j] * x[j]
        x[i] = s / a[i, i]
    return x


@njit(cache=True)
def newmark_lpm(sn, cn, offset, m, c, k, fext, u0, h, k_contact, tol_m, max_iter):  # pragma: no cover
    """Integrate the 4-DOF model from rest at ``u0`` with the Newmark trapezoidal rule.

    Parameters
    ----------
    sn, cn : ndarray (n + 1, Z)
        Components (y, z) of each roller's outward normal at every step [-].
    offset : ndarray (n + 1, Z)
        Gap to close before each roller carries load (clearance + drops) [m].
    m, c, k : ndarray (4, 4)
        Mass [kg], damping [N s/m] and linear stiffness [N/m] of (y_s, z_s, y_p, z_p).
    fext : ndarray (n + 1, 4)
        External force at every step [N] (the radial load; under base motion, minus each mass times the
        base's acceleration).
    u0 : ndarray (4,)
        Displacement at the first step [m] (velocity and acceleration 0).
    h : float
        Step [s].
    k_contact : float
        K of Q = K delta^(10/9) [N / m^(10/9)].
    tol_m : float
        Newton tolerance on the displacement update [m].
    max_iter : int
        Newton iterations allowed per step.

    Returns
    -------
    us : ndarray (n + 1, 4)
        Displacements [m].
    q_out : ndarray (n + 1, Z)
        Roller loads [N].
    n_iter : int
        Newton iterations in total.
    failed_at : int
        Step at which Newton did not converge, -1 if none.
    """
    n1, z = sn.shape
    beta, gamma = 0.25, 0.5
    a0 = 1.0 / (beta * h * h)
    a1 = gamma / (beta * h)
    # scalar loops, not array expressions or slice assignments: numba compiles each of those into a
    # function of its own (a broadcast ``us[0] = u`` alone cost ~1.5 s of compile time), same values
    keff = np.empty((4, 4))
    for i in range(4):
        for jj in range(4):
            keff[i, jj] = a0 * m[i, jj] + a1 * c[i, jj] + k[i, jj]
    us = np.empty((n1, 4))
    q_out = np.zeros((n1, z))
    u = np.empty(4)
    v = np.zeros(4)
    a = np.zeros(4)
    for i in range(4):
        u[i] = u0[i]
        us[0, i] = u[i]
    ey, ez = u[0] - u[2], u[1] - u[3]
    for j in range(z):
        d = ey * sn[0, j] + ez * cn[0, j] - offset[0, j]
        if d > 0.0:
            q_out[0, j] = k_contact * d * d ** (1.0 / 9.0)
    n_iter = 0
    c1 = 0.5 / beta - 1.0
    c2 = gamma / beta - 1.0
    c3 = h * (0.5 * gamma / beta - 1.0)
    mv = np.empty(4)
    cv = np.empty(4)
    rhs = np.empty(4)
    x = np.empty(4)
    r = np.empty(4)
    kt = np.empty((4, 4))
    for n in range(1, n1):
        for i in range(4):
            mv[i] = a0 * u[i] + a0 * h * v[i] + c1 * a[i]
            cv[i] = a1 * u[i] + c2 * v[i] + c3 * a[i]
            x[i] = u[i] + h * v[i] + 0.5 * h * h * a[i]
        for i in range(4):
            s = 0.0
            for jj in range(4):
                s += m[i, jj] * mv[jj] + c[i, jj] * cv[jj]
            rhs[i] = s
        converged = False
        for _ in range(max_iter):
            ey, ez = x[0] - x[2], x[1] - x[3]
            fy = fz = jss = jsc = jcc = 0.0
            for j in range(z):
                s_j, c_j = sn[n, j], cn[n, j]
                d = ey * s_j + ez * c_j - offset[n, j]
                if d > 0.0:
                    d19 = d ** (1.0 / 9.0)
                    q = k_contact * d * d19
                    dq = (10.0 / 9.0) * k_contact * d19
                    fy += q * s_j
                    fz += q * c_j
                    jss += dq * s_j * s_j
                    jsc += dq * s_j * c_j
                    jcc += dq * c_j * c_j
            g0, g1 = fy, fz
            for i in range(4):
                s = 0.0
                for jj in range(4):
                    s += keff[i, jj] * x[jj]
                    kt[i, jj] = keff[i, jj]
                r[i] = -(s - rhs[i] - fext[n, i])
            r[0] -= g0
            r[1] -= g1
            r[2] += g0
            r[3] += g1
            jg00, jg01, jg11 = jss, jsc, jcc
            kt[0, 0] += jg00
            kt[0, 1] += jg01
            kt[1, 0] += jg01
            kt[1, 1] += jg11
            kt[0, 2] -= jg00
            kt[0, 3] -= jg01
            kt[1, 2] -= jg01
            kt[1, 3] -= jg11
            kt[2, 0] -= jg00
            kt[2, 1] -= jg01
            kt[3, 0] -= jg01
            kt[3, 1] -= jg11
            kt[2, 2] += jg00
            kt[2, 3] += jg01
            kt[3, 2] += jg01
            kt[3, 3] += jg11
            dx = _solve4(kt, r)
            big = 0.0
            for i in range(4):
                x[i] += dx[i]
                if abs(dx[i]) > big:
                    big = abs(dx[i])
            n_iter += 1
            if big < tol_m:
                converged = True
                break
        if not converged:
            return us, q_out, n_iter, n
        for i in range(4):
            a_new = a0 * (x[i] - u[i]) - a0 * h * v[i] - c1 * a[i]
            v[i] = v[i] + h * ((1 - gamma) * a[i] + gamma * a_new)
            a[i] = a_new
            u[i] = x[i]
            us[n, i] = u[i]
        ey, ez = u[0] - u[2], u[1] - u[3]
        for j in range(z):
            d = ey * sn[n, j] + ez * cn[n, j] - offset[n, j]
            if d > 0.0:
                q_out[n, j] = k_contact * d * d ** (1.0 / 9.0)
    return us, q_out, n_iter, -1
