"""A fault detector against a healthy baseline: the roller-passage part removed, impacts found in time.

Why. The sensor sits in the load zone and sees every roller pass: a smooth
bump per roller, 96 V peak to peak in the paper's case, periodic at BPFO. A
defect on the inner race or on a roller adds a few sharp impacts only when
it meets a roller near the sensor: at the paper's 2550 Hz and 10 dB the
inner-race record differs from the healthy one by 6.2 V rms, 94% of that in
40 of 2295 samples (single impacts up to 125 V against 11.4 V of noise),
but its spectrum spreads over about 270 bins, none far above the noise, so
no envelope line carries it (README, "Detection as a real rig sees it").
The envelope tests also read the healthy bumps' own BPFO content in their
band as a fault when the noise is a real DAQ's (micro-volts): they need to
know what a healthy bearing produces.

What. Four steps on a record x [V] sampled at dt [s]:

1. Slip (:func:`estimate_slip`): the cage slip s maximising the power of the
   roller-passage lines sum_k |X(k BPFO_0 (1 - s))|^2, k = 1..3, over
   s in [0, s_max] (Hann-windowed DTFT, a grid fine enough that no line
   drifts a tenth of a cycle between nodes, then a bounded refinement).
2. Roller-passage part (:func:`refine_period`, :func:`periodic_part`): one
   Gauss-Newton step on BPFO from the least-squares fit, then least squares on every
   harmonic of BPFO(s) up to ``alias_folds`` x f_s (the harmonics above the
   Nyquist frequency fold into the band on the sample grid; the healthy
   LPM record's fold is 61 dB below its power and would otherwise be the
   residual's largest content at a DAQ's noise). The residual r is the
   record without anything BPFO-periodic; the noise scale is
   sigma = 1.4826 MAD(r) (robust to the impacts).
3. Outer race (:func:`harmonic_test`): an outer-race defect under the sensor
   is itself BPFO-periodic, so it changes the roller-passage harmonics.
   Their coefficients c (k = 1..K below Nyquist, the fit of step 2 without
   the folded harmonics) are compared with the healthy baseline's c_b,
   aligned by the phase phi of the roller train:
   q = min_phi ||A (c - R(phi) c_b)||^2 / sigma^2 (+ a relative
   ``tolerance`` of the baseline per harmonic), with A the harmonics'
   design matrix: under noise alone q ~ chi^2 with 2K - 1 degrees of
   freedom (Gaussian white noise, exact covariance sigma^2 (A^T A)^-1).
4. Inner race and rolling element (:func:`fold_test`): z = r / sigma is
   folded on the fault's period (1/BPFI(s) or 1/(2 BSF(s))), one cell per
   sample of the period; each cell's sum of z^2 is chi^2 with as many
   degrees of freedom as it has samples. The impacts of the right type fall
   in one cell every time; the wrong type's fold spreads them. The smallest
   cell p-value is corrected for the search over the n_c cells:
   p = 1 - (1 - p_min)^n_c (disjoint cells of white noise are independent).

Decision. Each type's p-value is tested at alpha = pfa / n_types (the
probability that noise alone is called any fault is at most pfa). Reported
per type: indicator = -log10 p, threshold = -log10 alpha, margin = their
ratio. The fault type is the detected type with the smallest p; ``none`` if
no type is detected. The null distributions are exact for white Gaussian
noise and a known sigma; sigma from the MAD and the fits' few degrees of
freedom are checked by Monte Carlo (tests).

The baseline (:class:`Baseline`) is the healthy bearing's record processed
the same way: in the workflow the model's noiseless healthy voltage on the
DAQ clock; on a rig, a recording of the machine in good order (its own noise
then adds to the harmonic test's variance: give a ``tolerance``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .detector import CLASSIFIED_TYPES
from .fault_bands import slipped_frequencies

#: What fault_indicator.json's detector entries mean with signals.detector.statistic = baseline.
DEFINITION = (
    "fault_types (statistic baseline): the cage slip from the roller-passage lines (k BPFO, k = 1..3); the "
    "BPFO-periodic part (every harmonic to alias_folds x f_s) removed by least squares, sigma = 1.4826 MAD of the "
    "rest; outer_race: the roller-passage harmonics below Nyquist against the healthy baseline's, aligned in "
    "phase, chi^2 with 2K-1 degrees of freedom; inner_race, rolling_element: the rest over sigma, squared and "
    "folded on 1/BPFI and 1/(2 BSF), one cell per sample, the smallest cell chi^2 p-value corrected for the "
    "search over the cells; indicator = -log10 p, threshold = -log10(pfa / n_types), detected = indicator > "
    "threshold; fault_type: none if no type is detected, else the detected type of smallest p"
)
_FOLD_CARRIER = {"inner_race": "bpfi_Hz", "rolling_element": "2bsf_Hz"}


@dataclass(frozen=True)
class BaselineSettings:
    """The baseline detector.

    Parameters
    ----------
    slip_max : float
        Largest cage slip searched [-].
    false_alarm_probability : float
        Probability that noise alone is called any fault [-].
    fault_types : tuple of str
        The fault types tested.
    alias_folds : float
        The roller-passage fit takes every BPFO harmonic up to alias_folds x f_s [-] (1: the band and its
        first fold).
    slip_harmonics : int
        Roller-passage lines k BPFO, k = 1..n, whose power fixes the slip [-].
    tolerance : float
        Relative standard deviation of the baseline's harmonics against the running bearing's when healthy [-]
        (0: the baseline is exact, as the model's noiseless healthy record is).
    """

    slip_max: float = 0.03
    false_alarm_probability: float = 1e-3
    fault_types: tuple[str, ...] = CLASSIFIED_TYPES
    alias_folds: float = 1.0
    slip_harmonics: int = 3
    tolerance: float = 0.0

    @property
    def alpha_per_type(self) -> float:
        """False-alarm probability of each type's test, pfa / n_types (Bonferroni) [-]."""
        return self.false_alarm_probability / len(self.fault_types)

    @classmethod
    def from_config(cls, sig: dict) -> "BaselineSettings":
        return cls(slip_max=sig["detector"]["slip_max"], false_alarm_probability=sig["false_alarm_probability"])


# --------------------------------------------------------------------------- the roller-passage part


def estimate_slip(x: np.ndarray, dt_s: float, bpfo0_Hz: float, slip_max: float, n_harmonics: int = 3) -> float:
    """Cage slip [-] maximising sum_k |X(k BPFO_0 (1 - s))|^2, k = 1..n, over s in [0, slip_max].

    X is the DTFT of the Hann-windowed record (mean removed). The grid step
    keeps the highest line's phase drift over the record below 0.1 cycle
    between nodes; the best node is refined by a bounded scalar search.
    """
    from scipy.optimize import minimize_scalar

    x = np.asarray(x, float)
    n = x.size
    t = np.arange(n) * dt_s
    y = np.hanning(n) * (x - x.mean())
    k = np.arange(1, n_harmonics + 1)

    def power(s: np.ndarray) -> np.ndarray:
        f = (k[None, :] * bpfo0_Hz * (1.0 - np.atleast_1d(s))[:, None]).ravel()
        dft = np.exp(-2j * np.pi * f[:, None] * t[None, :]) @ y
        return np.sum(np.abs(dft.reshape(-1, k.size)) ** 2, axis=1)

    step = 0.1 / (n_harmonics * bpfo0_Hz * n * dt_s)
    grid = np.linspace(0.0, slip_max, max(int(np.ceil(slip_max / step)), 1) + 1)
    # the grid from a 16-fold zero-padded FFT (nearest padded bin: 1/16 of the resolution), refined exactly below
    m = 16 * n
    spec = np.abs(np.fft.rfft(y, m)) ** 2
    idx = np.rint(k[None, :] * bpfo0_Hz * (1.0 - grid)[:, None] * m * dt_s).astype(int)
    p = spec[np.clip(idx, 0, spec.size - 1)].sum(axis=1)
    i = int(np.argmax(p))
    best = float(power(grid[i])[0])
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    if hi <= lo:
        return float(grid[i])
    r = minimize_scalar(lambda s: -float(power(s)[0]), bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-3 * step})
    return float(r.x) if -r.fun >= best else float(grid[i])


