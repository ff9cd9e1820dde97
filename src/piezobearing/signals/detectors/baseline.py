"""A fault detector against a healthy baseline: the roller-passage part removed, impacts found in time.

Why. The sensor sits in the load zone and sees every roller pass: a smooth
bump per roller, 96 V peak to peak in the paper's case, periodic at BPFO. A
defect on the inner race or on a roller adds a few sharp impacts only when
it meets a roller near the sensor: at the paper's 2550 Hz and 10 dB the
inner-race record differs from the healthy one by 6.2 V rms, 94% of that in
40 of 2295 samples (single impacts up to 125 V against 11.4 V of noise),
but its spectrum spreads over about 270 bins, none far above the noise, so
no envelope line carries it.
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

Clipped records
---------------
Why. An ADC clips its input x = b(t) + n(t) to its end codes [lo, hi]. The
record's BPFO-periodic part is then E[clip(b(t) + n)], not b(t): clipping
compresses the roller-passage harmonics and makes new ones. The baseline
detector's outer-race test (:func:`..outer_race.harmonic_test`) compares the
record's harmonics with the unclipped healthy baseline's and calls the
healthy bearing an outer-race fault (the ``daq_noise`` study at 1 V/sqrt(Hz):
20 of 20 seeds at 2550 and at 10240 Hz; docs/validation/detection.md).

What. For Gaussian noise n of standard deviation sigma (before the ADC) the
clipped sample Y = clip(mu + n, lo, hi) has the closed-form mean and variance
of a clipped normal (:func:`clipped_normal_moments`). With mu = b(theta), the
baseline's waveform over one period of the roller train:

1. Clip levels (:func:`clip_levels`): the ADC's end codes where the DAQ is
   known (``Settings.end_codes_V``); otherwise the record's smallest and
   largest value, each counted as an end code when at least two samples sit
   on it (an unclipped record with continuous noise repeats its extreme with
   probability ~0).
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
3. Outer race (:func:`clipped_harmonic_tests`): the record's harmonics c (k = 1..K)
   against the clipped mean's, m(theta) = E[clip(b(theta) + n)], aligned in
   phase, with the covariance of c under the clipped noise's periodic
   variance V(theta): C = (4 / n) E_theta[V a a^T] (a: the harmonics'
   cos/sin at theta; white noise, the samples' phases uniform over the
   period), so q ~ chi^2_{2K-1} again. The fundamental is the unclipped
   detector's search with m in place of the baseline.
4. Inner race and rolling element: the residual standardised sample by
   sample, z_i = r_i / sqrt(V(theta_i)), then the same folds (clipped noise is
   bounded, so the cells' chi^2 tails are conservative).

An unclipped record goes through the steps above unchanged. The
model ignores the mains and drive lines under the noise (a 1 mV line against
tens of volts of noise where the noise clips), and a clipped record at a
DAQ's micro-volt noise (the signal's own peaks beyond the range) reduces to
clip(b): what the healthy waveform clipped looks like.

Evidence (:class:`~.result.Detection`): per family statistic = -log10 p, threshold =
-log10(pfa / n_types), margin_dB = 10 log10(statistic / threshold); no lines (the
tests read the whole waveform, not envelope lines). ``details``: ``per_type`` (per
family indicator, threshold, detected, p_value, margin, slip, sigma_V and the
clipping keys) and ``tests`` (per family the test's own numbers: the outer-race
test's q, dof, log10_p, phase_rad, f0_Hz, n_harmonics; a fold's log10_p, cell,
cell_ratio, n_cells).

One module for the unclipped and the clipped record (one :func:`detect`, one
:func:`detect_many`): its length over 600 lines is the clipped-noise model,
which only this detector uses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar
from scipy.special import ndtr

from ...numerics.threads import one_blas_thread
from .. import daq
from ..fault_bands import slipped_frequencies
from ..harmonics import Harmonics, below_nyquist, harmonic_fits, n_fitted, refine_period
from ..outer_race import _phase_searches, harmonic_tests, log_chi2_sf, row_chunks
from ..passage import on_passage_clock
from .result import FAULT_TYPES, Detection, FamilyEvidence, margin_dB

#: What fault_indicator.json's detector entries mean with signals.detector.statistic = baseline.
DEFINITION = (
    "detection (statistic baseline): the cage slip from the roller-passage lines (k BPFO, k = 1..3); the "
    "BPFO-periodic part (every harmonic to alias_folds x f_s) removed by least squares, sigma = 1.4826 MAD of the "
    "rest; outer_race: the roller-passage harmonics below Nyquist against the healthy baseline's, aligned in "
    "phase, at the fundamental of the baseline's waveform fitted to the record over the slip window, chi^2 with "
    "2K-1 degrees of freedom; inner_race, rolling_element: the rest over sigma, squared and "
    "folded on 1/BPFI and 1/(2 BSF), one cell per sample (follow_passage_phase: on the record resampled where its "
    "roller-passage phase theta is uniform, the inner race on Z f_shaft t - theta), the smallest cell chi^2 "
    "p-value corrected for the search over the cells; per family statistic = -log10 p, threshold = "
    "-log10(pfa / n_types), detected = statistic > threshold, margin_dB = 10 log10(statistic / threshold) (details: "
    "per_type, each test's own numbers under tests); fault_type: none if no type is detected, else the detected "
    "type of smallest p"
)
_FOLD_CARRIER = {"inner_race": "bpfi_Hz", "rolling_element": "2bsf_Hz"}


@dataclass(frozen=True)
class Settings:
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
        Move the record to its roller-passage clock first (:func:`..passage.on_passage_clock`): for a cage
        whose slip jitters from passage to passage. False: the passages are taken as periodic over the record.
    end_codes_V : tuple of float or None
        The ADC's end codes and half its step, (lo [V], hi [V], q/2 [V]) (:func:`..daq.end_codes_V`), where the
        DAQ is known: a sample within q/2 of an end code is clipped (:func:`clip_levels`). None: an extreme
        counts as an end code when at least two samples sit on it.
    """

    slip_max: float = 0.03
    false_alarm_probability: float = 1e-3
    fault_types: tuple[str, ...] = FAULT_TYPES
    alias_folds: float = 1.0
    slip_harmonics: int = 3
    tolerance: float = 0.0
    gain_tolerance: float = 0.0
    follow_passage_phase: bool = False
    end_codes_V: tuple[float, float, float] | None = None

    @property
    def alpha_per_type(self) -> float:
        """False-alarm probability of each type's test, pfa / n_types (Bonferroni) [-]."""
        return self.false_alarm_probability / len(self.fault_types)

    @classmethod
    def from_config(cls, sig: dict) -> "Settings":
        d = sig["detector"]
        return cls(slip_max=d["slip_max"], false_alarm_probability=sig["false_alarm_probability"],
                   tolerance=d["baseline_tolerance"], gain_tolerance=d["baseline_gain_tolerance"],
                   follow_passage_phase=d["follow_passage_phase"],
                   end_codes_V=daq.end_codes_V(daq.NoiseSettings.from_config(sig)) if "noise" in sig else None)


