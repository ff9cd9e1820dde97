r"""A calibrated detection test from seeds: threshold at a false-alarm rate, detection probability, ROC.

A detector's statistic s (here the true fault family's margin, :mod:`piezobearing.comparison.calibrated`) on N
healthy realisations sets the threshold; on M faulty realisations it gives the detection probability there:

* **Threshold at a false-alarm rate alpha** (:func:`threshold_at`): the empirical (1 - alpha) quantile of the
  healthy statistics, the smallest order statistic with at most floor(alpha N) healthy values above it.
* **Threshold from a fitted tail** (:func:`tail_threshold`), for rates below what N seeds resolve: the healthy
  values above the empirical (1 - q) quantile u (the top q N) minus u are fitted by a generalized Pareto
  distribution (Pickands-Balkema-de Haan: the excesses over a high threshold of any distribution in an
  extreme-value domain tend to it; shape 0 is the exponential tail), and the threshold is
  u + G^{-1}(1 - alpha / q). The fit is checked by the Kolmogorov-Smirnov distance of the excesses to the fitted
  distribution and its p-value (with the parameters fitted on the same excesses the p-value is optimistic:
  a small one rejects the fit, a large one does not prove it).
* **Detection probability** at a threshold t (:func:`detection`): k of M faulty values above t, k / M with the
  Clopper-Pearson interval (exact, the beta quantiles alpha/2 and 1 - alpha/2 of k and k + 1 successes).
* **ROC** (:func:`roc`): false-alarm rate and detection probability at every threshold; its area, the
  Mann-Whitney probability that a faulty value exceeds a healthy one (ties counted half).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats


def _finite_sorted(values) -> np.ndarray:
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        raise ValueError("a threshold needs at least one healthy value")
    return np.sort(x)


def threshold_at(healthy, false_alarm_rate: float) -> float:
    """The empirical threshold: the smallest healthy order statistic with at most floor(alpha N) values above it.

    Parameters
    ----------
    healthy : array_like
        The statistic on N healthy realisations (-inf allowed: a statistic of zero in dB).
    false_alarm_rate : float
        alpha in (0, 1).
    """
    if not 0.0 < false_alarm_rate < 1.0:
        raise ValueError(f"false_alarm_rate = {false_alarm_rate!r}: give a rate in (0, 1)")
    x = _finite_sorted(healthy)
    k = int(math.floor(false_alarm_rate * x.size + 1e-9))
    return float(x[x.size - 1 - min(k, x.size - 1)])


@dataclass(frozen=True)
class Detection:
    """Detection probability at a threshold, with its Clopper-Pearson interval.

    Attributes
    ----------
    threshold : float
    detected : int
        Faulty values above the threshold k [-].
    n : int
        Faulty values M [-].
    probability : float
        k / M [-].
    ci_low, ci_high : float
        The interval at ``level`` [-].
    level : float
        Its confidence level [-].
    """

    threshold: float
    detected: int
    n: int
    probability: float
    ci_low: float
    ci_high: float
    level: float


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper-Pearson) interval of a binomial proportion k / n at confidence ``level``."""
    if n <= 0 or not 0 <= k <= n:
        raise ValueError(f"clopper_pearson: need 0 <= k <= n and n > 0, got k = {k}, n = {n}")
    a = 1.0 - level
    low = 0.0 if k == 0 else float(stats.beta.ppf(a / 2, k, n - k + 1))
    high = 1.0 if k == n else float(stats.beta.ppf(1 - a / 2, k + 1, n - k))
    return low, high


def detection(faulty, threshold: float, level: float = 0.95) -> Detection:
    """The share of faulty values above ``threshold`` and its Clopper-Pearson interval."""
    f = np.asarray(faulty, dtype=float)
    k = int(np.count_nonzero(f > threshold))
    low, high = clopper_pearson(k, f.size, level)
    return Detection(float(threshold), k, int(f.size), k / f.size, low, high, level)


@dataclass(frozen=True)
class TailFit:
    """A generalized Pareto fit of the healthy statistic's upper tail and the threshold it gives.

    Attributes
    ----------
    threshold : float
        u + G^{-1}(1 - alpha / q) [the statistic's unit].
    false_alarm_rate : float
        alpha [-].
    tail_fraction : float
        q: the share of healthy values whose excesses are fitted [-].
    location : float
        u, the empirical (1 - q) quantile [the statistic's unit].
    shape, scale : float
        The fitted GPD's shape xi (0: exponential) [-] and scale sigma [the statistic's unit].
    n_excesses : int
        Excesses fitted [-].
    ks_statistic, ks_p_value : float
        Kolmogorov-Smirnov distance of the excesses to the fit, and its p-value (optimistic: fitted
        parameters) [-].
    """

    threshold: float
    false_alarm_rate: float
    tail_fraction: float
    location: float
    shape: float
    scale: float
    n_excesses: int
    ks_statistic: float
    ks_p_value: float


def tail_threshold(healthy, false_alarm_rate: float, tail_fraction: float = 0.2) -> TailFit:
    """The threshold at ``false_alarm_rate`` from a generalized Pareto fit of the top ``tail_fraction`` of the
    healthy values (module docstring); needs false_alarm_rate < tail_fraction and at least 5 excesses."""
    if not 0.0 < false_alarm_rate < tail_fraction < 1.0:
        raise ValueError(f"tail_threshold: need 0 < false_alarm_rate ({false_alarm_rate}) < tail_fraction "
                         f"({tail_fraction}) < 1")
    x = _finite_sorted(healthy)
    x = x[np.isfinite(x)]
    u = threshold_at(x, tail_fraction)
    exc = x[x > u] - u
    if exc.size < 5:
        raise ValueError(f"tail_threshold: {exc.size} healthy values above the tail's start; give more seeds "
                         f"(at least {math.ceil(5 / tail_fraction)})")
    q = exc.size / x.size
    shape, _, scale = stats.genpareto.fit(exc, floc=0.0)
    t = u + float(stats.genpareto.ppf(1.0 - false_alarm_rate / q, shape, loc=0.0, scale=scale))
    ks = stats.kstest(exc, "genpareto", args=(shape, 0.0, scale))
    return TailFit(float(t), float(false_alarm_rate), float(q), float(u), float(shape), float(scale),
                   int(exc.size), float(ks.statistic), float(ks.pvalue))


@dataclass(frozen=True)
class Roc:
    """The ROC curve of a statistic: at each threshold, the healthy share above it and the faulty share above it.

    Attributes
    ----------
    false_alarm_rate, detection_probability : ndarray
        From (1, 1) at the lowest threshold to (0, 0) above the highest [-].
    auc : float
        The area under it: P(faulty > healthy) + P(faulty = healthy) / 2 [-].
    """

    false_alarm_rate: np.ndarray
    detection_probability: np.ndarray
    auc: float


def roc(healthy, faulty) -> Roc:
    """The ROC curve and its area (Mann-Whitney) of the statistic on healthy and faulty realisations."""
    h, f = np.asarray(healthy, dtype=float), np.asarray(faulty, dtype=float)
    levels = np.unique(np.concatenate([h, f]))
    far = np.r_[1.0, [np.mean(h > t) for t in levels]]
    pd = np.r_[1.0, [np.mean(f > t) for t in levels]]
    greater = np.mean(f[:, None] > h[None, :])
    ties = np.mean(f[:, None] == h[None, :])
    return Roc(far, pd, float(greater + 0.5 * ties))