def harmonic_matrix(n: int, dt_s: float, f0_Hz: float, n_harmonics: int) -> np.ndarray:
    """Columns 1, cos(2 pi k f0 t), sin(2 pi k f0 t), k = 1..K, at t = i dt [-]."""
    t = np.arange(n) * dt_s
    ph = 2.0 * np.pi * f0_Hz * np.outer(t, np.arange(1, n_harmonics + 1))
    a = np.empty((n, 2 * n_harmonics + 1))
    a[:, 0] = 1.0
    a[:, 1::2] = np.cos(ph)
    a[:, 2::2] = np.sin(ph)
    return a


def below_nyquist(dt_s: float, f0_Hz: float) -> int:
    """Harmonics of f0 below 0.999 x the Nyquist frequency [-]."""
    return max(int(np.floor(0.5 / dt_s / f0_Hz * 0.999)), 1)


def periodic_part(x: np.ndarray, dt_s: float, f0_Hz: float, alias_folds: float = 1.0) -> np.ndarray:
    """The record's f0-periodic part [V]: least squares on every harmonic of f0 up to alias_folds / dt.

    On the sample grid a harmonic above Nyquist is a folded line in the
    band; near-coincident folds make the matrix ill-conditioned, which the
    pivoted QR (:func:`_lstsq`) absorbs.
    """
    x = np.asarray(x, float)
    k = max(int(np.floor(alias_folds / dt_s / f0_Hz)), below_nyquist(dt_s, f0_Hz))
    a = harmonic_matrix(x.size, dt_s, f0_Hz, k)
    c = _lstsq(a, x)
    return a @ c


