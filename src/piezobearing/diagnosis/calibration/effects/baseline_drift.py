"""``baseline_drift``: a slow additive drift of the voltage, its shape chosen by the evidence.

Physics
-------
PZT is pyroelectric (p of about 4e-4 C/(m^2 K) for PZT-5A): a hand or a rod
warming the disk drives a current p A dT/dt through R, i.e. a voltage
R p A dT/dt. With A = 17.3 mm^2 and R = 50 MOhm, a warming of 0.1 K/s gives
about 35 mV that follows the slow temperature history. Amplifier offsets
and thermal EMFs add a constant or slowly varying term. Against the
impulses (about a second) these are smooth, but a temperature history need
not be a cubic: a hand resting on the fixture, then taken away, draws a
drift that changes course within the record (piecewise over seconds to
tens of seconds).

Model
-----
A cubic spline over the record (x from -1 at its start to +1 at its end)
with K interior knots spaced evenly, written as the Legendre cubic plus
K wandering terms:

.. math::  V_{drift}(t) = \\sum_{k=0}^{3} c_k P_k(x) + \\sum_{j=1}^{K} w_j b_j(x),

b_j the truncated powers (x - x_j)_+^3 at the knots made orthogonal to the
cubic and to each other over the record's samples and scaled to rms 1: the
``drift_p{k}_V`` keep their meaning (the Legendre coefficients of the
drift's cubic part; with K = 0 the model is the cubic of earlier
versions) and ``drift_w{j}_V`` is the rms of the j-th wandering term. K is
chosen by the evidence: the search fits every K of :data:`KNOTS` that keeps
the knots at least :data:`MIN_KNOT_SPACING_S` apart (:meth:`variants`) and
keeps the one of lowest BIC (each knot costs ln n). The spacing floor keeps
the drift slower than a press (about a second), so that it cannot take the
shape of the force's response.

A drift with a kink (heat switched on or off abruptly: the pyroelectric
voltage, R p A dT/dt through the thermal lags, starts with a jump of its
slope) is not a spline on fixed knots. Once the knot count is chosen, the
search tries a kink on that spline (:meth:`refinements`): three truncated
terms ((x - x_k)_+ / (1 - x_k))^d, d = 1, 2, 3 (a jump of slope, curvature
and third derivative at the kink), with the kink's time ``drift_kink_s``
fitted (at least :data:`KINK_MARGIN_S` from the ends; started at the best
two of the trial times :data:`KINK_GRID_S` apart), then the kink with more
knots in turn, each kept while it lowers BIC (four parameters more: 4 ln n).

Additive: it does not change the response. Start values: linear least
squares of the current residual.

Parameters: ``drift_p0_V`` ... ``drift_p3_V`` and ``drift_w1_V`` ...
``drift_wK_V``, each in [-10, 10] V; with a kink ``drift_kink_s`` and
``drift_k1_V`` ... ``drift_k3_V`` (each term's change of the drift by the
record's end).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import legendre

from ....fitting.params import Param
from .base import Effect, ForceRecord, StartContext

DEGREE = 3
#: Interior knot counts the evidence chooses from (0: the Legendre cubic alone).
KNOTS = (0, 1, 2, 4, 8)
#: Closest spacing of the knots [s]: a drift stays slower than a press (rise and fall ~1 s).
MIN_KNOT_SPACING_S = 2.0
#: Powers of the kink's truncated terms (x - x_k)_+^d: a jump of slope, curvature and third derivative.
KINK_DEGREES = (1, 2, 3)
#: Closest distance of the kink to the record's ends [s] (there the cubic already bends freely).
KINK_MARGIN_S = 1.0
#: Spacing of the trial kink times the start values are chosen from [s].
KINK_GRID_S = 0.25
#: How many of the best trial kink times start the fit.
KINK_STARTS = 2


def basis(record: ForceRecord, knots: int = 0) -> np.ndarray:
    """Legendre polynomials P_0..P_3 over the record and ``knots`` wandering terms (module docstring) [-]."""
    key = ("drift_basis", knots)
    if key not in record._cache:
        t = record.time_s
        x = 2 * (t - t[0]) / (t[-1] - t[0]) - 1
        cubic = legendre.legvander(x, DEGREE)
        if knots == 0:
            record._cache[key] = cubic
        else:
            xj = -1 + 2 * np.arange(1, knots + 1) / (knots + 1)
            tp = np.clip(x[:, None] - xj[None, :], 0.0, None) ** 3
            q, _ = np.linalg.qr(np.hstack([cubic, tp]))
            w = q[:, DEGREE + 1 :] * np.sqrt(x.size)  # orthonormal to the cubic and each other, rms 1
            record._cache[key] = np.hstack([cubic, w])
    return record._cache[key]


def _x(record: ForceRecord, t_s) -> np.ndarray:
    """Time [s] mapped onto the record's x in [-1, 1]."""
    t = record.time_s
    return 2 * (np.asarray(t_s, dtype=float) - t[0]) / (t[-1] - t[0]) - 1


