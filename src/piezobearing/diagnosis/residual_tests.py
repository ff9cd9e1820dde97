"""Tests of a residual whitened by its model's noise floor: unit-variance white noise if the model is right.

Four tests, each at a quarter of the family-wise significance (Bonferroni),
so that a residual of pure noise fails any of them with that probability:

- whiteness: Ljung-Box on the autocorrelation up to ``max_lag_s``;
- input correlation: the largest cross-correlation with the measured input
  (a model that mis-shapes the input's path leaves a residual correlated
  with it); skipped when the subject has no measured input;
- spectrum: averaged periodogram against the chi-square quantile, flagged
  bins grouped into narrowband and broadband peaks;
- time windows: residual energy in windows of ``window_s`` against the
  chi-square quantile, named by the record's segments (impulses, passages).

These are the tests of the whitened time-domain residual every subject is
judged in; a subject adds its own representations (per passage, synchronous
average, envelope spectrum) through
:class:`~piezobearing.diagnosis.subject.Representation`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import correlate
from scipy.stats import chi2 as chi2_dist
from scipy.stats import norm

from .record import Segments
from .settings import DiagnosticsSettings

#: The 99% two-sided band of a correlation, times 1/sqrt(n).
Z99 = float(norm.isf(0.005))


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
    """Whiteness, input correlation, spectrum and time-window tests of a whitened residual (see the module)."""

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
                "max_abs": float(np.max(np.abs(self.xcf))) if self.xcf.size else None,
                "lag_of_max_s": float(self.xcf_lags_s[np.argmax(np.abs(self.xcf))])
                if self.xcf.size
                else None,
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
    input_: np.ndarray | None,
    dt_s: float,
    settings: DiagnosticsSettings,
    segments: Segments | None = None,
    time_s: np.ndarray | None = None,
    filled: np.ndarray | None = None,
) -> ResidualTests:
    """The four tests of a residual whitened by the model's noise floor (unit variance if the model is right).

    - whiteness: Ljung-Box Q = n (n+2) sum r_k^2/(n-k), k = 1..M, against chi2(M);
    - input correlation: the normalised cross-correlation with the measured input at lags -M..M, whose
      largest magnitude times sqrt(n) is compared with the normal quantile at alpha / (2 (2M+1))
      (Bonferroni); without an input (``input_`` None) it passes with no lags;
    - spectrum: averaged Hann periodograms of non-overlapping segments, 2K times their ratio to the floor
      is chi2(2K); bins above the chi2 quantile at alpha / (number of bins) are peaks;
    - time windows: the sum of squares over each window of L samples is chi2(L); windows above the
      quantile at alpha / (number of windows) are flagged, and named by the ``segments`` they fall in.
    Each test runs at ``settings.test_alpha``. Samples marked in ``filled`` (not measured:
    :attr:`Record.left_out <piezobearing.diagnosis.record.Record>`) are left out: set to zero, the
    correlations and Ljung-Box count only the measured samples, each spectrum segment is divided by
    the share of its window's energy on measured samples, and each time window is judged on its
    measured samples alone (a window with none is not judged: ratio NaN).
    """
    keep = None if filled is None or not np.any(filled) else ~np.asarray(filled, dtype=bool)
    e = np.asarray(whitened, dtype=float)
    if keep is not None:
        e = np.where(keep, e, 0.0)
    n_all = e.size
    n = n_all if keep is None else int(np.count_nonzero(keep))
    alpha = settings.test_alpha
    m = int(np.clip(round(settings.max_lag_s / dt_s), 1, n // 4))
    ec = e - (e.mean() if keep is None else np.where(keep, np.sum(e) / n, 0.0))
    full = correlate(ec, ec, mode="full", method="fft")[n_all - 1 :]
    acf = full[1 : m + 1] / full[0]
    q = float(n * (n + 2) * np.sum(acf**2 / (n - np.arange(1, m + 1))))
    lb_p = float(chi2_dist.sf(q, m))
    acf_thr = float(norm.isf(alpha / (2 * m)) / np.sqrt(n))
    lags = np.arange(1, m + 1) * dt_s

    xlags, xc, xc_thr, xc_p = _input_correlation(ec, input_, m, dt_s, alpha, keep)

    freq, ratio, k, spec_thr, flags = _spectrum_test(ec, dt_s, settings.spectrum_segment_s, alpha, keep)
    peaks = _spectral_peaks(ec, dt_s, freq, ratio, flags)
    t0, w_ratio, w_thr, windows = _window_test(e, dt_s, settings.window_s, alpha, segments, time_s, keep)

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


def _input_correlation(
    ec: np.ndarray, input_: np.ndarray | None, m: int, dt_s: float, alpha: float, keep: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Lags [s], normalised cross-correlation of the residual with the input at lags -m..m, the
    Bonferroni threshold of one lag and the family's p-value (no input: empty lags, p = 1); ``keep``
    marks the measured samples (the others are zero in ``ec`` and left out of the input's too)."""
    n_all = ec.size
    n = n_all if keep is None else int(np.count_nonzero(keep))
    xlags = np.arange(-m, m + 1) * dt_s
    nl = 2 * m + 1
    xc_thr = float(norm.isf(alpha / (2 * nl)) / np.sqrt(n))
    if input_ is None:
        return np.zeros(0), np.zeros(0), xc_thr, 1.0
    u = np.asarray(input_, dtype=float)
    u = u - np.mean(u) if keep is None else np.where(keep, u - np.mean(u[keep]), 0.0)
    xc = correlate(ec, u, mode="full", method="fft")[n_all - 1 - m : n_all + m] / (
        np.linalg.norm(ec) * np.linalg.norm(u)
    )
    zmax = float(np.max(np.abs(xc)) * np.sqrt(n))
    return xlags, xc, xc_thr, float(min(1.0, 2 * nl * norm.sf(zmax)))


