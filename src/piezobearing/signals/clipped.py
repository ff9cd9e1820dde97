"""The baseline detector on a record the ADC clipped: compared with what a clipped healthy record is expected to be.

Why. An ADC clips its input x = b(t) + n(t) to its end codes [lo, hi]. The
record's BPFO-periodic part is then E[clip(b(t) + n)], not b(t): clipping
compresses the roller-passage harmonics and makes new ones. The baseline
detector's outer-race test (:func:`.baseline.harmonic_test`) compares the
record's harmonics with the unclipped healthy baseline's and calls the
healthy bearing an outer-race fault (the ``daq_noise`` study at 1 V/sqrt(Hz):
20 of 20 seeds at 2550 and at 10240 Hz, README).

What. For Gaussian noise n of standard deviation sigma (before the ADC) the
clipped sample Y = clip(mu + n, lo, hi) has the closed-form mean and variance
of a clipped normal (:func:`clipped_normal_moments`). With mu = b(theta), the
baseline's waveform over one period of the roller train:

1. Clip levels (:func:`clip_levels`): the record's smallest and largest
   value, each counted as an end code when at least two samples sit on it
   (the ADC's end codes; an unclipped record with continuous noise repeats
   its extreme with probability ~0).
2. sigma (:func:`noise_sigma`): the residual r = x - (the record's periodic
   fit) has at phase theta the variance V(theta) of the clipped normal;
   sigma is the value at which E_theta[V] is the residual's mean square
   (times n / (n - n_p), the fit's degrees of freedom). Not robust to
   impacts as the unclipped detector's MAD is (an inner-race fault's
   impacts raise it, bounded by the clip levels): the MAD of the fit's
   residual was tried and dropped, 2.9% low on clipped records (the fit
   shrinks a clipped residual's median more than its variance; the mean
   square 0.3% off after the correction), which set the rolling-element
   fold's false alarms on synthetic clipped records at 9.5% for 5%.
3. Outer race (:func:`harmonic_test`): the record's harmonics c (k = 1..K)
   against the clipped mean's, m(theta) = E[clip(b(theta) + n)], aligned in
   phase, with the covariance of c under the clipped noise's periodic
   variance V(theta): C = (4 / n) E_theta[V a a^T] (a: the harmonics'
   cos/sin at theta; white noise, the samples' phases uniform over the
   period), so q ~ chi^2_{2K-1} again. The fundamental is the unclipped
   detector's search with m in place of the baseline.
4. Inner race and rolling element: the residual standardised sample by
   sample, z_i = r_i / sqrt(V(theta_i)), then the same folds (clipped noise is
   bounded, so the cells' chi^2 tails are conservative).

An unclipped record goes through :func:`.baseline.detect` unchanged. The
model ignores the mains and drive lines under the noise (a 1 mV line against
tens of volts of noise where the noise clips), and a clipped record at a
DAQ's micro-volt noise (the signal's own peaks beyond the range) reduces to
clip(b): what the healthy waveform clipped looks like.
"""

from __future__ import annotations

import numpy as np

from ..threads import one_blas_thread
from . import baseline as B

#: What fault_indicator.json's baseline entries add on a clipped record.
DEFINITION = (
    "on a record with clipped samples (at least two on an extreme: clipped_fraction, clip_levels_V): "
    "noise_sigma_V, the noise before the ADC, from the residual's mean square against the clipped "
    "normal's variance; outer_race against E[clip(baseline + noise)] (the clipped normal's mean, closed form) with the "
    "harmonics' covariance under the clipped noise's periodic variance, chi^2 with 2K-1 degrees of freedom; "
    "inner_race, rolling_element: the residual over the clipped noise's standard deviation at each sample's "
    "phase, folded as above; sigma_V: the clipped residual's rms; the outer-race test's gain is 1 there "
    "(gain_tolerance_applied false where baseline_gain_tolerance > 0) and the folds on the record's own clock "
    "(follow_passage_phase_applied false where follow_passage_phase is set)"
)
#: Phases per period on which the clipped baseline is evaluated [-] (times the harmonics kept, at least).
_GRID_PER_HARMONIC = 32