def kink_basis(record: ForceRecord, kink_s: float) -> np.ndarray:
    """The kink's terms ((x - x_k)_+ / (1 - x_k))^d, d of :data:`KINK_DEGREES`: 0 before the kink, 1 at the
    record's end (a coefficient is the drift's change by the record's end from that term) [-]."""
    xk = float(_x(record, kink_s))
    u = np.clip(_x(record, record.time_s) - xk, 0.0, None) / (1.0 - xk)
    return np.column_stack([u**d for d in KINK_DEGREES])


class BaselineDrift(Effect):
    name = "baseline_drift"
    title = "slow additive drift (pyroelectric/thermal)"
    order = 310
    example = {"drift_p0_V": 0.005, "drift_p1_V": 0.02, "drift_p2_V": -0.01, "drift_p3_V": 0.005}
    example_reason = (
        "pyroelectric current p A dT/dt through R: 0.1 K/s of warming gives ~35 mV at 50 MOhm; "
        "a 20 mV linear term with offset and curvature"
    )
    additive_only = True
    physics = (
        "PZT is pyroelectric: a hand or rod warming the disk drives a current p A dT/dt through R (about "
        "35 mV for 0.1 K/s at R = 50 MOhm), and offsets and thermal EMFs add to it. The model adds a smooth "
        "curve to the voltage: a cubic spline over the record (the Legendre cubic plus wandering terms at "
        "knots at least 2 s apart), its number of knots chosen by the evidence (BIC), and a kink at a fitted time "
        "(heat switched on or off abruptly) where the evidence asks for it."
    )

    def __init__(self, knots: int = 0, kink: bool = False) -> None:
        self.knots = int(knots)
        self.kink = bool(kink)

    def _kink_range(self, record: ForceRecord) -> tuple[float, float]:
        t = record.time_s
        return float(t[0] + KINK_MARGIN_S), float(t[-1] - KINK_MARGIN_S)

    def params(self, record: ForceRecord) -> list[Param]:
        cubic = [
            Param(f"drift_p{k}_V", 0.0, -10.0, 10.0, scale=1e-3, description=f"Legendre coefficient {k} of the drift [V]")
            for k in range(DEGREE + 1)
        ]
        wander = [
            Param(f"drift_w{j}_V", 0.0, -10.0, 10.0, scale=1e-3, description=f"rms of wandering term {j} of the drift [V]")
            for j in range(1, self.knots + 1)
        ]
        kink = []
        if self.kink:
            lo, hi = self._kink_range(record)
            kink = [Param("drift_kink_s", 0.5 * (lo + hi), lo, hi, description="time of the drift's kink [s]")]
            kink += [
                Param(f"drift_k{d}_V", 0.0, -10.0, 10.0, scale=1e-3, description=f"kink term (x - x_k)_+^{d}: its change of the drift by the record's end [V]")
                for d in KINK_DEGREES
            ]
        return cubic + wander + kink

    def refinements(self, ctx: StartContext) -> list["BaselineDrift"]:
        """The chosen spline with a kink at a fitted time (heat switched on or off abruptly), then with the
        kink and more knots in turn (the kink took the misfit that stopped the knots), where the record is
        long enough to hold it."""
        lo, hi = self._kink_range(ctx.record)
        if self.kink or hi <= lo:
            return []
        return [BaselineDrift(k, kink=True) for k in self._knot_counts(ctx.record) if k >= self.knots]

    def _knot_counts(self, record: ForceRecord) -> list[int]:
        """The knot counts of :data:`KNOTS` that keep the knots :data:`MIN_KNOT_SPACING_S` apart."""
        d = float(record.time_s[-1] - record.time_s[0])
        return [k for k in KNOTS if d / (k + 1) >= MIN_KNOT_SPACING_S]

    def variants(self, ctx: StartContext) -> list["BaselineDrift"]:
        """The drift with each knot count of :data:`KNOTS` the record's length allows (the search keeps the
        one of lowest BIC)."""
        return [self if k == self.knots else BaselineDrift(k) for k in self._knot_counts(ctx.record)]

    def _coef(self, values: dict) -> np.ndarray:
        return np.array(
            [values[f"drift_p{k}_V"] for k in range(DEGREE + 1)]
            + [values[f"drift_w{j}_V"] for j in range(1, self.knots + 1)]
        )

    def additive(self, values, record):
        v = basis(record, self.knots) @ self._coef(values)
        if self.kink:
            v = v + kink_basis(record, values["drift_kink_s"]) @ np.array([values[f"drift_k{d}_V"] for d in KINK_DEGREES])
        return v

    def linear_basis(self, values, record):
        """The spline's columns and, with a kink, the kink's terms at its time (the voltage is linear in both)."""
        names = tuple(f"drift_p{k}_V" for k in range(DEGREE + 1)) + tuple(f"drift_w{j}_V" for j in range(1, self.knots + 1))
        out = [(names, basis(record, self.knots), ("drift", self.knots))]
        if self.kink:
            tk = float(values["drift_kink_s"])
            out.append((tuple(f"drift_k{d}_V" for d in KINK_DEGREES), kink_basis(record, tk), ("drift_kink", tk)))
        return out

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        """Linear least squares of the current residual; with a kink, at the :data:`KINK_STARTS` best of the
        trial times :data:`KINK_GRID_S` apart."""
        b = basis(ctx.record, self.knots)
        names = [p.name for p in self.params(ctx.record)]
        if not self.kink:
            coef, *_ = np.linalg.lstsq(b, ctx.residual_V, rcond=None)
            return [{n: float(np.clip(c, -10, 10)) for n, c in zip(names, coef, strict=True)}]
        lo, hi = self._kink_range(ctx.record)
        q, _ = np.linalg.qr(b)  # the spline's span, once: each trial kink is three columns against it
        r = ctx.residual_V - q @ (q.T @ ctx.residual_V)
        gain = []
        grid = np.arange(lo, hi + 1e-9, KINK_GRID_S)
        for tk in grid:
            h = kink_basis(ctx.record, tk)
            h = h - q @ (q.T @ h)
            c, *_ = np.linalg.lstsq(h, r, rcond=None)
            gain.append(float(np.dot(h @ c, r)))  # the residual's energy the kink takes beyond the spline
        out = []
        for tk in grid[np.argsort(gain)[::-1][:KINK_STARTS]]:
            a = np.hstack([b, kink_basis(ctx.record, tk)])
            coef, *_ = np.linalg.lstsq(a, ctx.residual_V, rcond=None)
            lin = [n for n in names if n != "drift_kink_s"]
            out.append({"drift_kink_s": tk, **{n: float(np.clip(c, -10, 10)) for n, c in zip(lin, coef, strict=True)}})
        return out

    def summary(self, values):
        knots = sum(1 for k in values if k.startswith("drift_w"))
        if "drift_kink_s" in values:  # the cubic's and the kink's terms trade off: their sizes are not the drift's
            return (
                f"a drift with a kink at t = {values['drift_kink_s']:.2f} s (heat switched on or off) on a cubic "
                f"spline with {knots} knots"
            )
        span = 2 * math.sqrt(sum(values[f"drift_p{k}_V"] ** 2 for k in range(1, DEGREE + 1)))
        wander = math.sqrt(sum(v**2 for k, v in values.items() if k.startswith("drift_w")))
        more = f"; {knots} knots, wandering {wander * 1e3:.2f} mV rms" if knots else ""
        return f"offset = {values['drift_p0_V'] * 1e3:.2f} mV, drift of the order of {span * 1e3:.2f} mV{more}"


EFFECT = BaselineDrift()
