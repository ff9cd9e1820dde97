"""Many bounded scalar minimisations at once: Brent's method as scipy's ``minimize_scalar(method="bounded")``,
one problem per array entry.

The outer-race test (:mod:`.baseline`) minimises over the phase of the roller
train and over the fundamental, several starts per record, for every record
of a Monte Carlo or a classification: thousands of small searches whose
functions cost little each. Run one at a time, the Python around each
evaluation costs more than the evaluation; here all problems step together
and the function is asked for the still-active problems' points as one array.
Each problem takes scipy 1.17's ``_minimize_scalar_bounded`` steps exactly
(golden section with parabolic steps, ``xatol`` as there, at most ``maxiter``
evaluations): the same points and the same minimum, bit for bit, as a
separate scipy call (test), since every step is the same elementwise IEEE
arithmetic.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

_SQRT_EPS = np.sqrt(2.2e-16)
_GOLDEN = 0.5 * (3.0 - np.sqrt(5.0))


def _sign1(v: np.ndarray) -> np.ndarray:
    """np.sign(v) + (v == 0): +-1, 1 at zero."""
    return np.sign(v) + (v == 0)


def fminbound_many(func: Callable[[np.ndarray, np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray,
                   xatol, maxiter: int = 500) -> tuple[np.ndarray, np.ndarray]:
    """Minimise P scalar functions, problem i on [lo_i, hi_i]: (x (P,), f(x) (P,)).

    Parameters
    ----------
    func : callable
        ``func(idx, x)``: the values of problems ``idx`` (int array) at the points ``x`` (same shape).
    lo, hi : ndarray (P,)
        The bounds.
    xatol : float or ndarray (P,)
        Absolute tolerance on x, as scipy's option of that name.
    maxiter : int
        Evaluations per problem at most.
    """
    a, b = np.array(lo, float, ndmin=1), np.array(hi, float, ndmin=1)
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise ValueError("Optimization bounds must be finite scalars.")
    if (a > b).any():
        raise ValueError("The lower bound exceeds the upper bound.")
    xatol = np.broadcast_to(np.asarray(xatol, float), a.shape)
    xf = a + _GOLDEN * (b - a)
    fulc, nfc = xf.copy(), xf.copy()
    rat, e = np.zeros_like(a), np.zeros_like(a)
    fx = np.asarray(func(np.arange(a.size), xf), float).copy()
    ffulc, fnfc = fx.copy(), fx.copy()
    num = np.ones(a.size, int)
    xm = 0.5 * (a + b)
    tol1 = _SQRT_EPS * np.abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    active = np.abs(xf - xm) > (tol2 - 0.5 * (b - a))
    while active.any():
        i = np.flatnonzero(active)
        ai, bi, xfi, xmi, t1, t2 = a[i], b[i], xf[i], xm[i], tol1[i], tol2[i]
        ei, rati = e[i], rat[i]
        golden = np.ones(i.size, bool)
        par = np.abs(ei) > t1  # a parabola through the three best points
        if par.any():
            fxi, nfci, fulci = fx[i], nfc[i], fulc[i]
            r = (xfi - nfci) * (fxi - ffulc[i])
            q = (xfi - fulci) * (fxi - fnfc[i])
            p = (xfi - fulci) * q - (xfi - nfci) * r
            q = 2.0 * (q - r)
            p = np.where(q > 0.0, -p, p)
            q = np.abs(q)
            r = ei
            ok = par & (np.abs(p) < np.abs(0.5 * q * r)) & (p > q * (ai - xfi)) & (p < q * (bi - xfi))
            ei = np.where(par, rati, ei)
            with np.errstate(divide="ignore", invalid="ignore"):
                step = (p + 0.0) / q
            xp = xfi + step
            near = ((xp - ai) < t2) | ((bi - xp) < t2)
            rati = np.where(ok, np.where(near, t1 * _sign1(xmi - xfi), step), rati)
            golden = ~ok
        ei = np.where(golden, np.where(xfi >= xmi, ai - xfi, bi - xfi), ei)
        rati = np.where(golden, _GOLDEN * ei, rati)
        x = xfi + _sign1(rati) * np.maximum(np.abs(rati), t1)
        fu = np.asarray(func(i, x), float)
        e[i], rat[i] = ei, rati
        num[i] += 1
        fxi, nfci, fnfci, fulci, ffulci = fx[i], nfc[i], fnfc[i], fulc[i], ffulc[i]
        better = fu <= fxi
        right = x >= xfi
        a[i] = np.where(better, np.where(right, xfi, ai), np.where(~right, x, ai))
        b[i] = np.where(better, np.where(right, bi, xfi), np.where(~right, bi, x))
        c1 = ~better & ((fu <= fnfci) | (nfci == xfi))
        c2 = ~better & ~c1 & ((fu <= ffulci) | (fulci == xfi) | (fulci == nfci))
        fulc[i] = np.where(better | c1, nfci, np.where(c2, x, fulci))
        ffulc[i] = np.where(better | c1, fnfci, np.where(c2, fu, ffulci))
        nfc[i] = np.where(better, xfi, np.where(c1, x, nfci))
        fnfc[i] = np.where(better, fxi, np.where(c1, fu, fnfci))
        xf[i] = np.where(better, x, xfi)
        fx[i] = np.where(better, fu, fxi)
        xm[i] = 0.5 * (a[i] + b[i])
        tol1[i] = _SQRT_EPS * np.abs(xf[i]) + xatol[i] / 3.0
        tol2[i] = 2.0 * tol1[i]
        active[i] = (np.abs(xf[i] - xm[i]) > (tol2[i] - 0.5 * (b[i] - a[i]))) & (num[i] < maxiter)
    return xf, fx
