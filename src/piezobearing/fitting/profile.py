"""Profile-likelihood intervals, computed where the Jacobian's are not honest.

The fit's 95% intervals (:func:`~piezobearing.fitting.least_squares.fit`)
come from the Gauss-Newton covariance: they take the cost as quadratic in the
fit's internal coordinates. For a parameter near a bound, a strongly
nonlinear one (a corner frequency, a lag) or a pair that trades off along a
curved valley, that is not so, and the interval can be far too narrow or
too wide. The profile interval does not assume it: with p_i fixed at u and
every other free parameter refitted,

    P(u) = min chi2(u, others) - chi2_min,

and the interval is where P(u) <= D, D = s^2 t^2 (s^2 = chi2_min / (n - k),
t the two-sided Student-t quantile): the same threshold that makes the
Jacobian interval exact for a model linear in its parameters, so the two
agree whenever the quadratic picture holds (for the diagnosis's likelihood,
chi2 ~ n for a correct model and D ~ 3.84 at 95%).

:func:`honest_intervals` first checks each parameter cheaply: along the line
on which a quadratic cost has its profile (u* + d cov[:, i] / cov[i, i]) it
evaluates the cost at the Jacobian interval's two ends (two residual
evaluations, no refit). Where chi2 there rises by D within ``tolerance``
(25%), the Jacobian interval is kept ("jacobian (checked)"); elsewhere, or
where the interval reaches a bound, :func:`profile_interval` finds the ends
by refitting (a few refits per end). Both functions work on any residual
function and parameter list of :func:`~piezobearing.fitting.least_squares.fit`:
the engine uses them on the final model of a diagnosis (every subject).

A residual that is not white (model error with structure in time, coloured
noise) holds fewer independent samples than its length, and both intervals
above are then too narrow. Given a factor f_i on each parameter's variance
(``inflation``: :func:`~piezobearing.fitting.correlation.correlation_factors`,
the residual's autocorrelation read where the parameter's Jacobian column
lives), the Jacobian interval's half-width is taken sqrt(f_i) times wider and
the threshold D_i = f_i D, in the check and in the profile alike (Royall &
Tsou's robust adjusted profile likelihood): for a quadratic cost the two stay
equal, as without it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Sequence

import numpy as np
from scipy.special import stdtrit

from .least_squares import FitResult, InfeasibleError, fit
from .params import Param

#: |rise of chi2 at a Jacobian interval's end / D - 1| above which the interval is profiled instead.
TOLERANCE = 0.25


@dataclass
class ProfileInterval:
    """The interval of one parameter [unit of its name] and how it was found.

    Attributes
    ----------
    name : str
    value : float
        Best-fit value.
    ci : list of float
        [lower, upper] at ``level``: the profile's, or the Jacobian's when it passed the check.
    jacobian_ci : list of float
        The Gauss-Newton (Jacobian) interval at the same level.
    method : str
        ``"jacobian (checked)"`` or ``"profile"``.
    rise : list of float
        Rise of chi2 over D at the two ends of the Jacobian interval (1 = quadratic cost) [-].
    at_bound : list of bool
        Whether the lower / upper end is the parameter's bound (the data do not close the interval there).
    refits : int
        Number of refits spent.
    factor : float or None
        The factor on the variance for the residual's autocorrelation the interval was widened by
        (:mod:`~piezobearing.fitting.correlation`; its half-width by its square root) [-]; None: not corrected.
    """

    name: str
    value: float
    ci: list[float]
    jacobian_ci: list[float]
    method: str
    rise: list[float] = field(default_factory=list)
    at_bound: list[bool] = field(default_factory=lambda: [False, False])
    refits: int = 0
    factor: float | None = None

    def report(self) -> dict:
        out = {
            "value": self.value,
            "ci": self.ci,
            "jacobian_ci": self.jacobian_ci,
            "method": self.method,
            "rise_at_jacobian_ends": self.rise,
            "at_bound": self.at_bound,
            "refits": self.refits,
        }
        if self.factor is not None:
            out["correlation_factor"] = self.factor
        return out


class _Profile:
    """The cost of a fitted problem as a function of one parameter (internal coordinate u)."""

    def __init__(self, residual_fn, params, result, name, level, max_nfev, ftol, inflation=1.0):
        self.fn, self.result, self.max_nfev, self.ftol = residual_fn, result, max_nfev, ftol
        self.free = [p for p in params if p.vary]
        self.fixed = [p for p in params if not p.vary]
        self.i = [p.name for p in self.free].index(name)
        self.p = self.free[self.i]
        dof = max(result.n_data - result.n_free, 1)
        tq = float(stdtrit(dof, 0.5 + level / 2))  # scipy.stats.t.ppf, bit for bit, without scipy.stats' import
        self.delta = result.chi2 / dof * tq**2 * inflation
        self.u0 = self.p.to_internal(result.values[name])
        self.lo = self.p.to_internal(self.p.lower) if np.isfinite(self.p.lower) else -np.inf
        self.hi = self.p.to_internal(self.p.upper) if np.isfinite(self.p.upper) else np.inf
        self.refits = 0
        self.warm: dict | None = None  # the last refit's values (a second start), None before the first
        cov = _internal_cov(result, self.free)
        self.ustar = np.array([q.to_internal(result.values[q.name]) for q in self.free])
        self.line = (
            cov[:, self.i] / cov[self.i, self.i]
            if cov[self.i, self.i] > 0
            else np.eye(len(self.free))[self.i]
        )

    def chi2_at(self, values: dict) -> float:
        try:
            r = np.asarray(self.fn(values), dtype=float)
        except InfeasibleError:
            return np.inf
        return float(r @ r)

    def refit(self, u: float) -> float:
        """P(u): chi2 with the parameter fixed at u and the others refitted, minus chi2_min."""
        # start the others on the quadratic profile line (where they compensate the fixed parameter along a
        # correlated valley), and from the last refit; keep the better
        along = self.ustar + (u - self.u0) * self.line
        best = None
        starts = [{q.name: q.to_physical(a) for q, a in zip(self.free, along, strict=True)}]
        for start in starts + ([self.warm] if self.warm is not None else []):
            ps = [
                replace(q, vary=False).with_value(q.to_physical(u))
                if j == self.i
                else q.with_value(start[q.name])
                for j, q in enumerate(self.free)
            ]
            self.refits += 1
            try:
                res = fit(self.fn, [*ps, *self.fixed], max_nfev=self.max_nfev, ftol=self.ftol)
            except InfeasibleError:  # no solution of the model at this start: the other start, or none
                continue
            if best is None or res.chi2 < best.chi2:
                best = res
        if best is None:  # the model has no solution with the parameter at u: outside any interval
            return np.inf
        self.warm = dict(best.values)
        return best.chi2 - self.result.chi2

    def end(self, side: int, u_start: float, p_start: float | None) -> tuple[float, bool]:
        """The end on ``side`` (-1 lower, +1 upper) where P = D: bracket outward (doubling the step), then
        regula falsi on sqrt(P); (the bound, True) when P stays below D up to it."""
        bound = self.lo if side < 0 else self.hi
        target = np.sqrt(self.delta)
        a, fa = self.u0, 0.0  # P(u0) = 0
        b = u_start
        fb = np.sqrt(max(self.refit(b), 0.0)) if p_start is None else np.sqrt(max(p_start, 0.0))
        step, grown = abs(b - a), 0
        while fb < target:  # bracket: grow the step until P >= D or the bound is reached
            if (b - bound) * side >= 0:
                return bound, True
            if grown == 16:
                return b, False
            a, fa = b, fb
            step *= 2.0
            grown += 1
            b = float(np.clip(b + side * step, min(bound, b), max(bound, b)))
            fb = np.sqrt(max(self.refit(b), 0.0))
        self.warm = None
        # Illinois regula falsi on g = sqrt(P) - sqrt(D) (nearly linear in u for a near-quadratic cost; it
        # converges also where P is flat and then rises steeply, as along a valley ending at a bound)
        ga, gb, last = fa - target, fb - target, 0
        c = b
        for _ in range(12):
            c = (a * gb - b * ga) / (gb - ga)
            gc = np.sqrt(max(self.refit(c), 0.0)) - target
            if abs(gc) < 0.01 * target:
                break
            if gc > 0:
                b, gb = c, gc
                ga, last = (0.5 * ga if last == 1 else ga), 1
            else:
                a, ga = c, gc
                gb, last = (0.5 * gb if last == -1 else gb), -1
        return float(c), False


def _wald(result: FitResult, p: Param, inflation: float = 1.0) -> tuple[float, float, tuple, tuple]:
    """u*, half-width (internal) of the Jacobian interval widened by sqrt(``inflation``), its physical ends, and
    the Gauss-Newton interval's (the fit's ``ci95``)."""
    u0 = p.to_internal(result.values[p.name])
    lo, hi = result.ci95[p.name]
    w = 0.5 * (p.to_internal(hi) - p.to_internal(lo))
    if inflation == 1.0:
        return u0, w, (lo, hi), (lo, hi)
    w = w * float(np.sqrt(inflation))
    return u0, w, (p.to_physical(u0 - w), p.to_physical(u0 + w)), (lo, hi)


def profile_interval(
    residual_fn: Callable[[dict[str, float]], np.ndarray],
    params: Sequence[Param],
    result: FitResult,
    name: str,
    level: float = 0.95,
    max_nfev: int | None = None,
    ftol: float = 1e-8,
    inflation: float | None = None,
) -> ProfileInterval:
    """The profile-likelihood interval of ``name`` (see the module docstring).

    ``residual_fn`` and ``params`` are those ``result`` was fitted with
    (:func:`~piezobearing.fitting.least_squares.fit`); ``result`` must hold
    the Jacobian intervals at 95% (``result.ci95``), which set the first
    trial ends. An end that reaches the parameter's bound before chi2 has
    risen by D is reported as the bound (``at_bound``). ``inflation``: the
    factor on the parameter's variance for a residual that is not white (the
    threshold is f D; None: 1, not reported).
    """
    f = 1.0 if inflation is None else float(inflation)
    pr = _Profile(residual_fn, params, result, name, level, max_nfev, ftol, f)
    u0, w, _, jac = _wald(result, pr.p, f)
    w = w if np.isfinite(w) and w > 0 else max(abs(u0) * 1e-3, 1e-6)
    w *= float(stdtrit(10**6, 0.5 + level / 2) / stdtrit(10**6, 0.975))
    lo, lo_b = pr.end(-1, max(u0 - w, pr.lo), None)
    pr.warm = None
    hi, hi_b = pr.end(+1, min(u0 + w, pr.hi), None)
    return ProfileInterval(
        name,
        result.values[name],
        [pr.p.to_physical(lo), pr.p.to_physical(hi)],
        list(jac),
        "profile",
        [],
        [lo_b, hi_b],
        pr.refits,
        inflation,
    )


def _rise_along_line(
    residual_fn, result: FitResult, free: list[Param], i: int, cov: np.ndarray, delta: float, w: float
) -> list[float]:
    """chi2 rise over D at u*_i -+ w along the quadratic profile line u* + d cov[:, i] / cov[i, i]."""
    u0 = np.array([p.to_internal(result.values[p.name]) for p in free])
    out = []
    for d in (-w, w):
        u = u0 + d * cov[:, i] / cov[i, i]
        vals = dict(result.values)
        inside = True
        for p, ui in zip(free, u, strict=True):
            x = p.to_physical(ui)
            inside &= p.lower <= x <= p.upper
            vals[p.name] = x
        if not inside:
            out.append(float("nan"))
            continue
        r = np.asarray(residual_fn(vals), dtype=float)
        out.append(float((r @ r - result.chi2) / delta))
    return out


def honest_intervals(
    residual_fn: Callable[[dict[str, float]], np.ndarray],
    params: Sequence[Param],
    result: FitResult,
    names: Sequence[str] | None = None,
    tolerance: float = TOLERANCE,
    max_profiles: int = 6,
    max_nfev: int | None = None,
    ftol: float = 1e-8,
    max_evaluations: int | None = None,
    inflation: dict[str, float] | None = None,
) -> dict[str, ProfileInterval]:
    """95% intervals of ``names`` (default: every free parameter), profiled where the Jacobian's are not honest.

    Each Jacobian interval is checked along the quadratic profile line (two
    residual evaluations); one whose ends raise chi2 by D outside
    [1 - ``tolerance``, 1 + ``tolerance``] times D, or reach a bound, is
    replaced by :func:`profile_interval`, at most ``max_profiles`` of them
    (the worst first; the others keep the Jacobian's with ``method``
    ``"jacobian (not honest; not profiled)"``), and at most
    ``max_evaluations`` residual evaluations in all (checks and profiles; a
    profile that would go beyond them is stopped and its parameter keeps the
    Jacobian's interval, ``method`` ``"jacobian (not honest; profile over
    budget)"``), so the cost stays bounded for a model of many parameters
    whose every evaluation runs a long forward model.

    ``inflation``: a factor on each parameter's variance for a residual that
    is not white (:func:`~piezobearing.fitting.correlation.correlation_factors`;
    see the module docstring): the checked interval is the Jacobian's widened
    by its square root, the check and the profile use the threshold times
    the factor, and each interval reports it (``correlation_factor``); a
    parameter it does not name keeps 1. None: no correction, nothing reported.
    """
    budget = _Budget(residual_fn, max_evaluations)
    residual_fn = budget
    free = [p for p in params if p.vary]
    index = {p.name: j for j, p in enumerate(free)}
    names = [n for n in (names if names is not None else index) if n in index]
    dof = max(result.n_data - result.n_free, 1)
    delta = result.chi2 / dof * float(stdtrit(dof, 0.975)) ** 2
    cov = _internal_cov(result, free)
    out: dict[str, ProfileInterval] = {}
    suspect = []
    for n in names:
        i, p = index[n], free[index[n]]
        f = None if inflation is None else float(inflation.get(n, 1.0))
        u0, w, ends, jac = _wald(result, p, 1.0 if f is None else f)
        ok = np.isfinite(w) and w > 0 and cov[i, i] > 0
        d_i = delta if f is None else delta * f
        rise = _rise_along_line(residual_fn, result, free, i, cov, d_i, w) if ok else [float("nan")] * 2
        out[n] = ProfileInterval(n, result.values[n], list(ends), list(jac), "jacobian (checked)", rise, factor=f)
        bad = [abs(r - 1.0) if np.isfinite(r) else np.inf for r in rise]
        if max(bad) > tolerance:
            suspect.append((max(bad), n))
    for k, (_, n) in enumerate(sorted(suspect, reverse=True)):
        if k >= max_profiles:
            out[n].method = "jacobian (not honest; not profiled)"
            continue
        try:
            prof = profile_interval(residual_fn, params, result, n, max_nfev=max_nfev, ftol=ftol,
                                    inflation=out[n].factor)
        except BudgetSpent:
            out[n].method = "jacobian (not honest; profile over budget)"
            continue
        prof.rise = out[n].rise
        out[n] = prof
    return out


class BudgetSpent(Exception):
    """Raised by :class:`_Budget` when the evaluations allowed are spent."""


class _Budget:
    """``residual_fn`` counted: raises :class:`BudgetSpent` past ``limit`` calls (None: no limit)."""

    def __init__(self, fn: Callable[[dict[str, float]], np.ndarray], limit: int | None):
        self.fn, self.limit, self.calls = fn, limit, 0

    def __call__(self, values: dict[str, float]) -> np.ndarray:
        if self.limit is not None and self.calls >= self.limit:
            raise BudgetSpent
        self.calls += 1
        return self.fn(values)


def _internal_cov(result: FitResult, free: list[Param]) -> np.ndarray:
    """The Gauss-Newton covariance in internal coordinates, from the fit's standard errors and correlations."""
    sd = np.array(
        [
            result.stderr[p.name] / (np.log(10) * result.values[p.name] if p.log else p.scale)
            if result.stderr.get(p.name) is not None
            else np.nan
            for p in free
        ]
    )
    corr = np.array([[result.correlation[a.name][b.name] for b in free] for a in free])
    cov = corr * np.outer(sd, sd)
    return np.nan_to_num(cov)