def clipped_normal_moments(mu, sigma: float, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of Y = clip(mu + sigma Z, lo, hi), Z standard normal [V, V^2].

    With alpha = (lo - mu) / sigma, beta = (hi - mu) / sigma, P = Phi(beta) - Phi(alpha):
    E[Y] = lo Phi(alpha) + hi (1 - Phi(beta)) + mu P + sigma (phi(alpha) - phi(beta)) and
    E[Y^2] = lo^2 Phi(alpha) + hi^2 (1 - Phi(beta)) + (mu^2 + sigma^2) P + 2 mu sigma (phi(alpha) - phi(beta))
    + sigma^2 (alpha phi(alpha) - beta phi(beta)). sigma = 0 gives clip(mu) and 0.
    """
    from scipy.special import ndtr

    mu = np.asarray(mu, float)
    if sigma <= 0:
        return np.clip(mu, lo, hi), np.zeros_like(mu)
    a, b = (lo - mu) / sigma, (hi - mu) / sigma
    pa, pb = ndtr(a), ndtr(b)
    da, db = np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi), np.exp(-0.5 * b * b) / np.sqrt(2 * np.pi)
    inside = pb - pa
    # an open side (lo = -inf or hi = +inf) holds no probability: its terms are 0, not inf x 0
    lo_, hi_ = (lo if np.isfinite(lo) else 0.0), (hi if np.isfinite(hi) else 0.0)
    with np.errstate(invalid="ignore"):
        ada, bdb = np.where(np.isfinite(a), a * da, 0.0), np.where(np.isfinite(b), b * db, 0.0)
    m1 = lo_ * pa + hi_ * (1.0 - pb) + mu * inside + sigma * (da - db)
    m2 = (lo_ * lo_ * pa + hi_ * hi_ * (1.0 - pb) + (mu * mu + sigma * sigma) * inside
          + 2.0 * mu * sigma * (da - db) + sigma * sigma * (ada - bdb))
    return m1, np.maximum(m2 - m1 * m1, 0.0)


def clip_levels(x: np.ndarray, end_codes: tuple[float, float, float] | None = None) -> tuple[float, float, float]:
    """The record's clip levels and clipped fraction: (lo [V], hi [V], fraction [-]).

    ``end_codes``: the ADC's end codes and half its step, (lo [V], hi [V], q/2 [V]) (:func:`.daq.end_codes_V`),
    where the DAQ is known: a sample within q/2 of an end code is clipped. Without them an extreme counts as
    an end code when at least two samples sit on it. That rule misreads a fine ADC: at 24 bits over +-60 V
    (step 7.2 uV) and 0.36 mV of noise two samples share the record's extreme code in 9 of 200 records of
    40 V bumps (``tests/test_signals_clipped.py``), and the clipped model called one such healthy record of
    the stage test an outer-race fault; the workflow passes its ADC's end codes. A side that is not clipped
    gets -inf (lo) or +inf (hi). A coarse ADC may repeat an unclipped extreme: the model then clips at a
    level almost no sample passes, E[clip(b + n)] differs from b by E[(b + n - hi)+], and the tests reduce
    to the unclipped ones (sigma from the mean square, not the MAD).
    """
    x = np.asarray(x, float)
    if end_codes is not None:
        e_lo, e_hi, half = end_codes
        n_lo, n_hi = int(np.count_nonzero(x <= e_lo + half)), int(np.count_nonzero(x >= e_hi - half))
        lo, hi = (e_lo if n_lo else -np.inf), (e_hi if n_hi else np.inf)
        return lo, hi, (n_lo + n_hi) / x.size
    lo, hi = float(x.min()), float(x.max())
    n_lo, n_hi = int(np.count_nonzero(x == lo)), int(np.count_nonzero(x == hi))
    lo, n_lo = (lo, n_lo) if n_lo >= 2 else (-np.inf, 0)
    hi, n_hi = (hi, n_hi) if n_hi >= 2 else (np.inf, 0)
    return lo, hi, (n_lo + n_hi) / x.size


def waveform(c: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """sum of c[0] + a_k cos(k theta) + b_k sin(k theta) [V] (the baseline's coefficients)."""
    k = np.arange(1, (c.size - 1) // 2 + 1)
    ph = np.outer(theta, k)
    return c[0] + np.cos(ph) @ c[1::2] + np.sin(ph) @ c[2::2]


def _phase_grid(n_harmonics: int) -> np.ndarray:
    m = max(_GRID_PER_HARMONIC * n_harmonics, 1024)
    return 2.0 * np.pi * np.arange(m) / m


def noise_sigma(residual_var: float, b: np.ndarray, lo: float, hi: float) -> float:
    """The noise's standard deviation before the ADC [V] at which the clipped noise's variance averaged over
    the waveform ``b`` (samples over one period), E_theta[Var clip(b + sigma Z)], is ``residual_var`` [V^2]
    (the residual's, corrected for the fit's degrees of freedom).

    Increasing in sigma until the clipping saturates; the root is bracketed between 1e-6 and 1e3 times
    sqrt(residual_var) (the largest if the residual is wider than any sigma makes).
    """
    from scipy.optimize import brentq

    s0 = float(np.sqrt(residual_var))
    if not s0 > 0:
        return 0.0
    g = lambda s: float(np.mean(clipped_normal_moments(b, s, lo, hi)[1])) - residual_var  # noqa: E731
    lo_s, hi_s = 1e-6 * s0, 1e3 * s0
    if g(hi_s) < 0:
        return hi_s
    return float(brentq(g, lo_s, hi_s, xtol=1e-6 * s0))


def clipped_baseline(cb: np.ndarray, sigma: float, lo: float, hi: float, n_harmonics: int,
                     tables: tuple | None = None) -> tuple:
    """The clipped healthy record's mean coefficients (mean, a_k, b_k; k = 1..K) [V] and the harmonics'
    covariance per sample, E_theta[V(theta) a a^T] (times 4 / n: the coefficients' covariance) [V^2],
    and the mean variance E_theta[V] [V^2], from the baseline's coefficients ``cb`` [V]. ``tables``: what does
    not depend on sigma and the levels (:func:`baseline_tables`), computed once for many records."""
    th, wave, cos, sin, a = baseline_tables(cb, n_harmonics) if tables is None else tables
    m, v = clipped_normal_moments(wave, sigma, lo, hi)
    cm = np.empty(2 * n_harmonics + 1)
    cm[0] = m.mean()
    cm[1::2], cm[2::2] = 2.0 * cos.T @ m / th.size, 2.0 * sin.T @ m / th.size
    return cm, (a * v[:, None]).T @ a / th.size, float(v.mean())


def baseline_tables(cb: np.ndarray, n_harmonics: int) -> tuple:
    """The phase grid [rad], the baseline's waveform on it [V], and the harmonics' cosines, sines and their
    interleaved matrix on it [-] (:func:`clipped_baseline`)."""
    th = _phase_grid(max(n_harmonics, (cb.size - 1) // 2))
    k = np.arange(1, n_harmonics + 1)
    cos, sin = np.cos(np.outer(th, k)), np.sin(np.outer(th, k))
    a = np.empty((th.size, 2 * n_harmonics))
    a[:, 0::2], a[:, 1::2] = cos, sin
    return th, waveform(cb, th), cos, sin, a


def harmonic_test(x: np.ndarray, dt_s: float, f0_Hz: float, baseline: B.Baseline, sigma: float, lo: float,
                  hi: float, tolerance: float = 0.0, f_range_Hz: tuple[float, float] | None = None) -> dict:
    """The outer-race test of :func:`.baseline.harmonic_test` on a clipped record ``x`` [V].

    The fundamental f from the unclipped test's search with the clipped mean's coefficients c_m in place of the
    baseline's (and sqrt(E[V]) as its noise scale); at f, q = min_phi (R(-phi) c - c_m)^T C^-1 (R(-phi) c - c_m),
    C = (4 / n) E_theta[V a a^T] + diag(tolerance^2 |c_m,k|^2) in the baseline's frame (the record rotated
    back, so that C need not rotate); q ~ chi^2_{2K-1} under noise alone. ``sigma``: the noise before the ADC
    [V]; ``lo``, ``hi``: the clip levels [V]. :func:`harmonic_tests` of one record.

    Returns the unclipped test's keys and ``clipped_mean_coefficients`` (c_m) [V], ``residual_sigma_V``
    (sqrt E[V]) [V].
    """
    x = np.asarray(x, float)
    return harmonic_tests(x[None, :], dt_s, [f0_Hz], baseline, [sigma], [(lo, hi)], tolerance, f_range_Hz)[0]


def harmonic_tests(x: np.ndarray, dt_s: float, f0_Hz, baseline: B.Baseline, sigma, levels, tolerance: float = 0.0,
                   f_range_Hz: tuple[float, float] | None = None) -> list[dict]:
    """:func:`harmonic_test` of each row of ``x`` (R, n) [V], with its own ``f0_Hz``, ``sigma`` and clip
    ``levels`` (lo, hi) (sequences of R); the unclipped tests' searches of all rows run together."""
    from .harmonics import harmonic_fits
    from .outer_race import _phase_searches, row_chunks

    x = np.asarray(x, float)
    kb = (baseline.coefficients.size - 1) // 2
    f_top = list(f0_Hz) if f_range_Hz is None else [f_range_Hz[1]] * x.shape[0]
    ks = [min(B.below_nyquist(dt_s, ft), kb) for ft in f_top]
    out: list = [None] * x.shape[0]
    batches = [(kk, list(part)) for kk in dict.fromkeys(ks)  # rows of one K together, in batches
               for part in row_chunks(np.array([i for i in range(x.shape[0]) if ks[i] == kk]), x.shape[1], kk)]
    for k, rows in batches:
        tables = baseline_tables(baseline.coefficients, k)  # once for all rows
        models = [clipped_baseline(baseline.coefficients, sigma[i], *levels[i], k, tables) for i in rows]
        first = B.harmonic_tests(x[rows], dt_s, [f0_Hz[i] for i in rows],
                                 [B.Baseline(baseline.slip, cm, dt_s) for cm, _, _ in models],
                                 [np.sqrt(v_mean) for _, _, v_mean in models], tolerance, f_range_Hz)
        f = np.array([d["f0_Hz"] for d in first])
        c = harmonic_fits(x[rows], dt_s, f, k)[0]
        info = []
        for cm, vaa, _ in models:
            cov = 4.0 / x.shape[1] * vaa
            if tolerance > 0:
                cov = cov + np.diag(tolerance**2 * np.repeat(cm[1::2] ** 2 + cm[2::2] ** 2, 2))
            info.append(np.linalg.inv(cov))
        # q(phi) = (c_m - R(-phi) c)^T C^-1 (c_m - R(-phi) c): the unclipped phase search with the roles swapped
        q, psi = _phase_searches(np.array([cm for cm, _, _ in models]), c, np.array(info))
        dof = 2 * k - 1
        for j, i in enumerate(rows):
            out[i] = {"statistic": float(q[j]), "dof": dof, "log10_p": B.log_chi2_sf(float(q[j]), dof) / np.log(10.0),
                      "phase_rad": -float(psi[j]), "f0_Hz": float(f[j]), "n_harmonics": k,
                      "clipped_mean_coefficients": models[j][0].tolist(),
                      "residual_sigma_V": float(np.sqrt(models[j][2]))}
    return out


def detect(x: np.ndarray, dt_s: float, kinematics: dict, baseline: B.Baseline,
           settings: B.BaselineSettings, end_codes: tuple[float, float, float] | None = None) -> B.BaselineDetection:
    """:func:`.baseline.detect`, and on a record with clipped samples the clipped-noise model above
    (:func:`detect_many` of one record).

    Parameters as :func:`.baseline.detect`; ``end_codes``: the ADC's, where known (:func:`clip_levels`). Every type's entry reports ``clipped_fraction`` [-] and, where
    clipped, ``noise_sigma_V`` (the noise before the ADC) [V] and ``clip_levels_V``. A clipped record's folds
    stay on the record's clock and its outer-race gain at 1: ``follow_passage_phase_applied`` and
    ``gain_tolerance_applied`` are false where the settings ask for them (not modelled under clipping).
    """
    return detect_many([x], dt_s, kinematics, baseline, settings, end_codes)[0]


@one_blas_thread
def detect_many(records, dt_s: float, kinematics: dict, baseline: B.Baseline, settings: B.BaselineSettings,
                end_codes: tuple[float, float, float] | None = None) -> list[B.BaselineDetection]:
    """:func:`detect` of each record of ``records`` (a sequence, or the rows of an array) [V]: the unclipped ones
    through :func:`.baseline.detect_many`, the clipped ones' outer-race tests together (records of one length);
    each detection is the record's alone."""
    xs = [np.asarray(x, float) for x in records]
    levels = [clip_levels(x, end_codes) for x in xs]
    out: list = [None] * len(xs)
    plain = [i for i, (_, _, frac) in enumerate(levels) if frac == 0.0]
    for i, d in zip(plain, B.detect_many([xs[i] for i in plain], dt_s, kinematics, baseline, settings), strict=True):
        for p in d.per_type.values():
            p["clipped_fraction"] = 0.0
        out[i] = d
    clipped = [i for i in range(len(xs)) if out[i] is None]
    for n in dict.fromkeys(xs[i].size for i in clipped):
        rows = [i for i in clipped if xs[i].size == n]
        th = _phase_grid((baseline.coefficients.size - 1) // 2)
        wave = waveform(baseline.coefficients, th)  # once for all records
        fronts = [_front(xs[i], dt_s, kinematics, baseline, settings, *levels[i][:2], wave) for i in rows]
        window = (kinematics["bpfo_Hz"] * (1.0 - settings.slip_max), kinematics["bpfo_Hz"])
        outer = harmonic_tests(np.array([xs[i] for i in rows]), dt_s, [fr[1]["bpfo_Hz"] for fr in fronts], baseline,
                               [fr[3] for fr in fronts], [levels[i][:2] for i in rows], settings.tolerance, window)
        for i, fr, o in zip(rows, fronts, outer, strict=True):
            out[i] = _decide_clipped(xs[i], fr, o, levels[i], dt_s, baseline, settings)
    return out


def _front(x, dt_s, kinematics, baseline, settings, lo, hi, wave) -> tuple:
    """A clipped record's steps before the outer-race test: (slip, fault frequencies, residual [V], the noise's
    sigma before the ADC [V]); ``wave``: the baseline's waveform on its phase grid [V]."""
    s, f0, p, f = B.roller_passage(x, dt_s, kinematics, baseline, settings)
    r = x - p
    scale = B.fit_variance_scale(x.size, dt_s, f0, settings.alias_folds)
    sigma = noise_sigma(float(np.mean(r * r)) * scale**2, wave, lo, hi)
    return s, f, r, sigma


def _decide_clipped(x, front, outer, levels, dt_s, baseline, settings) -> B.BaselineDetection:
    """The folds of a clipped record (standardised by the clipped noise's variance) and the decision."""
    s, f, r, sigma = front
    lo, hi, frac = levels
    # the residual standardised by the clipped noise's variance at each sample's phase of the roller train
    theta = 2.0 * np.pi * outer["f0_Hz"] * dt_s * np.arange(x.size) - outer["phase_rad"]
    _, v = clipped_normal_moments(waveform(baseline.coefficients, theta), sigma, lo, hi)
    z = r / np.sqrt(np.maximum(v, 1e-6 * np.mean(v)))  # as the unclipped detector's r / sigma
    details = {t: outer if t == "outer_race" else B.fold_test(z, dt_s, 1.0 / f[B._FOLD_CARRIER[t]])
               for t in settings.fault_types}
    return B.decide(details, settings, {
        "slip": s, "sigma_V": outer["residual_sigma_V"], "clipped_fraction": frac, "noise_sigma_V": sigma,
        "clip_levels_V": [lo, hi], "gain_tolerance_applied": settings.gain_tolerance == 0,
        "follow_passage_phase_applied": not settings.follow_passage_phase})
