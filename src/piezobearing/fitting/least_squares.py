"""Bounded nonlinear least squares with parameter objects and a fit report.

In the spirit of lmfit: each free parameter (:class:`~piezobearing.fitting.params.Param`)
has a value, bounds, a unit and a scale (``log`` for quantities that span
decades, such as a resistance). The fit runs in the internal coordinates
(log10 for ``log`` parameters), and the covariance from the Jacobian is
carried back to the physical values. The engine's likelihood fit of a
model (:mod:`piezobearing.diagnosis.fit`) and the calibration's fit of R
(:func:`piezobearing.sensor.calibration.fit_resistance`) both run on it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from scipy.special import stdtrit

from .params import Param


class InfeasibleError(ValueError):
    """A model has no solution at the values asked for (the bearing's rings without an equilibrium).

    A residual function raises it; :func:`fit` treats the point as infeasible: a trial step that lands there is
    refused (the trust region shrinks, the search steps back), a finite difference that lands there leaves its
    parameter out of that step's Jacobian, and a start value there raises it to the caller (which tries its
    next start).
    """


@dataclass
class FitResult:
    """Outcome of :func:`fit`: values, uncertainties and goodness of fit."""

    values: dict[str, float]
    stderr: dict[str, float]
    ci95: dict[str, list[float]]
    correlation: dict[str, dict[str, float]]
    residual: np.ndarray = field(repr=False)
    n_data: int = 0
    n_free: int = 0
    chi2: float = float("nan")
    success: bool = True
    message: str = ""
    #: sum ln h^2 of a non-stationary noise model (:meth:`NoiseFloor.scale`): -2 ln L = chi2 + log_det + const.
    log_det: float = 0.0
    #: The Gauss-Newton intervals when ``ci95`` was replaced by honest ones (:mod:`~piezobearing.fitting.profile`).
    ci95_jacobian: dict[str, list[float]] | None = None
    #: d residual / d free parameter at the solution, in the fit's internal coordinates (n x k; None without a
    #: free parameter): the correlation correction of the intervals reads it (:mod:`~piezobearing.fitting.correlation`).
    jacobian: np.ndarray | None = field(default=None, repr=False)

    @property
    def aic(self) -> float:
        """Akaike information criterion chi2 + log_det + 2 k.

        Equal to -2 log L up to a constant when the residual is normalised
        by a known noise level (chi2 + log_det is then -2 log L + const).
        """
        return self.chi2 + self.log_det + 2.0 * self.n_free

    @property
    def bic(self) -> float:
        """Bayesian information criterion chi2 + log_det + k ln n (same normalisation as :attr:`aic`)."""
        return self.chi2 + self.log_det + self.n_free * float(np.log(max(self.n_data, 1)))

    def report(self) -> dict:
        """JSON-ready summary (no arrays)."""
        return {
            "values": self.values,
            "stderr": self.stderr,
            "ci95": self.ci95,
            **({"ci95_jacobian": self.ci95_jacobian} if self.ci95_jacobian is not None else {}),
            "correlation": self.correlation,
            "n_data": self.n_data,
            "n_free": self.n_free,
            "chi2": self.chi2,
            "aic": self.aic,
            "bic": self.bic,
            "log_det": self.log_det,
            "success": self.success,
            "message": self.message,
        }


def fit(
    residual_fn: Callable[[dict[str, float]], np.ndarray],
    params: Sequence[Param],
    max_nfev: int | None = None,
    ftol: float = 1e-8,
    n_data: int | None = None,
) -> FitResult:
    """Minimise sum(residual_fn(values)**2) over the free parameters.

    ``residual_fn`` takes a dict of physical values (free and fixed) and
    returns the residual vector. The 95% intervals are Student-t intervals
    from the Gauss-Newton covariance s^2 (J^T J)^-1 in internal coordinates,
    mapped to physical units (asymmetric for ``log`` parameters); they assume
    white residuals, which the diagnostics check. ``ftol`` is the relative
    change of the sum of squares at which the fit stops (scipy's ``ftol``).
    ``n_data`` is the number of independent data when it is not the residual's
    size (entries of a residual that are zero by construction, e.g. samples a
    likelihood leaves out, carry no information): the degrees of freedom and BIC use it.
    """
    free = [p for p in params if p.vary]
    fixed = {p.name: float(p.value) for p in params if not p.vary}

    def unpack(u: np.ndarray) -> dict[str, float]:
        vals = dict(fixed)
        vals.update({p.name: p.to_physical(ui) for p, ui in zip(free, u, strict=True)})
        return vals

    if not free:
        r = np.asarray(residual_fn(unpack(np.array([]))), dtype=float)
        return FitResult(fixed, {}, {}, {}, r, r.size if n_data is None else n_data, 0, float(r @ r))

    u0 = np.array([p.to_internal(p.value) for p in free])
    lo = np.array([p.to_internal(p.lower) if np.isfinite(p.lower) else -np.inf for p in free])
    hi = np.array([p.to_internal(p.upper) if np.isfinite(p.upper) else np.inf for p in free])
    u0 = np.clip(u0, np.where(np.isfinite(lo), lo, u0), np.where(np.isfinite(hi), hi, u0))
    fun, jac = _fun_and_jacobian(residual_fn, free, unpack, lo, hi)
    # Imported here: scipy.optimize costs about 0.2 s of import, which every workflow job that imports the
    # sensor's circuit types (most of them; few fit anything) would pay.
    from scipy.optimize import least_squares

    sol = least_squares(fun, u0, jac=jac, bounds=(lo, hi), x_scale="jac", max_nfev=max_nfev, ftol=ftol)
    r = sol.fun
    n, k = (r.size if n_data is None else n_data), len(free)
    dof = max(n - k, 1)
    s2 = float(r @ r) / dof
    jtj = sol.jac.T @ sol.jac
    cov = np.linalg.pinv(jtj) * s2
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    tq = float(stdtrit(dof, 0.975))  # scipy.stats.t.ppf's own function, bit for bit, without scipy.stats' import
    values = unpack(sol.x)
    stderr, ci95, corr = {}, {}, {}
    for i, p in enumerate(free):
        lo_i, hi_i = p.to_physical(sol.x[i] - tq * sd[i]), p.to_physical(sol.x[i] + tq * sd[i])
        ci95[p.name] = [lo_i, hi_i]
        # first-order physical standard error
        stderr[p.name] = float(sd[i] * (np.log(10) * values[p.name] if p.log else p.scale))
        corr[p.name] = {
            q.name: float(cov[i, j] / (sd[i] * sd[j])) if sd[i] > 0 and sd[j] > 0 else float("nan")
            for j, q in enumerate(free)
        }
    return FitResult(values, stderr, ci95, corr, r, n, k, float(r @ r), bool(sol.success), str(sol.message),
                     jacobian=sol.jac)


def _fun_and_jacobian(residual_fn, free: list[Param], unpack, lo: np.ndarray, hi: np.ndarray):
    """The residual of the internal coordinates and its Jacobian for scipy's ``least_squares``.

    The Jacobian is scipy's own 2-point differences (``approx_derivative`` with scipy's steps: the same numbers
    as ``jac="2-point"`` gives them), except where ``residual_fn`` has a ``linear_columns`` attribute: a function
    of the values giving d residual / d value, exactly, for the parameters the residual is linear in (an
    additive voltage's coefficients: :func:`~piezobearing.diagnosis.fit.likelihood_residual`). Those columns are
    then taken from it (times d value / d internal = the parameter's scale) instead of one model evaluation each;
    the difference of a linear column from its finite difference is rounding.

    A point where ``residual_fn`` raises :class:`InfeasibleError` has the residual +inf (scipy's trust region
    refuses the step and shrinks); a finite difference that lands on one gives its column 0 (the parameter
    stays where it is for that step). The start point must be feasible.
    """
    from scipy.optimize._numdiff import approx_derivative  # imported here: see fit

    columns = getattr(residual_fn, "linear_columns", None)

    last: list = [None, None]  # the latest point evaluated and its residual: scipy asks the Jacobian there
    size: list = [None]

    def value(u: np.ndarray) -> np.ndarray:
        try:
            r = residual_fn(unpack(u))
        except InfeasibleError:
            if size[0] is None:
                raise
            return np.full(size[0], np.inf)
        size[0] = r.size
        return r

    def fun(u: np.ndarray) -> np.ndarray:
        r = value(u)
        last[:] = np.array(u, dtype=float), r
        return r

    def jac(u: np.ndarray) -> np.ndarray:
        f0 = last[1] if last[0] is not None and np.array_equal(last[0], u) else fun(u)
        cols = columns(unpack(u)) if columns is not None else {}
        linear = [i for i, p in enumerate(free) if p.name in cols and not p.log]
        other = [i for i in range(len(free)) if i not in linear]
        out = np.empty((f0.size, len(free)))
        if other:
            base = np.array(u, dtype=float)

            def part(x: np.ndarray) -> np.ndarray:
                full = base.copy()
                full[other] = x
                return value(full)

            out[:, other] = approx_derivative(part, base[other], method="2-point", f0=f0,
                                              bounds=(lo[other], hi[other])).reshape(f0.size, len(other))
        for i in linear:
            out[:, i] = cols[free[i].name] * free[i].scale
        out[:, ~np.all(np.isfinite(out), axis=0)] = 0.0
        return out

    return fun, jac


def nrmse(residual: np.ndarray, measured: np.ndarray) -> float:
    """rms(residual) / rms(measured)."""
    return float(np.sqrt(np.mean(np.square(residual)) / np.mean(np.square(measured))))
