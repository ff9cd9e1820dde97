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
   sigma = 1.4826 MAD(r) (robust to the impacts) x sqrt(n / (n - n_p)) (the
   residual of a fit of n_p parameters keeps (n - n_p) / n of the noise's
   variance: 3% at 2550 Hz, which made the outer-race test run high).
3. Outer race (:func:`harmonic_test`): an outer-race defect under the sensor
   is itself BPFO-periodic, so it changes the roller-passage harmonics.
   Their coefficients c (k = 1..K below Nyquist, the fit of step 2 without
   the folded harmonics) are compared with the healthy baseline's c_b,
   aligned by the phase phi of the roller train:
   q = min_phi ||A(f) (c(f) - R(phi) c_b)||^2 / sigma^2 (+ a relative
   ``tolerance`` of the baseline per harmonic), with A(f) the harmonics'
   design matrix at the fundamental f; f is the healthy model's, the
   baseline's waveform fitted to the record over the slip window: under
   noise alone q ~ chi^2 with 2K - 1 degrees of freedom (Gaussian white
   noise, exact covariance sigma^2 (A^T A)^-1; bounded by the likelihood
   ratio with f fitted in both models).
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

from dataclasses import dataclass, field

import numpy as np

from ..threads import one_blas_thread
from .detector import CLASSIFIED_TYPES
from .fault_bands import slipped_frequencies
from .harmonics import (  # noqa: F401 (API)
    Harmonics,
    below_nyquist,
    harmonic_fit,
    harmonic_matrix,
    n_fitted,
    periodic_part,
    refine_period,
)
from .harmonics import lstsq_qr as _lstsq  # noqa: F401 (the tests' reference)
from .outer_race import (  # noqa: F401 (API: the outer-race test, moved to its module)
    _information,
    _phase_search,
    harmonic_test,
    harmonic_tests,
    log_chi2_sf,
)
from .passage import on_passage_clock

