"""Fit a forward model by maximum likelihood with the measured noise floor.

The noise spectrum S(f) of a model (:mod:`piezobearing.diagnosis.noise`) is
measured, not fitted, so the cost is

    chi2 = sum_k |R_k|^2 / (n S_k / 2)   over the DFT bins of the residual,

with chi2 ~ n for a correct model and BIC = chi2 + k ln n (the noise level
measured, not fitted). When the model is driven by a measured, noisy input
(errors in variables), a delay or a lead applied to that input rotates and
amplifies its noise at every frequency, and a fit could then "explain" part
of the carried noise (false discoveries) while its Gauss-Newton steps slow
down. The fit therefore drives the model with the input the model gives
(:meth:`~piezobearing.diagnosis.model.Model.fit_input`, e.g. the force
low-passed at twice its band, its content untouched) and weights by the
floor of that input, S_fit = s_v^2 + s_f^2 |G W|^2. The residual, NRMSE and
tests reported use the measured input as it is.

Samples the record leaves out (:attr:`Record.left_out
<piezobearing.diagnosis.record.Record>`: interpolated across a gap of the
recorded clock, not measured, and those where the model's memory still
carries the interpolated input) count nowhere: the residual is zero there
before it is weighted, the number of data is that of the measured samples
(``Record.n_measured``: chi2 ~ n_measured for a correct model), and NRMSE
and rms are taken over the measured samples.

NRMSE = rms(residual) / rms(measured voltage) throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np
from scipy import fft as sfft

from ..fitting.least_squares import FitResult, InfeasibleError, fit, nrmse
from .model import Model
from .noise import NoiseFloor
from .record import Record


def fd_weighted(residual_V: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The residual as n real numbers of unit variance for a correct model.

    R = rfft(r); interior bins give Re and Im scaled by sqrt(2 / (n S)), the
    0 and Nyquist bins their real part scaled by sqrt(1 / (n S)). The sum of
    squares is sum r^2 / sigma^2 for white noise of variance sigma^2 = S.
    """
    n = residual_V.size
    r = sfft.rfft(residual_V)  # scipy's: numpy's result bit for bit, 2x faster on a record's length (25001 = 23 x 1087)
    w = np.sqrt(2.0 / (n * s))
    w[0] /= np.sqrt(2.0)
    if n % 2 == 0:
        w[-1] /= np.sqrt(2.0)
    r *= w  # one complex product for the real and the imaginary parts (the same numbers as two)
    return np.concatenate([r.real, r[1:-1].imag if n % 2 == 0 else r[1:].imag])


def fd_to_time(weighted: np.ndarray) -> np.ndarray:
    """The time series of :func:`fd_weighted`'s numbers (each column of a 2-D array): the inverse of its packing
    without the weights, an orthogonal map (sums of squares and products kept). Of the likelihood's residual it is
    the residual whitened by the floor (:func:`whiten`), of a Jacobian column that column in time."""
    e = np.asarray(weighted, dtype=float)
    n = e.shape[0]
    half = n // 2 + 1
    re, im = e[:half], e[half:]
    w = np.full(half, np.sqrt(2.0 / n))
    w[0] = np.sqrt(1.0 / n)
    if n % 2 == 0:
        w[-1] = np.sqrt(1.0 / n)
    spec = re.astype(complex)
    spec[1 : 1 + im.shape[0]] += 1j * im
    spec /= w.reshape((-1,) + (1,) * (e.ndim - 1))
    return sfft.irfft(spec, n, axis=0)