# --------------------------------------------------------------------------- the roller-passage part


def estimate_slip(x: np.ndarray, dt_s: float, bpfo0_Hz: float, slip_max: float, n_harmonics: int = 3) -> float:
    """Cage slip [-] maximising sum_k |X(k BPFO_0 (1 - s))|^2, k = 1..n, over s in [0, slip_max].

    X is the DTFT of the Hann-windowed record (mean removed). The grid step
    keeps the highest line's phase drift over the record below 0.1 cycle
    between nodes; the best node is refined by a bounded scalar search.
    """
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
    def from_record(cls, v: np.ndarray, dt_s: float, kinematics: dict, settings: Settings) -> "Baseline":
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
                   settings: Settings) -> tuple[float, float, np.ndarray, dict]:
    """The first steps on the record ``x`` [V], clipped or not: its clock
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


def decide(details: dict, settings: Settings, common: dict, shaft_Hz: float) -> Detection:
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
    families = {t: FamilyEvidence(t, float(p["indicator"]), float(thr), margin_dB(p["indicator"], thr), p["detected"])
                for t, p in per_type.items()}
    return Detection.from_families("baseline", families, kind, None, shaft_Hz, settings.false_alarm_probability,
                                   {"per_type": per_type, "tests": details})


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


#: What fault_indicator.json's baseline entries add on a clipped record.
CLIPPED_DEFINITION = (
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

    ``end_codes``: the ADC's end codes and half its step, (lo [V], hi [V], q/2 [V]) (:func:`..daq.end_codes_V`),
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


def clipped_harmonic_tests(x: np.ndarray, dt_s: float, f0_Hz, baseline: Baseline, sigma, levels,
                           tolerance: float = 0.0, f_range_Hz: tuple[float, float] | None = None) -> list[dict]:
    """The outer-race test of :func:`..outer_race.harmonic_tests` on clipped records, each row of ``x`` (R, n) [V]
    with its own ``f0_Hz`` [Hz], ``sigma`` (the noise before the ADC) [V] and clip ``levels`` (lo, hi) [V]
    (sequences of R).

    The fundamental f from the unclipped test's search with the clipped mean's coefficients c_m in place of the
    baseline's (and sqrt(E[V]) as its noise scale); at f, q = min_phi (R(-phi) c - c_m)^T C^-1 (R(-phi) c - c_m),
    C = (4 / n) E_theta[V a a^T] + diag(tolerance^2 |c_m,k|^2) in the baseline's frame (the record rotated
    back, so that C need not rotate); q ~ chi^2_{2K-1} under noise alone. The unclipped tests' searches of all
    rows run together.

    Returns
    -------
    list of dict
        The unclipped test's keys and ``clipped_mean_coefficients`` (c_m) [V], ``residual_sigma_V``
        (sqrt E[V]) [V].
    """
    x = np.asarray(x, float)
    kb = (baseline.coefficients.size - 1) // 2
    f_top = list(f0_Hz) if f_range_Hz is None else [f_range_Hz[1]] * x.shape[0]
    ks = [min(below_nyquist(dt_s, ft), kb) for ft in f_top]
    out: list = [None] * x.shape[0]
    batches = [(kk, list(part)) for kk in dict.fromkeys(ks)  # rows of one K together, in batches
               for part in row_chunks(np.array([i for i in range(x.shape[0]) if ks[i] == kk]), x.shape[1], kk)]
    for k, rows in batches:
        tables = baseline_tables(baseline.coefficients, k)  # once for all rows
        models = [clipped_baseline(baseline.coefficients, sigma[i], *levels[i], k, tables) for i in rows]
        first = harmonic_tests(x[rows], dt_s, [f0_Hz[i] for i in rows],
                                 [Baseline(baseline.slip, cm, dt_s) for cm, _, _ in models],
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
            out[i] = {"statistic": float(q[j]), "dof": dof, "log10_p": log_chi2_sf(float(q[j]), dof) / np.log(10.0),
                      "phase_rad": -float(psi[j]), "f0_Hz": float(f[j]), "n_harmonics": k,
                      "clipped_mean_coefficients": models[j][0].tolist(),
                      "residual_sigma_V": float(np.sqrt(models[j][2]))}
    return out


def _clipped_front(x, dt_s, kinematics, baseline, settings, lo, hi, wave) -> tuple:
    """A clipped record's steps before the outer-race test: (slip, fault frequencies, residual [V], the noise's
    sigma before the ADC [V]); ``wave``: the baseline's waveform on its phase grid [V]."""
    s, f0, p, f = roller_passage(x, dt_s, kinematics, baseline, settings)
    r = x - p
    scale = fit_variance_scale(x.size, dt_s, f0, settings.alias_folds)
    sigma = noise_sigma(float(np.mean(r * r)) * scale**2, wave, lo, hi)
    return s, f, r, sigma