def refine_period(x: np.ndarray, dt_s: float, f0_Hz: float, alias_folds: float = 1.0) -> tuple[float, np.ndarray]:
    """One Gauss-Newton step on f0 of the periodic fit, then the fit: (f0 [Hz], the periodic part [V]).

    The DTFT peak of a few lines is biased by their windows' leakage (a
    slip error of about 4e-9 leaves 1e-4 V of a 96 V roller train in the
    residual: structure a DAQ's micro-volt noise does not hide). The
    periodic model p = A c has dp/df0 = sum_k 2 pi k t (-a_k sin + b_k cos);
    least squares on [A, dp/df0] gives the frequency step.
    """
    x = np.asarray(x, float)
    k = max(int(np.floor(alias_folds / dt_s / f0_Hz)), below_nyquist(dt_s, f0_Hz))
    a = harmonic_matrix(x.size, dt_s, f0_Hz, k)
    c = _lstsq(a, x)
    t = np.arange(x.size) * dt_s
    w = 2.0 * np.pi * np.arange(1, k + 1)
    deriv = t * ((-c[1::2] * w) * a[:, 2::2] + (c[2::2] * w) * a[:, 1::2]).sum(axis=1)
    step = float(_lstsq(np.column_stack([a, deriv]), x)[-1])
    if abs(step) < 0.5 / (x.size * dt_s * k):  # within the linear range (half a cycle of the top harmonic over the record)
        f0_Hz += step
    a = harmonic_matrix(x.size, dt_s, f0_Hz, k)
    return f0_Hz, a @ _lstsq(a, x)


@functools.lru_cache(maxsize=1)
def _blas_pools():
    """The BLAS thread pools of this process, found once: finding them (threadpoolctl walks every loaded
    library) cost about 3 ms a call, a tenth of the classification rule's 800 detections (issue 14)."""
    import scipy.linalg  # noqa: F401  (loads SciPy's BLAS, the one _lstsq uses, before the pools are listed)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def one_blas_thread(fn):
    """Run ``fn`` on one BLAS thread: its small least-squares problems ran 50-200 times slower with
    OpenBLAS's threads on a loaded machine (measured, 2 cores at load 17)."""

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        with _blas_pools().limit(limits=1, user_api="blas"):
            return fn(*args, **kwargs)

    return wrapped


