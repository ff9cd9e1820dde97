"""Model versus measurement: fit, residual tests, effect ranking, stepwise selection, verdict.

The measured record gives the recorded force F and voltage V on one clock.
A :class:`~piezobearing.diagnosis.calibration.model.ForwardModel` (the RC baseline plus effects)
predicts V from F. This module

1. measures the noise floor in the quiet stretches between impulses: the
   white-noise levels s_v of the voltage channel and s_f of the force
   channel (line-free trimmed mean of the periodogram between 5% and 45% of
   the sampling rate, so that drift, decaying tails and mains lines do not
   inflate them). A correct model driven by the recorded force leaves
   r = V - M(F) = n_v - G n_f: white noise through the model's response G,
   with spectrum S(f) = s_v^2 + s_f^2 |G(f)|^2 (the floor of that model);
2. fits a model by maximum likelihood with a known noise spectrum,
   chi2 = sum_k |R_k|^2 / (n S_k / 2) over the DFT bins, so that chi2 ~ n
   for a correct model and BIC = chi2 + k ln n (the noise level measured,
   not fitted). The force channel is noisy too (errors in variables): a
   delay or a lead applied to the recorded force rotates and amplifies its
   noise at every frequency, and a fit could then "explain" part of the
   carried noise (false discoveries) while its Gauss-Newton steps slow
   down. The fit therefore drives the model with the force low-passed at
   twice its band (:func:`~piezobearing.diagnosis.calibration.effects.base.denoised_force`; the
   force's content is untouched, the carried noise remains only in the
   band) and weights by the floor of that input, S_fit = s_v^2 +
   s_f^2 |G W|^2. The residual, NRMSE and tests reported use the recorded
   force as it is;
3. tests the residual whitened by S (which is white for a correct model):
   autocorrelation (Ljung-Box), cross-correlation with the force, its
   spectrum against the floor, and its energy in short time windows, each
   at a quarter of the family-wise significance;
4. ranks every catalogue effect by the BIC drop when it is added to the
   current model, and adds effects stepwise while the drop exceeds
   ``min_delta_bic`` and the effect explains at least ``min_share`` of the
   misfit above the noise floor (chi2 - (n - k));
5. gives the verdict: ``explained`` when the final residual passes the tests,
   else ``unexplained`` with where the structure is (time windows,
   frequencies, lags). When structure remains, an effect added on the way
   may only be standing in for the missing mechanism (a catalogue effect can
   mimic the low-frequency behaviour of, say, a resonance); the selection is
   then cut at the first addition that explained less than
   ``min_share_if_unexplained`` of the misfit left at its step.

NRMSE = rms(residual) / rms(measured voltage) throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.signal import correlate
from scipy.stats import chi2 as chi2_dist
from scipy.stats import norm

from ..sensor.calibration import Impulse
from .calibration.effects import CATALOGUE, Effect, Record, StartContext
from .calibration.effects.base import denoised_force, prefilter_response
from .calibration.model import ForwardModel
from .least_squares import FitResult, fit, nrmse

Z99 = float(norm.isf(0.005))  # 2.576: the 99% two-sided band of a correlation, times 1/sqrt(n)


# =========================================================================== settings


@dataclass(frozen=True)
class DiagnosticsSettings:
    """Settings of the diagnosis (config section ``diagnostics``).

    Parameters
    ----------
    max_steps : int
        Most effects the stepwise selection adds [-].
    min_delta_bic : float
        BIC drop an addition needs (10: "very strong" evidence) [-].
    min_share : float
        Share of the current misfit above the noise floor (chi2 - (n - k)) an addition must explain [-].
    min_share_if_unexplained : float
        When structure remains after the search, the share each kept addition must have explained [-].
    significance : float
        Family-wise false-alarm probability of the four residual tests of the verdict [-].
    max_lag_s : float
        Largest lag of the auto- and cross-correlation tests [s].
    spectrum_segment_s : float
        Segment length of the residual spectrum (its resolution is 1/segment) [s].
    window_s : float
        Length of the windows of the residual-energy test in time [s].
    quiet_settle_s : float
        Time after the force settles before a stretch counts as quiet [s].
    max_nfev : int
        Most model evaluations per fit [-].
    ftol : float
        Relative change of chi2 at which a fit stops (1e-6 of chi2 ~ n is far below any BIC step) [-].
    """

    max_steps: int = 4
    min_delta_bic: float = 10.0
    min_share: float = 0.2
    min_share_if_unexplained: float = 0.5
    significance: float = 0.01
    max_lag_s: float = 0.1
    spectrum_segment_s: float = 2.0
    window_s: float = 0.1
    quiet_settle_s: float = 0.1
    max_nfev: int = 400
    ftol: float = 1e-6

    @classmethod
    def from_config(cls, section: dict | None) -> "DiagnosticsSettings":
        return cls(**(section or {}))

    @property
    def test_alpha(self) -> float:
        """Significance of each of the four residual tests (Bonferroni) [-]."""
        return self.significance / 4


# =========================================================================== noise floor


@dataclass(frozen=True)
class NoiseFloor:
    """White-noise levels of the two channels, measured in quiet stretches.

    Attributes
    ----------
    voltage_noise_V : float
        Std of the voltage channel's own noise [V].
    force_noise_N : float
        Std of the force channel's noise [N].
    quiet_s : float
        Total length of the quiet stretches used [s].
    n_stretches : int
        Number of quiet stretches [-].
    method : str
        How the levels were measured.
    """

    voltage_noise_V: float
    force_noise_N: float
    quiet_s: float
    n_stretches: int
    method: str
    quiet_mask: np.ndarray = field(repr=False, default=None)

    def spectrum(self, response: np.ndarray) -> np.ndarray:
        """S(f) = s_v^2 + s_f^2 |G(f)|^2: variance per sample of the residual noise at each bin [V^2]."""
        s = self.voltage_noise_V**2 + self.force_noise_N**2 * np.abs(response) ** 2
        return np.maximum(s, 1e-30)  # noise-free (synthetic) records: finite weights

    def rms_V(self, response: np.ndarray, n: int) -> float:
        """rms of the residual noise of a model with response G on n samples [V] (Parseval)."""
        s = np.broadcast_to(self.spectrum(response), (n // 2 + 1,))
        w = np.full(s.size, 2.0)
        w[0] = 1.0
        if n % 2 == 0:
            w[-1] = 1.0
        return float(np.sqrt(np.sum(w * s) / n))

    def report(self) -> dict:
        return {
            "voltage_noise_V": self.voltage_noise_V,
            "force_noise_N": self.force_noise_N,
            "quiet_s": self.quiet_s,
            "n_stretches": self.n_stretches,
            "method": self.method,
        }


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of the runs of True in a boolean array."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True))


def _dilate(mask: np.ndarray, before: int, after: int) -> np.ndarray:
    out = mask.copy()
    for a, b in _runs(mask):
        out[max(a - before, 0) : min(b + after, mask.size)] = True
    return out


def robust_diff_std(x: np.ndarray) -> float:
    """Std of white noise on a smooth signal from the MAD of its first differences."""
    d = np.diff(x)
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2))


def quiet_mask(force_N: np.ndarray, dt_s: float, settle_s: float, min_length_s: float = 0.2) -> np.ndarray:
    """Samples where the force rests: away from every press by ``settle_s`` after and 50 ms before.

    A press is where the force, smoothed over 20 ms, departs from its resting
    level (the 10th percentile) by more than 1% of its range or 6 noise
    standard deviations of the smoothed force. Only stretches of at least
    ``min_length_s`` are kept.
    """
    f = np.asarray(force_N, dtype=float)
    w = max(int(round(0.02 / dt_s)), 1)
    fs = np.convolve(f, np.ones(w) / w, mode="same")
    sigma = robust_diff_std(f) / np.sqrt(w)
    rest = np.percentile(fs, 10)
    active = np.abs(fs - rest) > max(0.01 * np.ptp(fs), 6 * sigma)
    active = _dilate(active, int(round(0.05 / dt_s)), int(round(settle_s / dt_s)))
    quiet = ~active
    keep = np.zeros_like(quiet)
    for a, b in _runs(quiet):
        if (b - a) * dt_s >= min_length_s:
            keep[a:b] = True
    return keep


def white_level(
    x: np.ndarray,
    mask: np.ndarray,
    dt_s: float,
    segment: int = 256,
    line_factor: float = 20.0,
    trim: float = 6.0,
) -> tuple[float, int]:
    """Variance of the white part of x in the masked stretches [unit^2], and the number of ordinates used.

    Each stretch is cut into segments (at most ``segment`` samples, at least
    64), detrended and Hann-windowed; only periodogram ordinates between 5%
    and 45% of the sampling rate are used, so slow trends and decaying
    tails do not count. For white noise each ordinate is sigma^2 times an
    exponential variable. A first level from the median (over ln 2) marks
    spectral lines (ordinates above ``line_factor`` times it, with 4 bins
    either side, e.g. mains); the level is then the mean of the remaining
    ordinates below ``trim`` times the first level, corrected for that
    truncation (E[X | X < c] = (1 - (1 + c) e^-c) / (1 - e^-c) for a unit
    exponential).
    """
    spectra = []
    for a, b in _runs(mask):
        for s0 in range(a, b - 63, segment):
            seg = x[s0 : min(s0 + segment, b)]
            if seg.size < 64:
                continue
            t = np.arange(seg.size)
            seg = seg - np.polyval(np.polyfit(t, seg, 1), t)
            win = np.hanning(seg.size)
            p = np.abs(np.fft.rfft(seg * win)) ** 2 / np.sum(win**2)
            fr = np.fft.rfftfreq(seg.size)
            spectra.append(p[(fr >= 0.05) & (fr <= 0.45)])
    if not spectra:
        return float("nan"), 0
    level0 = float(np.median(np.concatenate(spectra)) / np.log(2))
    kept = []
    for p in spectra:
        line = _dilate(p > line_factor * level0, 4, 4)
        kept.append(p[~line & (p < trim * level0)])
    k = np.concatenate(kept)
    c = trim
    return float(np.mean(k) * (1 - np.exp(-c)) / (1 - (1 + c) * np.exp(-c))), int(k.size)


def estimate_noise_floor(
    record: Record, voltage_V: np.ndarray, settings: DiagnosticsSettings, tau_s: float = 0.0
) -> NoiseFloor:
    """Measure s_v and s_f in the quiet stretches (settling ``quiet_settle_s`` + 5 tau after each press).

    Falls back on the whole record when the quiet stretches hold fewer than
    1000 samples: s_f from the force's high band, s_v from the voltage's high
    band less the force noise carried with the gain ``|G|`` of the nominal
    circuit (recorded in ``method``).
    """
    dt = record.dt_s
    mask = quiet_mask(record.force_N, dt, settings.quiet_settle_s + 5 * tau_s)
    if mask.sum() >= 1000:
        vf, _ = white_level(record.force_N, mask, dt)
        vv, _ = white_level(voltage_V, mask, dt)
        runs = _runs(mask)
        return NoiseFloor(
            float(np.sqrt(vv)),
            float(np.sqrt(vf)),
            float(mask.sum() * dt),
            len(runs),
            "quiet stretches: line-free trimmed mean of the periodogram, 5-45% of fs",
            mask,
        )
    whole = np.ones(record.n, dtype=bool)
    vf, _ = white_level(record.force_N, whole, dt)
    vv, _ = white_level(voltage_V, whole, dt)
    return NoiseFloor(
        float(np.sqrt(vv)),
        float(np.sqrt(vf)),
        0.0,
        0,
        "whole record (no quiet stretches): voltage level includes carried force noise",
        mask,
    )


# =========================================================================== fitting


def fd_weighted(residual_V: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The residual as n real numbers of unit variance for a correct model.

    R = rfft(r); interior bins give Re and Im scaled by sqrt(2 / (n S)), the
    0 and Nyquist bins their real part scaled by sqrt(1 / (n S)). The sum of
    squares is sum r^2 / sigma^2 for white noise of variance sigma^2 = S.
    """
    n = residual_V.size
    r = np.fft.rfft(residual_V)
    w = np.sqrt(2.0 / (n * s))
    w[0] /= np.sqrt(2.0)
    if n % 2 == 0:
        w[-1] /= np.sqrt(2.0)
        return np.concatenate([(r * w).real, (r[1:-1] * w[1:-1]).imag])
    return np.concatenate([(r * w).real, (r[1:] * w[1:]).imag])