def _decide_clipped(x, front, outer, levels, dt_s, baseline, settings, shaft_Hz) -> Detection:
    """The folds of a clipped record (standardised by the clipped noise's variance) and the decision."""
    s, f, r, sigma = front
    lo, hi, frac = levels
    # the residual standardised by the clipped noise's variance at each sample's phase of the roller train
    theta = 2.0 * np.pi * outer["f0_Hz"] * dt_s * np.arange(x.size) - outer["phase_rad"]
    _, v = clipped_normal_moments(waveform(baseline.coefficients, theta), sigma, lo, hi)
    z = r / np.sqrt(np.maximum(v, 1e-6 * np.mean(v)))  # as the unclipped detector's r / sigma
    details = {t: outer if t == "outer_race" else fold_test(z, dt_s, 1.0 / f[_FOLD_CARRIER[t]])
               for t in settings.fault_types}
    return decide(details, settings, {
        "slip": s, "sigma_V": outer["residual_sigma_V"], "clipped_fraction": frac, "noise_sigma_V": sigma,
        "clip_levels_V": [lo, hi], "gain_tolerance_applied": settings.gain_tolerance == 0,
        "follow_passage_phase_applied": not settings.follow_passage_phase}, shaft_Hz)


# --------------------------------------------------------------------------- the detector


def reference_baseline(reference, sample_rate_Hz: float, kinematics: dict, settings: Settings) -> Baseline:
    """The healthy baseline from ``reference``: a :class:`Baseline`, or a healthy record [V] at ``sample_rate_Hz``."""
    if isinstance(reference, Baseline):
        return reference
    if reference is None:
        raise ValueError("the baseline detector needs a healthy reference record (reference=...); give one, "
                         "or choose the envelope detector")
    return Baseline.from_record(np.asarray(reference, float), 1.0 / sample_rate_Hz, kinematics, settings)