def _lstsq(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Least squares by pivoted QR (rank-revealing: coincident folded harmonics get the minimum-norm split)."""
    from scipy.linalg import lstsq

    return lstsq(a, x, cond=1e-10, lapack_driver="gelsy", check_finite=False)[0]


def slip_of(kinematics: dict, bpfo_Hz: float) -> float:
    """The cage slip [-] at which BPFO = ``bpfo_Hz`` (clipped to [0, 0.999])."""
    return float(np.clip(1.0 - bpfo_Hz / kinematics["bpfo_Hz"], 0.0, 0.999))


def robust_sigma(r: np.ndarray) -> float:
    """1.4826 x the median absolute deviation [V] (the standard deviation of Gaussian noise)."""
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


@dataclass(frozen=True)
class Baseline:
    """The healthy bearing's roller-passage harmonics.

    Attributes
    ----------
    slip : float
        Its estimated cage slip [-].
    coefficients : ndarray
        Mean, then (a_k, b_k) of a_k cos + b_k sin for k = 1..K below Nyquist [V].
    dt_s : float
    """

    slip: float
    coefficients: np.ndarray
    dt_s: float

    @classmethod
    @one_blas_thread
    def from_record(cls, v: np.ndarray, dt_s: float, kinematics: dict, settings: BaselineSettings) -> "Baseline":
        """The baseline of a healthy record ``v`` [V] (noiseless from the model, or measured)."""
        s = estimate_slip(v, dt_s, kinematics["bpfo_Hz"], settings.slip_max, settings.slip_harmonics)
        f0, _ = refine_period(v, dt_s, slipped_frequencies(kinematics, s)["bpfo_Hz"], settings.alias_folds)
        s = slip_of(kinematics, f0)
        a = harmonic_matrix(np.size(v), dt_s, f0, below_nyquist(dt_s, f0))
        c = _lstsq(a, np.asarray(v, float))
        return cls(s, c, dt_s)


# --------------------------------------------------------------------------- tests


def log_chi2_sf(q, dof):
    """ln P(chi^2_dof > q), with the leading asymptotic term where scipy underflows [-] (arrays too)."""
    from scipy import stats
    from scipy.special import gammaln

    q, dof = np.broadcast_arrays(np.asarray(q, float), np.asarray(dof, float))
    v = np.asarray(stats.chi2.logsf(q, dof), float)
    bad = ~np.isfinite(v)
    if bad.any():
        a = 0.5 * dof[bad]
        v[bad] = -0.5 * q[bad] + (a - 1.0) * np.log(0.5 * q[bad]) - gammaln(a)
    return float(v) if v.ndim == 0 else v


def _search_corrected(log_p: float, n_tests: int) -> float:
    """ln of 1 - (1 - p)^n for p = e^log_p (the smallest of n independent p-values) [-]."""
    if log_p > -30.0:
        return float(np.log(-np.expm1(n_tests * np.log1p(-np.exp(log_p)))))
    return float(np.log(n_tests) + log_p)


def _rotate(c: np.ndarray, phi) -> np.ndarray:
    """Coefficients of the periodic signal shifted in phase by phi at the fundamental [V] (one row per phi)."""
    phi = np.atleast_1d(np.asarray(phi, float))[:, None]
    k = np.arange(1, (c.size - 1) // 2 + 1)[None, :]
    a, b = c[1::2][None, :], c[2::2][None, :]
    cos, sin = np.cos(k * phi), np.sin(k * phi)
    out = np.repeat(c[None, :], phi.shape[0], axis=0)
    out[:, 1::2] = a * cos - b * sin
    out[:, 2::2] = a * sin + b * cos
    return out


def harmonic_test(x: np.ndarray, dt_s: float, f0_Hz: float, baseline: Baseline, sigma: float,
                  tolerance: float = 0.0) -> dict:
    """Roller-passage harmonics of ``x`` against the baseline's (outer-race test).

    q(phi) = (c - R(phi) c_b)^T C^-1 (c - R(phi) c_b), C = sigma^2 (A^T A)^-1
    + diag(tolerance^2 |c_b|^2) (the mean left out); minimised over the phase
    phi of the roller train. Under noise alone q ~ chi^2_{2K-1}.

    Returns
    -------
    dict
        statistic q, dof, log10_p, phase_rad, n_harmonics K.
    """
    from scipy.optimize import minimize_scalar

    x = np.asarray(x, float)
    k = min(below_nyquist(dt_s, f0_Hz), (baseline.coefficients.size - 1) // 2)
    a = harmonic_matrix(x.size, dt_s, f0_Hz, k)
    c = _lstsq(a, x)
    cb = baseline.coefficients[: 2 * k + 1]
    g = a.T @ a / sigma**2
    if tolerance > 0:
        amp2 = np.repeat(cb[1::2] ** 2 + cb[2::2] ** 2, 2)
        cov = np.linalg.inv(g[1:, 1:]) + np.diag(tolerance**2 * amp2)
        g = np.zeros_like(g)
        g[1:, 1:] = np.linalg.inv(cov)
    g[0, :] = 0.0
    g[:, 0] = 0.0

    def q(phi) -> np.ndarray:
        d = c[None, :] - _rotate(cb, phi)
        return np.einsum("pi,ij,pj->p", d, g, d)

    phi0 = float(np.arctan2(-c[2], c[1]) - np.arctan2(-cb[2], cb[1]))
    # the fundamental's phase within a few of its noise widths, then the best phase near it
    phis = phi0 + np.linspace(-0.2, 0.2, 81)
    qs = q(phis)
    j = int(np.argmin(qs))
    r = minimize_scalar(lambda p: float(q(p)[0]), bounds=(phis[max(j - 1, 0)], phis[min(j + 1, phis.size - 1)]),
                        method="bounded")
    val = min(float(r.fun), float(qs[j]))
    dof = 2 * k - 1
    return {"statistic": val, "dof": dof, "log10_p": log_chi2_sf(val, dof) / np.log(10.0),
            "phase_rad": float(r.x), "n_harmonics": k}


def fold_test(z: np.ndarray, dt_s: float, period_s: float) -> dict:
    """Standardised residual ``z`` folded on ``period_s``: the cell whose sum of z^2 is least likely.

    Cell j of the n_c = round(period / dt) cells of the period holds the
    samples whose phase (i dt / period mod 1) falls in [j, j+1) / n_c; its
    sum of z^2 is chi^2 with m_j degrees of freedom under white noise. The
    smallest p-value is corrected for the search over the cells.

    Returns
    -------
    dict
        log10_p (corrected), cell (phase of the best cell, [0, 1)), cell_ratio (its mean z^2) [-], n_cells.
    """
    z = np.asarray(z, float)
    nc = max(int(round(period_s / dt_s)), 2)
    phase = np.mod(np.arange(z.size) * (dt_s / period_s), 1.0)
    cell = np.minimum((phase * nc).astype(int), nc - 1)
    s = np.bincount(cell, z * z, nc)
    m = np.bincount(cell, None, nc)
    logp = np.where(m > 0, log_chi2_sf(s, np.maximum(m, 1)), 0.0)
    j = int(np.argmin(logp))
    return {"log10_p": _search_corrected(float(logp[j]), nc) / np.log(10.0), "cell": j / nc,
            "cell_ratio": float(s[j] / max(m[j], 1)), "n_cells": nc}


# --------------------------------------------------------------------------- the detector


@dataclass(frozen=True)
class BaselineDetection:
    """The baseline detector's result on one record (the same keys as :class:`.detector.Detection`)."""

    fault_type: str
    per_type: dict = field(default_factory=dict)
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"fault_type": self.fault_type, "per_type": self.per_type,
                "lines": {t: [self.details[t]] for t in self.per_type}}