def whiten(residual_V: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The residual filtered by 1/sqrt(S) (zero-phase, circular): unit-variance white noise for a correct model."""
    return sfft.irfft(sfft.rfft(residual_V) / np.sqrt(s), residual_V.size)


@dataclass
class ModelFit:
    """A fitted model and its residual."""

    model: Model
    result: FitResult
    model_V: np.ndarray = field(repr=False)
    residual_V: np.ndarray = field(repr=False)
    whitened: np.ndarray = field(repr=False)
    response: np.ndarray = field(repr=False)
    nrmse: float
    floor_nrmse: float
    floor_rms_V: float
    residual_rms_V: float = float("nan")
    #: h(t) of a non-stationary noise model (None: stationary), :func:`noise_scale`.
    scale: np.ndarray | None = field(repr=False, default=None)

    def compact(self) -> "ModelFit":
        """This fit without its full-length arrays (its numbers and :meth:`summary` kept): what a ranked
        candidate that is not added needs, so that a long record's ranking holds no series per candidate."""
        empty = np.zeros(0)
        return replace(
            self,
            result=replace(self.result, residual=empty, jacobian=None),
            model_V=empty,
            residual_V=empty,
            whitened=empty,
            response=empty,
            scale=None,
        )

    @property
    def values(self) -> dict:
        return self.result.values

    @property
    def chi2(self) -> float:
        """-2 ln L + const: the weighted sum of squares plus sum ln h^2 of a non-stationary noise model."""
        return self.result.chi2 + self.result.log_det

    @property
    def bic(self) -> float:
        return self.result.bic

    @property
    def n_free(self) -> int:
        return self.result.n_free

    @property
    def excess(self) -> float:
        """chi2 above its expectation n - k for a correct model [-]."""
        return self.chi2 - (self.result.n_data - self.n_free)

    def summary(self) -> dict:
        r = self.result
        return {
            "effects": self.model.names,
            "nrmse": self.nrmse,
            "noise_floor_nrmse": self.floor_nrmse,
            "residual_rms_V": self.residual_rms_V,
            "noise_floor_rms_V": self.floor_rms_V,
            "chi2": r.chi2,
            "chi2_per_sample": r.chi2 / r.n_data,
            "noise_follows_signal": self.scale is not None,
            "noise_log_det": r.log_det,
            "bic": r.bic,
            "n_free": r.n_free,
            "params": r.values,
            "stderr": r.stderr,
            "ci95": r.ci95,
            **({"ci95_jacobian": r.ci95_jacobian} if r.ci95_jacobian is not None else {}),
            "converged": r.success,
        }


def likelihood_residual(
    model: Model, record: Record, voltage_V: np.ndarray, floor: NoiseFloor, scale: np.ndarray | None = None
) -> Callable[[dict], np.ndarray]:
    """The fit's residual function: values -> the residual weighted by the floor (chi2 = its sum of squares).

    The model is driven by its :meth:`~piezobearing.diagnosis.model.Model.fit_input`
    and the floor is that of the input filtered by ``fit_weight`` (module docstring);
    ``scale`` (h(t), :meth:`~piezobearing.diagnosis.noise.NoiseFloor.scale`) divides
    the residual first. The engine's profile likelihood (:mod:`~piezobearing.fitting.profile`)
    refits with it.
    """
    v = np.asarray(voltage_V, dtype=float)
    clean = model.fit_input(record)
    w = model.fit_weight(record)
    inv = None if scale is None else 1.0 / scale
    kept = record.kept  # 0 at filled samples: they carry no information
    if kept is not None:
        inv = kept if inv is None else inv * kept

    def weighted(values: dict) -> np.ndarray:
        s = floor.spectrum(model.response(values, record) * w)
        r = v - model.simulate(values, record, clean)
        return fd_weighted(r if inv is None else r * inv, s)

    if getattr(model, "linear_basis", None) is not None:
        weighted.linear_columns = _linear_columns(model, record, floor, w, inv)
    return weighted


#: Transforms of a model's linear-parameter bases a likelihood keeps (by the basis's key).
BASIS_FFTS = 16


def _linear_columns(model: Model, record: Record, floor: NoiseFloor, w, inv: np.ndarray | None) -> Callable:
    """values -> {name: d weighted residual / d value} for the parameters the model's voltage is linear in.

    A model states them with the optional method ``linear_basis(values, record)``: blocks ``(names,
    basis (n, k), key)``, the voltage's derivative by each named parameter (an additive term's coefficients:
    a drift's spline, the mains amplitudes; none of them in the response), ``key`` naming the basis's content
    (its transform is kept). The residual's column is then -:func:`fd_weighted` of the basis, without a model
    evaluation; :func:`~piezobearing.fitting.least_squares.fit` takes it instead of a finite difference.
    """
    ffts: dict = {}

    def columns(values: dict) -> dict[str, np.ndarray]:
        blocks = model.linear_basis(values, record)
        if not blocks:
            return {}
        s = floor.spectrum(model.response(values, record) * w)
        n = record.n
        wt = np.sqrt(2.0 / (n * s))
        wt[0] /= np.sqrt(2.0)
        if n % 2 == 0:
            wt[-1] /= np.sqrt(2.0)
        out = {}
        for names, basis, key in blocks:
            r = ffts.get(key)
            if r is None:
                r = sfft.rfft(basis if inv is None else basis * inv[:, None], axis=0)
                ffts[key] = r
                while len(ffts) > BASIS_FFTS:
                    ffts.pop(next(iter(ffts)))
            rw = r * wt[:, None]
            col = np.concatenate([rw.real, rw[1:-1].imag if n % 2 == 0 else rw[1:].imag], axis=0)
            out.update({name: -col[:, j] for j, name in enumerate(names)})
        return out

    return columns


def noise_scale(model: Model, values: dict, record: Record, floor: NoiseFloor) -> np.ndarray | None:
    """h(t) of the model at ``values`` (None when its noise is stationary).

    A model states a time-varying gain of its input-noise path with the
    optional method ``noise_envelope(values, record)`` (an array a(t), or
    None); see :meth:`~piezobearing.diagnosis.noise.NoiseFloor.scale`. Below
    a 0.1% change of h along the record the model counts as stationary.
    """
    env = getattr(model, "noise_envelope", None)
    a = None if env is None else env(values, record)
    if a is None:
        return None
    h = floor.scale(model.response(values, record), a, record.n)
    return None if h is None or np.ptp(h) < 1e-3 else h


def fit_model(
    model: Model,
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    start: dict | None = None,
    starts: list[dict] | None = None,
    max_nfev: int | None = None,
    ftol: float = 1e-8,
) -> ModelFit:
    """Fit ``model`` by the likelihood of the module docstring (errors in variables when it has an input).

    ``start`` holds start values (others: defaults); each dict in ``starts``
    overrides some of them for one more start, and the best fit is kept. A start at which the model has no
    solution (:class:`~piezobearing.fitting.least_squares.InfeasibleError`) is skipped; with none left the
    error goes to the caller.
    """
    v = np.asarray(voltage_V, dtype=float)
    weighted = likelihood_residual(model, record, v, floor)
    best, infeasible = None, None
    for extra in starts or [{}]:
        try:
            res = fit(
                weighted,
                model.params(record, {**(start or {}), **extra}),
                max_nfev=max_nfev,
                ftol=ftol,
                n_data=record.n_measured,
            )
        except InfeasibleError as e:  # this start has no solution of the model: the next start
            infeasible = e
            continue
        if best is None or res.chi2 < best.chi2:
            best = res
    if best is None:
        raise InfeasibleError(f"{model.label}: no start with a solution of the model ({infeasible})")
    h = noise_scale(model, best.values, record, floor)
    if h is not None:
        # the noise follows the signal: refit once with the scale of the first fit held (feasible
        # generalised least squares: the scale must not be a lever of the fit), -2 ln L gains sum ln h^2
        res = fit(
            likelihood_residual(model, record, v, floor, h),
            model.params(record, best.values),
            max_nfev=max_nfev,
            ftol=ftol,
            n_data=record.n_measured,
        )
        hk = h if record.kept is None else h[record.kept > 0]
        res.log_det = float(np.sum(np.log(np.square(hk))))
        best = res
    out = finish(model, record, v, floor, best, h)
    model.release()
    return out


def finish(
    model: Model, record: Record, v: np.ndarray, floor: NoiseFloor, res: FitResult, scale: np.ndarray | None = None
) -> ModelFit:
    """The fit's model voltage, residual and whitened residual (divided by ``scale`` first), driven by the
    measured input as it is; filled samples are zero in the whitened residual and left out of the rms."""
    mv = model.simulate(res.values, record)
    g = model.response(res.values, record)
    s = floor.spectrum(g)
    r = v - mv
    floor_rms = floor.rms_V(g, record.n)
    kept = record.kept
    rk, vk = (r, v) if kept is None else (r[kept > 0], v[kept > 0])
    vrms = float(np.sqrt(np.mean(vk**2)))
    rrms = float(np.sqrt(np.mean(rk**2)))
    rs = r if scale is None else r / scale
    z = whiten(rs, s) if kept is None else whiten(rs * kept, s) * kept
    return ModelFit(
        model, res, mv, r, z, np.asarray(g), nrmse(rk, vk), floor_rms / vrms, floor_rms, rrms, scale
    )
