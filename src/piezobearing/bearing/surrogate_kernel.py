"""Compiled Newton loop of the quasi-static roller-load equilibrium (numba).

The same damped Newton iteration as the numpy reference of
:func:`piezobearing.bearing.surrogate.quasi_static_loads` (``method="numpy"``),
written row by row as scalar loops so that numba compiles it. The reference
is vectorised over the rows, but a row's iterates depend on that row alone,
so running each row to convergence on its own takes the same steps and line
searches; each row's sums over the rollers are added in numpy's order
(:func:`_rsum`). What differs: numpy's ``power`` and ``hypot`` use the CPU's
SIMD implementations (SVML on AVX-512), this code the C library's, so a
load can differ in its last bit, and after the iterations by up to the
equilibrium's tolerance. The reference spends its time in numpy's per-call
overhead on small arrays (rows still iterating, trials of the line search)
and in temporaries of (n, Z) arrays. ``cache=True`` keeps the compiled code
in ``__pycache__``: only the first process of an installation compiles.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _rsum(x, z):  # pragma: no cover - compiled
    """Sum of x[0:z] in numpy's order for a row of at most 128 (its pairwise sum: 8 partial sums, then the rest)."""
    if z < 8:
        res = 0.0
        for j in range(z):
            res += x[j]
        return res
    r0, r1, r2, r3, r4, r5, r6, r7 = x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]
    i = 8
    while i < z - (z % 8):
        r0 += x[i]
        r1 += x[i + 1]
        r2 += x[i + 2]
        r3 += x[i + 3]
        r4 += x[i + 4]
        r5 += x[i + 5]
        r6 += x[i + 6]
        r7 += x[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < z:
        res += x[i]
        i += 1
    return res


@njit(cache=True)
def _state(e0, e1, s, c, drop, gap, k_contact, f_r, q, dq, tmp, tmp2, out):  # pragma: no cover - compiled
    """One row's loads q, slopes dq (Z) at the offset (e0, e1); out = (f_y, f_z, potential)."""
    z = s.shape[0]
    kdq = (10.0 / 9.0) * k_contact
    for j in range(z):
        delta = ((e0 * s[j] + e1 * c[j]) - gap) - drop[j]
        if delta > 0.0:
            d19 = delta ** (1.0 / 9.0)
            q[j] = k_contact * delta * d19
            dq[j] = kdq * d19
        else:
            q[j] = 0.0
            dq[j] = 0.0
        tmp[j] = q[j] * delta  # 0 where unloaded, as numpy's q <delta>
        tmp2[j] = q[j] * s[j]
    out[2] = _rsum(tmp, z) * (9.0 / 19.0) - e1 * (-f_r)
    out[0] = _rsum(tmp2, z)
    for j in range(z):
        tmp2[j] = q[j] * c[j]
    out[1] = _rsum(tmp2, z) + f_r


@njit(cache=True)
def _soft_step(a, b, d, fy, fz, e0, e1, si, ci, di, gap, k_contact, f_r, reg_k):  # pragma: no cover - compiled
    """One near-singular row's step (the numpy reference's ``_newton_step``): Newton's along the stiff
    direction, then down the soft one to just past the first roller it brings into contact; without a roller
    ahead, the step of the Hessian with a floor of stiffness ``reg_k``."""
    z = si.shape[0]
    tr = a + d
    lam = 0.5 * tr + math.sqrt(0.25 * (a - d) ** 2 + b * b)
    if abs(lam - d) >= abs(lam - a):
        u1, u2 = lam - d, b
    else:
        u1, u2 = b, lam - a
    nu = math.hypot(u1, u2)
    if nu <= 0.0:
        u1, u2 = 1.0, 0.0
    else:
        u1, u2 = u1 / nu, u2 / nu
    stiff = (fy * u1 + fz * u2) / lam if lam > 0.0 else 0.0
    b0, b1 = -stiff * u1, -stiff * u2
    v1, v2 = -u2, u1
    gv = fy * v1 + fz * v2
    sign = 1.0 if gv < 0.0 else (-1.0 if gv > 0.0 else 0.0)
    if lam > 0.0:
        dy, dz = sign * v1, sign * v2
    else:
        dy, dz = -fy, -fz
    dn = math.hypot(dy, dz)
    if dn > 0.0:
        dy, dz = dy / dn, dz / dn
    ey, ez = e0 + b0, e1 + b1
    t_in = np.inf
    r_in = 0.0
    for j in range(z):
        delta = ((ey * si[j] + ez * ci[j]) - gap) - di[j]
        rate = dy * si[j] + dz * ci[j]
        if delta < 0.0 and rate > 0.0:
            tj = -delta / rate
            if tj < t_in:
                t_in, r_in = tj, rate
    moving = gv != 0.0 or lam <= 0.0
    if not moving:
        return b0, b1
    if t_in < np.inf:
        length = t_in + min((f_r / k_contact) ** 0.9 / r_in, t_in)
        return b0 + length * dy, b1 + length * dz
    reg = 1e-9 * tr + reg_k
    a, d = a + reg, d + reg
    det = a * d - b * b
    return -((d * fy - b * fz) / det), -((-b * fy + a * fz) / det)


@njit(cache=True)
def newton_rows(s, c, drop, e, reach, gap, k_contact, f_r, thr, reg_k, q_out):  # pragma: no cover - compiled
    """Solve every row's equilibrium from its start offset ``e`` (n, 2), overwritten with the solution.

    Parameters
    ----------
    s, c : ndarray (n, Z)
        sin psi and -cos psi of the rollers [-].
    drop : ndarray (n, Z)
        Extra gaps [m].
    e : ndarray (n, 2)
        Start offsets in, equilibrium offsets out [m].
    reach : ndarray (n,)
        Longest Newton step of each row [m].
    gap, k_contact, f_r : float
        P_d / 2 [m], K [N / m^(10/9)], F_r [N].
    thr : float
        Force residual below which a row has converged [N].
    reg_k : float
        The constant floor of stiffness where the Hessian is near singular and no roller is ahead [N/m].
    q_out : ndarray (n, Z)
        Roller loads [N], written.

    Returns
    -------
    norm : ndarray (n,)
        Each row's final force residual [N].
    evaluations : int
        Equilibrium evaluations (rows times trials) in all.
    """
    n, z = s.shape
    q = np.empty(z)
    dq = np.empty(z)
    qt = np.empty(z)
    dqt = np.empty(z)
    tmp = np.empty(z)
    tmp2 = np.empty(z)
    st = np.empty(3)
    stt = np.empty(3)
    norm_out = np.empty(n)
    evaluations = 0
    for i in range(n):
        si, ci, di = s[i], c[i], drop[i]
        e0, e1 = e[i, 0], e[i, 1]
        _state(e0, e1, si, ci, di, gap, k_contact, f_r, q, dq, tmp, tmp2, st)
        evaluations += 1
        for _ in range(200):
            fy, fz, pot = st[0], st[1], st[2]
            norm = math.hypot(fy, fz)
            if not norm > thr:
                break
            for j in range(z):
                tmp[j] = (dq[j] * si[j]) * si[j]
            a = _rsum(tmp, z)
            for j in range(z):
                tmp[j] = (dq[j] * si[j]) * ci[j]
            b = _rsum(tmp, z)
            for j in range(z):
                tmp[j] = (dq[j] * ci[j]) * ci[j]
            d = _rsum(tmp, z)
            if a * d - b * b > 1e-6 * (a + d) * (a + d):
                det = a * d - b * b
                s0 = -((d * fy - b * fz) / det)
                s1 = -((-b * fy + a * fz) / det)
            else:
                s0, s1 = _soft_step(a, b, d, fy, fz, e0, e1, si, ci, di, gap, k_contact, f_r, reg_k)
            length = math.hypot(s0, s1)
            scale = min(1.0, reach[i] / max(length, 1e-300))
            s0 *= scale
            s1 *= scale
            slope = fy * s0 + fz * s1
            # the line search: the full step, then just past the first roller it brings into contact, then halved
            lam = 1.0
            t0, t1 = e0 + s0, e1 + s1
            _state(t0, t1, si, ci, di, gap, k_contact, f_r, qt, dqt, tmp, tmp2, stt)
            evaluations += 1
            bad = (stt[2] > pot + 1e-4 * lam * slope) and (math.hypot(stt[0], stt[1]) >= norm)
            for trial in range(59):
                if not bad:
                    break
                if trial == 0:
                    engage = np.inf
                    for j in range(z):
                        sn = s0 * si[j] + s1 * ci[j]
                        d0 = ((e0 * si[j] + e1 * ci[j]) - gap) - di[j]
                        if d0 < 0.0 and sn > 0.0:
                            engage = min(engage, -d0 / sn)
                    lam = min(max(1.1 * engage, 0.01), 0.5) * lam
                else:
                    lam = 0.5 * lam
                t0, t1 = e0 + lam * s0, e1 + lam * s1
                _state(t0, t1, si, ci, di, gap, k_contact, f_r, qt, dqt, tmp, tmp2, stt)
                evaluations += 1
                bad = (stt[2] > pot + 1e-4 * lam * slope) and (math.hypot(stt[0], stt[1]) >= norm)
            e0, e1 = t0, t1
            for j in range(z):
                q[j] = qt[j]
                dq[j] = dqt[j]
            st[0], st[1], st[2] = stt[0], stt[1], stt[2]
        e[i, 0], e[i, 1] = e0, e1
        norm_out[i] = math.hypot(st[0], st[1])
        for j in range(z):
            q_out[i, j] = q[j]
    return norm_out, evaluations