def _spectrum_test(
    ec: np.ndarray, dt_s: float, segment_s: float, alpha: float, keep: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, int, float, np.ndarray]:
    """Frequencies [Hz], averaged periodogram of the whitened residual (its ratio to the floor), number
    of segments, threshold ratio and the flags of the bins above it (``keep``: measured samples; each
    segment's periodogram divided by the share of the window's energy on them)."""
    n = ec.size
    seg = int(min(round(segment_s / dt_s), n))
    k = max(n // seg, 1)
    win = np.hanning(seg)
    segs = ec[: k * seg].reshape(k, seg)
    if keep is None:
        segs = segs - segs.mean(axis=1, keepdims=True)
        share = np.ones((k, 1))
    else:
        kp = keep[: k * seg].reshape(k, seg)
        mean = np.sum(segs, axis=1, keepdims=True) / np.maximum(kp.sum(axis=1, keepdims=True), 1)
        segs = np.where(kp, segs - mean, 0.0)
        share = np.maximum(np.sum(kp * win**2, axis=1, keepdims=True) / np.sum(win**2), 1e-3)
    ratio = np.mean(np.abs(np.fft.rfft(segs * win, axis=1)) ** 2 / share, axis=0) / np.sum(win**2)
    freq = np.fft.rfftfreq(seg, dt_s)
    test_bins = np.arange(1, ratio.size - (1 if seg % 2 == 0 else 0))
    spec_thr = float(chi2_dist.isf(alpha / max(test_bins.size, 1), 2 * k) / (2 * k))
    flags = np.zeros(ratio.size, dtype=bool)
    flags[test_bins] = ratio[test_bins] > spec_thr
    return freq, ratio, k, spec_thr, flags


def _window_test(
    e: np.ndarray,
    dt_s: float,
    window_s: float,
    alpha: float,
    segments: Segments | None,
    time_s: np.ndarray | None,
    keep: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, float, list[dict]]:
    """Window start times [s], mean square of the whitened residual per window, threshold, and the
    flagged groups of windows (named by the segment holding their middle), largest first. With
    ``keep`` (measured samples) a window's mean square and threshold are those of its measured
    samples; a window without any has ratio NaN and is not judged."""
    n = e.size
    lw = max(int(round(window_s / dt_s)), 8)
    nw = n // lw
    t = np.arange(n) * dt_s if time_s is None else np.asarray(time_s)
    energy = np.sum(e[: nw * lw].reshape(nw, lw) ** 2, axis=1)
    w_thr = float(chi2_dist.isf(alpha / max(nw, 1), lw) / lw)
    if keep is None:
        w_ratio = energy / lw
        flags = w_ratio > w_thr
    else:
        lk = np.sum(keep[: nw * lw].reshape(nw, lw), axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            w_ratio = np.where(lk > 0, energy / np.maximum(lk, 1), np.nan)
        thr = chi2_dist.isf(alpha / max(nw, 1), np.maximum(lk, 1)) / np.maximum(lk, 1)
        flags = (lk > 0) & (np.nan_to_num(w_ratio) > thr)
    t0 = t[: nw * lw : lw]
    windows = []
    for a, b in _flagged_groups(flags, gap=0):
        ts, te = float(t0[a]), float(t[min((b + 1) * lw, n) - 1])
        d = {"time_s": [ts, te], "max_ratio": float(np.nanmax(w_ratio[a : b + 1]))}
        if segments is not None and len(segments):
            mid = int(((a + b + 1) * lw) // 2)
            for j in range(len(segments)):
                if segments.start[j] <= mid < segments.stop[j]:
                    anchor = float(t[segments.anchor_index[j]])
                    d[segments.name] = j + 1
                    d[f"from_{segments.anchor}_s"] = [ts - anchor, te - anchor]
        windows.append(d)
    windows.sort(key=lambda d: -d["max_ratio"])
    return t0, w_ratio, w_thr, windows


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