#: What fault_indicator.json's detector entries mean with signals.detector.statistic = baseline.
DEFINITION = (
    "fault_types (statistic baseline): the cage slip from the roller-passage lines (k BPFO, k = 1..3); the "
    "BPFO-periodic part (every harmonic to alias_folds x f_s) removed by least squares, sigma = 1.4826 MAD of the "
    "rest; outer_race: the roller-passage harmonics below Nyquist against the healthy baseline's, aligned in "
    "phase, at the fundamental of the baseline's waveform fitted to the record over the slip window, chi^2 with "
    "2K-1 degrees of freedom; inner_race, rolling_element: the rest over sigma, squared and "
    "folded on 1/BPFI and 1/(2 BSF), one cell per sample (follow_passage_phase: on the record resampled where its "
    "roller-passage phase theta is uniform, the inner race on Z f_shaft t - theta), the smallest cell chi^2 "
    "p-value corrected for the search over the cells; indicator = -log10 p, threshold = -log10(pfa / n_types), detected = indicator > "
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
    gain_tolerance : float
        Relative standard deviation of the baseline's overall level against the running bearing's [-]: the
        outer-race test fits one gain g on the baseline's harmonics with the penalty (g - 1)^2 / tau^2 (0: g = 1).
        A baseline off in level (the sensor's load share, d33, C) is absorbed; a change of the waveform's shape
        is not. A free gain (tau = inf) was tried and dropped: with the fundamental searched too, a gain below 1
        pays for the drift that attenuates an off-frequency fit, and the search then averages the fault's high
        harmonics away (a synthetic outer-race fault at 10 dB went from q = 921 to 40, 33 degrees of freedom).
    follow_passage_phase : bool
        Move the record to its roller-passage clock first (:func:`.passage.on_passage_clock`): for a cage
        whose slip jitters from passage to passage (README, "Slip jitter"). False: the passages are taken as
        periodic over the record.
    """

    slip_max: float = 0.03
    false_alarm_probability: float = 1e-3
    fault_types: tuple[str, ...] = CLASSIFIED_TYPES
    alias_folds: float = 1.0
    slip_harmonics: int = 3
    tolerance: float = 0.0
    gain_tolerance: float = 0.0
    follow_passage_phase: bool = False

    @property
    def alpha_per_type(self) -> float:
        """False-alarm probability of each type's test, pfa / n_types (Bonferroni) [-]."""
        return self.false_alarm_probability / len(self.fault_types)

    @classmethod
    def from_config(cls, sig: dict) -> "BaselineSettings":
        d = sig["detector"]
        return cls(slip_max=d["slip_max"], false_alarm_probability=sig["false_alarm_probability"],
                   tolerance=d["baseline_tolerance"], gain_tolerance=d["baseline_gain_tolerance"],
                   follow_passage_phase=d["follow_passage_phase"])


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
        c, _ = Harmonics(np.size(v), dt_s, f0, below_nyquist(dt_s, f0)).fit(np.asarray(v, float))
        return cls(s, c, dt_s)


# --------------------------------------------------------------------------- tests


def _search_corrected(log_p: float, n_tests: int) -> float:
    """ln of 1 - (1 - p)^n for p = e^log_p (the smallest of n independent p-values) [-]."""
    if log_p > -30.0:
        return float(np.log(-np.expm1(n_tests * np.log1p(-np.exp(log_p)))))
    return float(np.log(n_tests) + log_p)


def roller_passage(x: np.ndarray, dt_s: float, kinematics: dict, baseline: Baseline,
                   settings: BaselineSettings) -> tuple[float, float, np.ndarray, dict]:
    """Both detectors' first steps on the record ``x`` [V] (:func:`detect`, :func:`.clipped.detect`): its clock
    checked against the baseline's, the slip from the roller-passage lines, one Gauss-Newton step on BPFO and
    the periodic part. Returns the slip [-], BPFO [Hz], the periodic part [V] and the fault frequencies at
    that slip [Hz]."""
    if abs(dt_s - baseline.dt_s) > 1e-9 * dt_s:
        raise ValueError(f"the record's step {dt_s:g} s differs from the baseline's {baseline.dt_s:g} s")
    s = estimate_slip(x, dt_s, kinematics["bpfo_Hz"], settings.slip_max, settings.slip_harmonics)
    f0, p = refine_period(x, dt_s, slipped_frequencies(kinematics, s)["bpfo_Hz"], settings.alias_folds)
    s = slip_of(kinematics, f0)
    return s, f0, p, slipped_frequencies(kinematics, s)


def fit_variance_scale(n: int, dt_s: float, f0_Hz: float, alias_folds: float) -> float:
    """sqrt(n / (n - n_p)) [-]: the residual of a least-squares fit of n_p parameters (the roller-passage
    fit's) keeps (n - n_p) / n of white noise's variance."""
    n_p = 2 * n_fitted(dt_s, f0_Hz, alias_folds) + 1
    return float(np.sqrt(n / max(n - n_p, 1)))


def decide(details: dict, settings: BaselineSettings, common: dict) -> BaselineDetection:
    """Each type's test result in ``details`` (its ``log10_p``) at alpha = pfa / n_types, with the entries of
    ``common`` added to each type's; the fault type: the detected type of smallest p, else none."""
    thr = -np.log10(settings.alpha_per_type)
    per_type = {}
    for t, d in details.items():
        ind = -d["log10_p"]
        per_type[t] = {"indicator": ind, "threshold": thr, "detected": bool(ind > thr),
                       "p_value": float(10.0 ** -ind), "margin": ind / thr, **common}
    hits = [t for t in per_type if per_type[t]["detected"]]
    kind = max(hits, key=lambda t: per_type[t]["indicator"]) if hits else "none"
    return BaselineDetection(kind, per_type, details)


def _noise_scale(r: np.ndarray, dt_s: float, f0_Hz: float, alias_folds: float) -> float:
    """sigma [V] of the residual ``r`` of the roller-passage fit: 1.4826 MAD x :func:`fit_variance_scale`."""
    sigma = robust_sigma(r) * fit_variance_scale(r.size, dt_s, f0_Hz, alias_folds)
    if not sigma > 0:
        raise ValueError("the record without its roller-passage part is constant: no noise to scale by")
    return sigma


def fold_test(z: np.ndarray, dt_s: float, period_s: float, phase: np.ndarray | None = None) -> dict:
    """Standardised residual ``z`` folded on ``period_s``: the cell whose sum of z^2 is least likely.

    Cell j of the n_c = round(period / dt) cells of the period holds the
    samples whose phase (i dt / period mod 1, or ``phase`` [cycles] of each
    sample where given: a fault whose rate is not constant on the record's
    clock) falls in [j, j+1) / n_c; its sum of z^2 is chi^2 with m_j degrees
    of freedom under white noise. The smallest p-value is corrected for the
    search over the cells.

    Returns
    -------
    dict
        log10_p (corrected), cell (phase of the best cell, [0, 1)), cell_ratio (its mean z^2) [-], n_cells.
    """
    z = np.asarray(z, float)
    nc = max(int(round(period_s / dt_s)), 2)
    phase = np.mod(np.arange(z.size) * (dt_s / period_s) if phase is None else np.asarray(phase, float), 1.0)
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


def detect(x: np.ndarray, dt_s: float, kinematics: dict, baseline: Baseline,
           settings: BaselineSettings) -> BaselineDetection:
    """Test every fault type of ``settings`` in the record ``x`` [V] against the healthy ``baseline``
    (:func:`detect_many` of one record).

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
    return detect_many([x], dt_s, kinematics, baseline, settings)[0]


@one_blas_thread
def detect_many(records, dt_s: float, kinematics: dict, baseline: Baseline,
                settings: BaselineSettings) -> list[BaselineDetection]:
    """:func:`detect` of each record of ``records`` (a sequence, or the rows of an array) [V]; the outer-race tests
    of records of one length run together (:func:`.outer_race.harmonic_tests`), the rest record by record. Each
    detection is the record's alone (tests)."""
    xs = [np.asarray(x, float) for x in records]
    parts = [_front(x, dt_s, kinematics, baseline, settings) for x in xs]
    outer: list = [None] * len(xs)
    if "outer_race" in settings.fault_types:
        window = (kinematics["bpfo_Hz"] * (1.0 - settings.slip_max), kinematics["bpfo_Hz"])
        for n in dict.fromkeys(x.size for x in xs):
            rows = [i for i, x in enumerate(xs) if x.size == n]
            res = harmonic_tests(np.array([xs[i] for i in rows]), dt_s, [parts[i][1]["bpfo_Hz"] for i in rows],
                                 [baseline] * len(rows), [parts[i][2] for i in rows], settings.tolerance, window,
                                 settings.gain_tolerance)
            for i, d in zip(rows, res, strict=True):
                outer[i] = d
    return [_decide_types(part, o, kinematics, dt_s, settings) for part, o in zip(parts, outer, strict=True)]


def _front(x: np.ndarray, dt_s: float, kinematics: dict, baseline: Baseline, settings: BaselineSettings) -> tuple:
    """A record's steps before the tests: (slip, fault frequencies, sigma [V], z, its clock or None, the
    folds' fault frequencies)."""
    s, f0, p, f = roller_passage(x, dt_s, kinematics, baseline, settings)
    sigma = _noise_scale(x - p, dt_s, f0, settings.alias_folds)
    z, t_of, f_fold = (x - p) / sigma, None, f
    if settings.follow_passage_phase:  # the folds on the record's roller-passage clock (module passage)
        clock = on_passage_clock(x, dt_s, f0)
        f0_fold, p_fold = refine_period(clock.voltage_V, dt_s, clock.f0_Hz, settings.alias_folds)
        r = clock.voltage_V - p_fold
        z, t_of = r / _noise_scale(r, dt_s, f0_fold, settings.alias_folds), clock.time_s
        f_fold = slipped_frequencies(kinematics, slip_of(kinematics, f0_fold))
    return s, f, sigma, z, t_of, f_fold


def _decide_types(part: tuple, outer: dict | None, kinematics: dict, dt_s: float,
                  settings: BaselineSettings) -> BaselineDetection:
    """Every type's test of one record (the outer race's given) and the decision."""
    s, f, sigma, z, t_of, f_fold = part
    details = {}
    for t in settings.fault_types:
        if t == "outer_race":
            details[t] = outer
        elif t == "inner_race" and t_of is not None:  # the defect turns with the shaft: Z f_shaft t - theta
            phase = f_fold["bpfo_Hz"] / f_fold["ftf_Hz"] * f["shaft_Hz"] * t_of - f_fold["bpfo_Hz"] * dt_s * np.arange(z.size)
            details[t] = fold_test(z, dt_s, 1.0 / f_fold["bpfi_Hz"], phase)
        else:
            details[t] = fold_test(z, dt_s, 1.0 / f_fold[_FOLD_CARRIER[t]])
    return decide(details, settings, {"slip": s, "sigma_V": sigma})