@one_blas_thread
def detect(x: np.ndarray, dt_s: float, kinematics: dict, baseline: Baseline,
           settings: BaselineSettings) -> BaselineDetection:
    """Test every fault type of ``settings`` in the record ``x`` [V] against the healthy ``baseline``.

    Parameters
    ----------
    x : ndarray
        The record on the DAQ clock [V].
    dt_s : float
        Its sample step [s] (the baseline's).
    kinematics : dict
        No-slip kinematic frequencies [Hz].
    baseline : Baseline
    settings : BaselineSettings
    """
    x = np.asarray(x, float)
    if abs(dt_s - baseline.dt_s) > 1e-9 * dt_s:
        raise ValueError(f"the record's step {dt_s:g} s differs from the baseline's {baseline.dt_s:g} s")
    s = estimate_slip(x, dt_s, kinematics["bpfo_Hz"], settings.slip_max, settings.slip_harmonics)
    f0, p = refine_period(x, dt_s, slipped_frequencies(kinematics, s)["bpfo_Hz"], settings.alias_folds)
    s = slip_of(kinematics, f0)
    f = slipped_frequencies(kinematics, s)
    r = x - p
    sigma = robust_sigma(r)
    if not sigma > 0:
        raise ValueError("the record without its roller-passage part is constant: no noise to scale by")
    alpha = settings.alpha_per_type
    details = {}
    for t in settings.fault_types:
        if t == "outer_race":
            details[t] = harmonic_test(x, dt_s, f["bpfo_Hz"], baseline, sigma, settings.tolerance)
        else:
            details[t] = fold_test(r / sigma, dt_s, 1.0 / f[_FOLD_CARRIER[t]])
    thr = -np.log10(alpha)
    per_type = {}
    for t, d in details.items():
        ind = -d["log10_p"]
        per_type[t] = {"indicator": ind, "threshold": thr, "detected": bool(ind > thr),
                       "p_value": float(10.0 ** -ind), "margin": ind / thr, "slip": s, "sigma_V": sigma}
    hits = [t for t in per_type if per_type[t]["detected"]]
    kind = max(hits, key=lambda t: per_type[t]["indicator"]) if hits else "none"
    return BaselineDetection(kind, per_type, details)