def whiten(residual_V: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The residual filtered by 1/sqrt(S) (zero-phase, circular): unit-variance white noise for a correct model."""
    return np.fft.irfft(np.fft.rfft(residual_V) / np.sqrt(s), residual_V.size)


@dataclass
class ModelFit:
    """A fitted model and its residual."""

    model: ForwardModel
    result: FitResult
    model_V: np.ndarray = field(repr=False)
    residual_V: np.ndarray = field(repr=False)
    whitened: np.ndarray = field(repr=False)
    response: np.ndarray = field(repr=False)
    nrmse: float
    floor_nrmse: float
    floor_rms_V: float

    @property
    def values(self) -> dict:
        return self.result.values

    @property
    def chi2(self) -> float:
        return self.result.chi2

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
            "residual_rms_V": float(np.sqrt(np.mean(self.residual_V**2))),
            "noise_floor_rms_V": self.floor_rms_V,
            "chi2": r.chi2,
            "chi2_per_sample": r.chi2 / r.n_data,
            "bic": r.bic,
            "n_free": r.n_free,
            "params": r.values,
            "stderr": r.stderr,
            "ci95": r.ci95,
            "converged": r.success,
        }


def fit_model(
    model: ForwardModel,
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    start: dict | None = None,
    starts: list[dict] | None = None,
    max_nfev: int | None = None,
    ftol: float = 1e-8,
) -> ModelFit:
    """Fit ``model`` by the errors-in-variables cost (see the module docstring).

    ``start`` holds start values (others: defaults); each dict in ``starts``
    overrides some of them for one more start, and the best fit is kept.
    """
    v = np.asarray(voltage_V, dtype=float)
    clean = denoised_force(record)
    w = prefilter_response(record.freq_Hz, record)

    def weighted(values: dict) -> np.ndarray:
        s = floor.spectrum(model.response(values, record) * w)
        return fd_weighted(v - model.simulate(values, record, clean), s)

    best = None
    for extra in starts or [{}]:
        res = fit(weighted, model.params(record, {**(start or {}), **extra}), max_nfev=max_nfev, ftol=ftol)
        if best is None or res.chi2 < best.chi2:
            best = res
    return _finish(model, record, v, floor, best)


def _finish(model, record, v, floor, res: FitResult) -> ModelFit:
    mv = model.simulate(res.values, record)
    g = model.response(res.values, record)
    s = floor.spectrum(g)
    r = v - mv
    floor_rms = floor.rms_V(g, record.n)
    vrms = float(np.sqrt(np.mean(v**2)))
    return ModelFit(model, res, mv, r, whiten(r, s), np.asarray(g), nrmse(r, v), floor_rms / vrms, floor_rms)


# =========================================================================== residual tests


def _flagged_groups(flags: np.ndarray, gap: int = 1) -> list[tuple[int, int]]:
    """[first, last] index of groups of flagged entries, merging gaps of up to ``gap``."""
    idx = np.flatnonzero(flags)
    if idx.size == 0:
        return []
    groups, a, b = [], idx[0], idx[0]
    for i in idx[1:]:
        if i - b <= gap + 1:
            b = i
        else:
            groups.append((int(a), int(b)))
            a = b = i
    groups.append((int(a), int(b)))
    return groups


@dataclass
class ResidualTests:
    """Whiteness, input correlation, spectrum and time-window tests of a whitened residual."""

    alpha: float
    n: int
    # autocorrelation
    acf_lags_s: np.ndarray = field(repr=False)
    acf: np.ndarray = field(repr=False)
    acf_threshold: float = 0.0
    ljung_box_Q: float = 0.0
    ljung_box_p: float = 1.0
    # cross-correlation with the force
    xcf_lags_s: np.ndarray = field(repr=False, default=None)
    xcf: np.ndarray = field(repr=False, default=None)
    xcf_threshold: float = 0.0
    xcf_p: float = 1.0
    # spectrum of the whitened residual (ratio to the floor)
    spec_freq_Hz: np.ndarray = field(repr=False, default=None)
    spec_ratio: np.ndarray = field(repr=False, default=None)
    spec_threshold: float = 0.0
    spec_segments: int = 0
    peaks: list = field(default_factory=list)
    # windows in time
    window_t0_s: np.ndarray = field(repr=False, default=None)
    window_ratio: np.ndarray = field(repr=False, default=None)
    window_threshold: float = 0.0
    windows: list = field(default_factory=list)
    acf_lags: list = field(default_factory=list)
    xcf_lags: list = field(default_factory=list)

    @property
    def band99(self) -> float:
        """The per-lag 99% band of a correlation of white noise, 2.576/sqrt(n) [-]."""
        return Z99 / np.sqrt(self.n)

    @property
    def white(self) -> bool:
        return self.ljung_box_p >= self.alpha

    @property
    def uncorrelated(self) -> bool:
        return self.xcf_p >= self.alpha

    @property
    def spectrum_ok(self) -> bool:
        return not self.peaks

    @property
    def windows_ok(self) -> bool:
        return not self.windows

    @property
    def passed(self) -> bool:
        return self.white and self.uncorrelated and self.spectrum_ok and self.windows_ok

    def summary(self) -> dict:
        return {
            "passed": self.passed,
            "test_significance": self.alpha,
            "whiteness": {
                "ljung_box_Q": self.ljung_box_Q,
                "lags": int(self.acf.size),
                "p": self.ljung_box_p,
                "white": self.white,
                "significant_lags_s": self.acf_lags,
            },
            "input_correlation": {
                "max_abs": float(np.max(np.abs(self.xcf))),
                "lag_of_max_s": float(self.xcf_lags_s[np.argmax(np.abs(self.xcf))]),
                "threshold": self.xcf_threshold,
                "band99": self.band99,
                "p": self.xcf_p,
                "uncorrelated": self.uncorrelated,
                "significant_lags_s": self.xcf_lags,
            },
            "spectrum": {
                "segments": self.spec_segments,
                "threshold_ratio": self.spec_threshold,
                "peaks": self.peaks,
            },
            "time_windows": {
                "window_s": float(self.window_t0_s[1] - self.window_t0_s[0])
                if self.window_t0_s.size > 1
                else float("nan"),
                "threshold_ratio": self.window_threshold,
                "flagged": self.windows,
            },
        }


def _lag_ranges(lags_s: np.ndarray, flags: np.ndarray, values: np.ndarray) -> list[dict]:
    out = []
    for a, b in _flagged_groups(flags, gap=2):
        i = a + int(np.argmax(np.abs(values[a : b + 1])))
        out.append(
            {
                "lags_s": [float(lags_s[a]), float(lags_s[b])],
                "peak_lag_s": float(lags_s[i]),
                "value": float(values[i]),
            }
        )
    out.sort(key=lambda d: -abs(d["value"]))
    return out[:5]


def residual_tests(
    whitened: np.ndarray,
    force_N: np.ndarray,
    dt_s: float,
    settings: DiagnosticsSettings,
    impulses: list[Impulse] | None = None,
    time_s: np.ndarray | None = None,
) -> ResidualTests:
    """The four tests of a residual whitened by the model's noise floor (unit variance if the model is right).

    - whiteness: Ljung-Box Q = n (n+2) sum r_k^2/(n-k), k = 1..M, against chi2(M);
    - input correlation: the normalised cross-correlation with the force at lags -M..M, whose largest
      magnitude times sqrt(n) is compared with the normal quantile at alpha / (2 (2M+1)) (Bonferroni);
    - spectrum: averaged Hann periodograms of non-overlapping segments, 2K times their ratio to the floor
      is chi2(2K); bins above the chi2 quantile at alpha / (number of bins) are peaks;
    - time windows: the sum of squares over each window of L samples is chi2(L); windows above the
      quantile at alpha / (number of windows) are flagged.
    Each test runs at ``settings.test_alpha``.
    """
    e = np.asarray(whitened, dtype=float)
    n = e.size
    alpha = settings.test_alpha
    m = int(np.clip(round(settings.max_lag_s / dt_s), 1, n // 4))
    ec = e - e.mean()
    full = correlate(ec, ec, mode="full", method="fft")[n - 1 :]
    acf = full[1 : m + 1] / full[0]
    q = float(n * (n + 2) * np.sum(acf**2 / (n - np.arange(1, m + 1))))
    lb_p = float(chi2_dist.sf(q, m))
    acf_thr = float(norm.isf(alpha / (2 * m)) / np.sqrt(n))
    lags = np.arange(1, m + 1) * dt_s

    u = np.asarray(force_N, dtype=float) - np.mean(force_N)
    xc = correlate(ec, u, mode="full", method="fft")[n - 1 - m : n + m] / (
        np.linalg.norm(ec) * np.linalg.norm(u)
    )
    xlags = np.arange(-m, m + 1) * dt_s
    nl = 2 * m + 1
    xc_thr = float(norm.isf(alpha / (2 * nl)) / np.sqrt(n))
    zmax = float(np.max(np.abs(xc)) * np.sqrt(n))
    xc_p = float(min(1.0, 2 * nl * norm.sf(zmax)))

    # spectrum
    seg = int(min(round(settings.spectrum_segment_s / dt_s), n))
    k = max(n // seg, 1)
    win = np.hanning(seg)
    segs = ec[: k * seg].reshape(k, seg)
    segs = segs - segs.mean(axis=1, keepdims=True)
    ratio = np.mean(np.abs(np.fft.rfft(segs * win, axis=1)) ** 2, axis=0) / np.sum(win**2)
    freq = np.fft.rfftfreq(seg, dt_s)
    test_bins = np.arange(1, ratio.size - (1 if seg % 2 == 0 else 0))
    spec_thr = float(chi2_dist.isf(alpha / max(test_bins.size, 1), 2 * k) / (2 * k))
    flags = np.zeros(ratio.size, dtype=bool)
    flags[test_bins] = ratio[test_bins] > spec_thr
    peaks = _spectral_peaks(ec, dt_s, freq, ratio, flags)

    # time windows
    lw = max(int(round(settings.window_s / dt_s)), 8)
    nw = n // lw
    t = np.arange(n) * dt_s if time_s is None else np.asarray(time_s)
    energy = np.sum(e[: nw * lw].reshape(nw, lw) ** 2, axis=1)
    w_thr = float(chi2_dist.isf(alpha / max(nw, 1), lw) / lw)
    w_ratio = energy / lw
    t0 = t[: nw * lw : lw]
    windows = []
    for a, b in _flagged_groups(w_ratio > w_thr, gap=0):
        ts, te = float(t0[a]), float(t[min((b + 1) * lw, n) - 1])
        d = {"time_s": [ts, te], "max_ratio": float(np.max(w_ratio[a : b + 1]))}
        if impulses:
            mid = int(((a + b + 1) * lw) // 2)
            for j, imp in enumerate(impulses):
                if imp.start <= mid < imp.stop:
                    d["impulse"] = j + 1
                    d["from_force_peak_s"] = [
                        ts - float(t[imp.force_peak_index]),
                        te - float(t[imp.force_peak_index]),
                    ]
        windows.append(d)
    windows.sort(key=lambda d: -d["max_ratio"])

    return ResidualTests(
        alpha=alpha,
        n=n,
        acf_lags_s=lags,
        acf=acf,
        acf_threshold=acf_thr,
        ljung_box_Q=q,
        ljung_box_p=lb_p,
        xcf_lags_s=xlags,
        xcf=xc,
        xcf_threshold=xc_thr,
        xcf_p=xc_p,
        spec_freq_Hz=freq,
        spec_ratio=ratio,
        spec_threshold=spec_thr,
        spec_segments=k,
        peaks=peaks,
        window_t0_s=t0,
        window_ratio=w_ratio,
        window_threshold=w_thr,
        windows=windows,
        acf_lags=_lag_ranges(lags, np.abs(acf) > acf_thr, acf),
        xcf_lags=_lag_ranges(xlags, np.abs(xc) > xc_thr, xc),
    )


def _spectral_peaks(
    e: np.ndarray, dt_s: float, freq: np.ndarray, ratio: np.ndarray, flags: np.ndarray
) -> list[dict]:
    """Groups of flagged bins, each with its peak frequency refined on the whole record's periodogram."""
    if not flags.any():
        return []
    df = freq[1] - freq[0]
    nfft = 4 * int(2 ** np.ceil(np.log2(e.size)))
    p = np.abs(np.fft.rfft(e * np.hanning(e.size), nfft)) ** 2
    fz = np.fft.rfftfreq(nfft, dt_s)
    out = []
    for a, b in _flagged_groups(flags, gap=1):
        sel = (fz >= freq[a] - df) & (fz <= freq[b] + df)
        f_peak = float(fz[sel][np.argmax(p[sel])]) if sel.any() else float(freq[a])
        width = float(freq[b] - freq[a] + df)
        out.append(
            {
                "frequency_Hz": f_peak,
                "band_Hz": [float(freq[a] - df / 2), float(freq[b] + df / 2)],
                "max_ratio": float(np.max(ratio[a : b + 1])),
                "excess_dB": float(10 * np.log10(np.max(ratio[a : b + 1]))),
                "kind": "narrowband" if width <= max(3 * df, 0.25 * f_peak) else "broadband",
                "excess_power": float(np.sum(ratio[a : b + 1] - 1) * df),
            }
        )
    out.sort(key=lambda d: -d["excess_power"])
    return out


def peak_where(pk: dict) -> str:
    """Where a spectral peak of the residual lies: its frequency, or its band and peak [Hz]."""
    f = pk["frequency_Hz"]
    if pk["kind"] == "narrowband":
        return f"{f:.2f} Hz"
    return f"{pk['band_Hz'][0]:.2f}-{pk['band_Hz'][1]:.2f} Hz (peak {f:.2f} Hz)"


def findings(tests: ResidualTests) -> list[dict]:
    """What structure remains and where, one dict per failed test (empty when all pass)."""
    out = []
    if not tests.spectrum_ok:
        for pk in tests.peaks[:5]:
            f = pk["frequency_Hz"]
            where = peak_where(pk)
            out.append(
                {
                    "test": "spectrum",
                    "kind": pk["kind"],
                    "frequency_Hz": f,
                    "band_Hz": pk["band_Hz"],
                    "excess_dB": pk["excess_dB"],
                    "where": f"residual {pk['kind']} {pk['excess_dB']:.1f} dB above the noise floor at {where}",
                }
            )
    if not tests.white:
        lag = tests.acf_lags[0] if tests.acf_lags else None
        msg = f"residual not white (Ljung-Box p = {tests.ljung_box_p:.2g})"
        if lag:
            msg += f"; strongest autocorrelation {lag['value']:+.3f} at lag {lag['peak_lag_s'] * 1e3:.1f} ms"
        out.append(
            {
                "test": "whiteness",
                "p": tests.ljung_box_p,
                "lag_s": lag["peak_lag_s"] if lag else None,
                "where": msg,
            }
        )
    if not tests.uncorrelated:
        i = int(np.argmax(np.abs(tests.xcf)))
        lag_s = float(tests.xcf_lags_s[i])
        out.append(
            {
                "test": "input_correlation",
                "p": tests.xcf_p,
                "lag_s": lag_s,
                "value": float(tests.xcf[i]),
                "where": f"residual correlated with the force: {tests.xcf[i]:+.3f} at lag "
                f"{lag_s * 1e3:+.1f} ms (residual after force for positive lags)",
            }
        )
    if not tests.windows_ok:
        for w in tests.windows[:5]:
            ts, te = w["time_s"]
            msg = f"residual energy {w['max_ratio']:.1f}x the floor at t = {ts:.2f}-{te:.2f} s"
            if "impulse" in w:
                a, b = w["from_force_peak_s"]
                msg += f" (impulse {w['impulse']}, {a:+.2f} to {b:+.2f} s from its force peak)"
            out.append(
                {
                    "test": "time_window",
                    "time_s": w["time_s"],
                    "impulse": w.get("impulse"),
                    "max_ratio": w["max_ratio"],
                    "where": msg,
                }
            )
    return out


def per_impulse(
    fit_: ModelFit, voltage_V: np.ndarray, impulses: list[Impulse], time_s: np.ndarray
) -> list[dict]:
    """NRMSE, rms residual and whitened mean square within each impulse's window."""
    out = []
    for j, imp in enumerate(impulses):
        sl = slice(imp.start, imp.stop)
        r = fit_.residual_V[sl]
        out.append(
            {
                "impulse": j + 1,
                "time_force_peak_s": float(time_s[imp.force_peak_index]),
                "force_peak_N": imp.force_peak_N,
                "nrmse": nrmse(r, voltage_V[sl]),
                "residual_rms_V": float(np.sqrt(np.mean(r**2))),
                "excess_ratio": float(np.mean(fit_.whitened[sl] ** 2)),
            }
        )
    return out


# =========================================================================== ranking and selection


@dataclass
class Candidate:
    """An effect added to the current model and refitted."""

    effect: Effect
    fit: ModelFit
    delta_bic: float
    excess_explained: float
    tests: ResidualTests | None = None
    param_names: tuple[str, ...] = ()

    def summary(self, current: ModelFit) -> dict:
        names = self.param_names
        v = self.fit.values
        return {
            "effect": self.effect.name,
            "title": self.effect.title,
            "delta_bic": self.delta_bic,
            "delta_chi2": current.chi2 - self.fit.chi2,
            "nrmse": self.fit.nrmse,
            "nrmse_before": current.nrmse,
            "noise_floor_nrmse": self.fit.floor_nrmse,
            "excess_explained": self.excess_explained,
            "whiteness_p": self.tests.ljung_box_p if self.tests else None,
            "white": self.tests.white if self.tests else None,
            "params": {k: v[k] for k in v if k in names},
            "stderr": {k: self.fit.result.stderr.get(k) for k in names},
            "ci95": {k: self.fit.result.ci95.get(k) for k in names},
            "resistance_ohm": v["resistance_ohm"],
            "summary": self.effect.summary({k: v[k] for k in v if k in names}),
        }


def add_effect(
    current: ModelFit,
    effect: Effect,
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    settings: DiagnosticsSettings,
) -> ModelFit:
    """Fit current model + effect, warm-started from the current values and the effect's starts."""
    model = current.model.with_effect(effect)
    ctx = StartContext(record, voltage_V, current.model_V, current.values)
    return fit_model(
        model,
        record,
        voltage_V,
        floor,
        start=dict(current.values),
        starts=effect.starts(ctx),
        max_nfev=settings.max_nfev,
        ftol=settings.ftol,
    )


def rank(
    current: ModelFit,
    effects: list[Effect],
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    settings: DiagnosticsSettings,
    progress: Callable[[str], None] | None = None,
) -> list[Candidate]:
    """Every effect added to the current model in turn, best evidence (largest BIC drop) first."""
    out = []
    for e in effects:
        if progress:
            progress(f"{current.model.label} + {e.name}")
        f = add_effect(current, e, record, voltage_V, floor, settings)
        drop = current.chi2 - f.chi2
        explained = float(np.clip(drop / max(current.excess, drop, 1e-12), 0.0, 1.0))
        tests = residual_tests(f.whitened, record.force_N, record.dt_s, settings)
        out.append(
            Candidate(e, f, current.bic - f.bic, explained, tests, tuple(p.name for p in e.params(record)))
        )
    out.sort(key=lambda c: -c.delta_bic)
    return out


def accepted(c: Candidate, settings: DiagnosticsSettings) -> bool:
    """The evidence rule, the same for every effect."""
    return c.delta_bic > settings.min_delta_bic and c.excess_explained >= settings.min_share


# =========================================================================== the diagnosis


@dataclass
class Diagnosis:
    """Everything the report and the figures need."""

    record: Record
    voltage_V: np.ndarray
    impulses: list
    floor: NoiseFloor
    settings: DiagnosticsSettings
    baseline: ModelFit
    configured: ModelFit
    ranking: list[Candidate]
    steps: list[dict]
    fits: list[ModelFit]
    selected: list[str]
    final: ModelFit
    tests: dict[str, ResidualTests]
    verdict: str
    unexplained: list[dict]
    dropped: list[dict] = field(default_factory=list)

    def to_dict(self) -> dict:
        rec = self.record
        out = {
            "n_samples": rec.n,
            "sample_rate_Hz": rec.sample_rate_Hz,
            "duration_s": float(rec.time_s[-1] - rec.time_s[0]),
            "voltage_rms_V": float(np.sqrt(np.mean(self.voltage_V**2))),
            "n_impulses": len(self.impulses),
            "noise_floor": self.floor.report(),
            "noise_floor_nrmse": self.final.floor_nrmse,
            "baseline": {**self.baseline.summary(), "tests": self.tests["baseline"].summary()},
            "configured": {**self.configured.summary(), "tests": self.tests["configured"].summary()},
            "ranking": [c.summary(self.configured) for c in self.ranking],
            "winner": None,
            "selected": self.selected,
            "steps": self.steps,
            "dropped_steps": self.dropped,
            "final": {**self.final.summary(), "tests": self.tests["final"].summary()},
            "verdict": self.verdict,
            "unexplained": self.unexplained,
            "per_impulse": {
                "baseline": per_impulse(self.baseline, self.voltage_V, self.impulses, rec.time_s),
                "final": per_impulse(self.final, self.voltage_V, self.impulses, rec.time_s),
            },
            "settings": self.settings.__dict__,
            "catalogue": {name: {"title": e.title, "physics": e.physics} for name, e in CATALOGUE.items()},
        }
        if self.ranking and self.selected and self.selected[0] == self.ranking[0].effect.name:
            best = self.ranking[0]
            out["winner"] = {**best.summary(self.configured), "physics": best.effect.physics}
        return out


def diagnose(
    record: Record,
    voltage_V: np.ndarray,
    circuit,
    configured_effects: list[str] | tuple = (),
    settings: DiagnosticsSettings | None = None,
    impulses: list[Impulse] | None = None,
    initial_resistance_ohm: float | None = None,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """The whole diagnosis of one record (see the module docstring).

    Parameters
    ----------
    record : Record
        Time axis and recorded force.
    voltage_V : ndarray
        Measured voltage [V].
    circuit : SensorCircuit
        Nominal circuit (its R is the baseline fit's start unless ``initial_resistance_ohm``).
    configured_effects : list of str
        Effects switched on in the config (``model.effects``).
    """
    settings = settings or DiagnosticsSettings()
    v = np.asarray(voltage_V, dtype=float)
    impulses = impulses or []
    r0 = initial_resistance_ohm or circuit.resistance_ohm
    floor = estimate_noise_floor(record, v, settings, tau_s=circuit.with_resistance(r0).tau_s)
    note = progress or (lambda _msg: None)

    note("baseline")
    base_model = ForwardModel(circuit)
    baseline = fit_model(
        base_model,
        record,
        v,
        floor,
        start={"resistance_ohm": r0},
        starts=[{}, {"resistance_ohm": 10 * r0}],
        max_nfev=settings.max_nfev,
        ftol=settings.ftol,
    )
    current = baseline
    conf_model = ForwardModel.build(circuit, list(configured_effects))
    for e in conf_model.effects:
        note(f"configured: + {e.name}")
        current = add_effect(current, e, record, v, floor, settings)
    configured = current
    tests = {
        "baseline": residual_tests(
            baseline.whitened, record.force_N, record.dt_s, settings, impulses, record.time_s
        )
    }
    tests["configured"] = (
        tests["baseline"]
        if configured is baseline
        else residual_tests(
            configured.whitened, record.force_N, record.dt_s, settings, impulses, record.time_s
        )
    )

    def step_entry(f: ModelFit, added: str | None, c: Candidate | None) -> dict:
        return {
            "effects": f.model.names,
            "added": added,
            "nrmse": f.nrmse,
            "noise_floor_nrmse": f.floor_nrmse,
            "bic": f.bic,
            "chi2": f.chi2,
            "n_free": f.n_free,
            "delta_bic": c.delta_bic if c else None,
            "excess_explained": c.excess_explained if c else None,
            "params": f.values,
        }

    steps = [step_entry(configured, None, None)]
    fits = [configured]
    added: list[Candidate] = []
    ranking: list[Candidate] = []
    for step in range(settings.max_steps):
        remaining = [e for e in CATALOGUE.values() if e not in current.model.effects]
        if not remaining:
            break
        cands = rank(current, remaining, record, v, floor, settings, note)
        if step == 0:
            ranking = cands
        best = cands[0]
        if not accepted(best, settings):
            break
        current = best.fit
        added.append(best)
        steps.append(step_entry(current, best.effect.name, best))
        fits.append(current)

    def final_tests(f: ModelFit) -> ResidualTests:
        return residual_tests(f.whitened, record.force_N, record.dt_s, settings, impulses, record.time_s)

    tests["final"] = final_tests(fits[-1])
    dropped: list[dict] = []
    if not tests["final"].passed:
        weak = [i for i, c in enumerate(added) if c.excess_explained < settings.min_share_if_unexplained]
        if weak:
            cut = weak[0]
            dropped = [
                {
                    **steps[i + 1],
                    "reason": f"structure remains and this addition explained "
                    f"{c.excess_explained:.0%} (< {settings.min_share_if_unexplained:.0%}) of the misfit "
                    "left at its step: it may stand in for an effect outside the catalogue",
                }
                for i, c in enumerate(added)
                if i >= cut
            ]
            added, steps, fits = added[:cut], steps[: cut + 1], fits[: cut + 1]
            tests["final"] = final_tests(fits[-1])
    final = fits[-1]
    found = findings(tests["final"])
    return Diagnosis(
        record,
        v,
        impulses,
        floor,
        settings,
        baseline,
        configured,
        ranking,
        steps,
        fits,
        [c.effect.name for c in added],
        final,
        tests,
        "explained" if not found else "unexplained",
        found,
        dropped,
    )


# =========================================================================== arrays for figures


def residual_psd(x: np.ndarray, dt_s: float, segment_s: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided PSD [unit^2/Hz] from non-overlapping Hann segments (the segmentation of the spectrum test)."""
    n = x.size
    seg = int(min(round(segment_s / dt_s), n))
    k = max(n // seg, 1)
    win = np.hanning(seg)
    segs = x[: k * seg].reshape(k, seg)
    segs = segs - segs.mean(axis=1, keepdims=True)
    p = np.mean(np.abs(np.fft.rfft(segs * win, axis=1)) ** 2, axis=0) / np.sum(win**2)
    return np.fft.rfftfreq(seg, dt_s), 2 * p * dt_s


def arrays(d: Diagnosis) -> dict[str, np.ndarray]:
    """The arrays the figures need (saved as diagnosis.npz next to diagnosis.json)."""
    rec, st = d.record, d.settings
    out = {
        "time_s": rec.time_s,
        "force_N": rec.force_N,
        "voltage_V": d.voltage_V,
        "quiet_mask": d.floor.quiet_mask.astype(np.int8),
        "impulse_start": np.array([i.start for i in d.impulses], dtype=int),
        "impulse_stop": np.array([i.stop for i in d.impulses], dtype=int),
        "impulse_peak": np.array([i.force_peak_index for i in d.impulses], dtype=int),
    }
    for key, f in (("baseline", d.baseline), ("configured", d.configured), ("final", d.final)):
        t = d.tests[key]
        freq, psd = residual_psd(f.residual_V, rec.dt_s, st.spectrum_segment_s)
        s = d.floor.spectrum(f.response)
        floor_psd = 2 * np.interp(freq, rec.freq_Hz, np.broadcast_to(s, rec.freq_Hz.shape)) * rec.dt_s
        out.update(
            {
                f"{key}_model_V": f.model_V,
                f"{key}_residual_V": f.residual_V,
                f"{key}_whitened": f.whitened,
                f"{key}_psd_freq_Hz": freq,
                f"{key}_psd_V2_per_Hz": psd,
                f"{key}_floor_psd_V2_per_Hz": floor_psd,
                f"{key}_threshold_psd_V2_per_Hz": floor_psd * t.spec_threshold,
                f"{key}_acf_lags_s": t.acf_lags_s,
                f"{key}_acf": t.acf,
                f"{key}_xcf_lags_s": t.xcf_lags_s,
                f"{key}_xcf": t.xcf,
                f"{key}_window_t0_s": t.window_t0_s,
                f"{key}_window_ratio": t.window_ratio,
            }
        )
        out[f"{key}_acf_threshold"] = np.array(t.acf_threshold)
        out[f"{key}_xcf_threshold"] = np.array(t.xcf_threshold)
        out[f"{key}_window_threshold"] = np.array(t.window_threshold)
    out["band99"] = np.array(Z99 / np.sqrt(rec.n))
    return out