def detect(samples: np.ndarray, sample_rate_Hz: float, kinematics: dict, settings: Settings, reference) -> Detection:
    """Test every fault type of ``settings`` in the record against the healthy ``reference``
    (:func:`detect_many` of one record).

    Parameters
    ----------
    samples : ndarray
        The record [V].
    sample_rate_Hz : float
        Its sampling rate [Hz] (the reference's).
    kinematics : dict
        Kinematic frequencies without slip [Hz].
    settings : Settings
    reference : Baseline or ndarray
        The healthy bearing: its :class:`Baseline`, or its record [V] at ``sample_rate_Hz``.
    """
    return detect_many([samples], sample_rate_Hz, kinematics, settings, reference)[0]


@one_blas_thread
def detect_many(records, sample_rate_Hz: float, kinematics: dict, settings: Settings, reference) -> list[Detection]:
    """:func:`detect` of each record of ``records`` (a sequence, or the rows of an array) [V]; records with clipped
    samples (:func:`clip_levels`) through the clipped-noise model. The outer-race tests of records of one length
    run together (:func:`..outer_race.harmonic_tests`); each detection is the record's alone (tests)."""
    dt_s = 1.0 / sample_rate_Hz
    baseline = reference_baseline(reference, sample_rate_Hz, kinematics, settings)
    xs = [np.asarray(x, float) for x in records]
    levels = [clip_levels(x, settings.end_codes_V) for x in xs]
    plain = [i for i, (_, _, frac) in enumerate(levels) if frac == 0.0]
    clipped = [i for i, (_, _, frac) in enumerate(levels) if frac > 0.0]
    out: list = [None] * len(xs)
    for i, d in zip(plain, _detect_unclipped([xs[i] for i in plain], dt_s, kinematics, baseline, settings),
                    strict=True):
        out[i] = d
    for n in dict.fromkeys(xs[i].size for i in clipped):
        rows = [i for i in clipped if xs[i].size == n]
        wave = waveform(baseline.coefficients, _phase_grid((baseline.coefficients.size - 1) // 2))  # once for all
        fronts = [_clipped_front(xs[i], dt_s, kinematics, baseline, settings, *levels[i][:2], wave) for i in rows]
        window = (kinematics["bpfo_Hz"] * (1.0 - settings.slip_max), kinematics["bpfo_Hz"])
        outer = clipped_harmonic_tests(np.array([xs[i] for i in rows]), dt_s, [fr[1]["bpfo_Hz"] for fr in fronts],
                                       baseline, [fr[3] for fr in fronts], [levels[i][:2] for i in rows],
                                       settings.tolerance, window)
        for i, fr, o in zip(rows, fronts, outer, strict=True):
            out[i] = _decide_clipped(xs[i], fr, o, levels[i], dt_s, baseline, settings, kinematics["shaft_Hz"])
    return out


def _detect_unclipped(xs: list, dt_s: float, kinematics: dict, baseline: Baseline,
                      settings: Settings) -> list[Detection]:
    """The unclipped records' detections; the outer-race tests of records of one length together."""
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


def _front(x: np.ndarray, dt_s: float, kinematics: dict, baseline: Baseline, settings: Settings) -> tuple:
    """A record's steps before the tests: (slip, fault frequencies, sigma [V], z, its clock or None, the
    folds' fault frequencies)."""
    s, f0, p, f = roller_passage(x, dt_s, kinematics, baseline, settings)
    sigma = _noise_scale(x - p, dt_s, f0, settings.alias_folds)
    z, t_of, f_fold = (x - p) / sigma, None, f
    if settings.follow_passage_phase:  # the folds on the record's roller-passage clock (..passage)
        clock = on_passage_clock(x, dt_s, f0)
        f0_fold, p_fold = refine_period(clock.voltage_V, dt_s, clock.f0_Hz, settings.alias_folds)
        r = clock.voltage_V - p_fold
        z, t_of = r / _noise_scale(r, dt_s, f0_fold, settings.alias_folds), clock.time_s
        f_fold = slipped_frequencies(kinematics, slip_of(kinematics, f0_fold))
    return s, f, sigma, z, t_of, f_fold


def _decide_types(part: tuple, outer: dict | None, kinematics: dict, dt_s: float,
                  settings: Settings) -> Detection:
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
    details_common = {"slip": s, "sigma_V": sigma, "clipped_fraction": 0.0}
    return decide(details, settings, details_common, kinematics["shaft_Hz"])
