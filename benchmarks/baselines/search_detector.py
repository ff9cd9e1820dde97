"""The benchmarks' baseline: the search detector, which the envelope detector replaced.

``benchmarks/bench_detect_record.py`` and ``benchmarks/bench_detector.py``
time it beside the package's detectors for their ratios; the package does
not import it (its detectors are :mod:`piezobearing.signals.detectors`).

The paper's test (:func:`piezobearing.signals.detection.fault_indicator`) reads the one envelope
bin at the kinematic BPFO. A cage that slips 1.5 % moves the line by more
than a bin and the test loses it. Here every line of every fault type
(:mod:`piezobearing.signals.fault_bands`) is searched over the bins its band covers for slip in
[0, s_max], and the threshold is raised for that search.

Statistic. A single-sided envelope spectrum A_j [V] of noise alone has, bin
by bin, A_j^2 = sigma^2 X_j with X_j ~ Exp(1) independent (circular complex
Gaussian bins, as in :func:`piezobearing.signals.detection.indicator_threshold`). The local
floor of harmonic k is the mean A^2 of M_f bins around k x carrier (all
windows of all analysed types and ``guard_bins`` around them left out):
sigma^2 Y_k with Y_k ~ Gamma(M_f, 1/M_f). Line l of harmonic k, searched
over M_l bins, gives

.. math::  R_l = \\max_{j \\in W_l} A_j^2 / \\overline{A^2}_{floor,k} = Z_l / Y_k,
           \\qquad Z_l = \\max_{j \\le M_l} X_j .

One window alone: P(R_l > t) = 1 - E_Y[(1 - e^{-tY})^{M_l}]. Without the
floor's own scatter this is 1 - (1 - p)^{M} for a per-bin probability p
(:func:`per_bin_probability`); :func:`window_threshold` sets the level so
that the *window's* false-alarm probability is the configured one.

Indicator of a fault type: I = sum_l R_l over its lines. Its distribution
under noise alone is computed, not bounded: the density of Z_l is
M e^{-z}(1 - e^{-z})^{M-1}; the lines of one harmonic share Y_k, so their sum
S_k = sum Z_l is a convolution and G_k = S_k / Y_k follows by Gauss-Legendre
quadrature over Y_k; the harmonics (disjoint floors) are convolved again.
The threshold is the (1 - alpha) quantile of that distribution
(:class:`NullDistribution`).

False alarms of the decision. The detector tests ``n`` fault types; each at
alpha = pfa / n (Bonferroni), so the probability that noise alone is called
any fault is at most the configured ``pfa``.

Classification (outer race / inner race / rolling element / none). No type
detected: ``none``. One: that type. Several (their lines can coincide: in the
N 305, 2 BSF = 69.5 Hz lies 1.3 Hz below BPFO = 70.8 Hz, inside the slip
band): each detected type's *own* lines, those whose windows overlap no
window of another detected type, are tested alone at the same alpha. The
type whose own lines are significant with the largest margin I/threshold
wins; if none is, the type with the largest margin of its full indicator
(for an outer-race fault the roller type's extra FTF sidebands hold only
noise, so the outer race, with fewer lines and a lower threshold, wins).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.optimize import brentq
from scipy.signal import fftconvolve
from scipy.special import roots_legendre
from scipy.stats import gamma as gamma_distribution

from piezobearing.signals import detection, envelope
from piezobearing.signals.fault_bands import FaultLine, fault_bands, fault_lines, window_bins

#: The fault types the classifier chooses among (plus "none").
CLASSIFIED_TYPES = ("outer_race", "inner_race", "rolling_element")
#: What fault_indicator.json's detector entries mean.
DEFINITION = (
    "fault_types: per fault type the search detector on the noisy record's whole Hann-windowed envelope "
    "spectrum in the envelope's band: each line (k x carrier + m x sideband spacing) searched over the bins its "
    "frequency covers for cage slip in [0, signals.detector.slip_max]; ratio = largest A^2 there over the mean "
    "A^2 of the harmonic's floor (within floor_halfwidth x carrier, all windows and floor_guard_bins around them "
    "left out); indicator = sum of the ratios; threshold = (1 - pfa/n_types) quantile of its distribution under "
    "noise alone (max of M exponential bins over a Gamma floor, computed); detected = indicator > threshold; "
    "margin = indicator / threshold; own_lines: the same test on the lines no other detected type shares; "
    "fault_type: none if no type is detected, else the detected type whose own lines are significant with the "
    "largest margin, else the largest margin"
)
#: Envelope windows and the variance inflation of a mean of their bins' powers.
WINDOWS = envelope.WINDOWS
#: Quadrature nodes over the floor's Gamma distribution.
_N_QUAD = 64
#: Grid points of the null densities.
_N_GRID = 2**15


# --------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class DetectorSettings:
    """The search detector.

    Parameters
    ----------
    n_harmonics : int
        Harmonics k = 1..K of each carrier [-].
    n_sidebands : int
        Sidebands m = -S..S of inner-race (shaft rate) and rolling-element (FTF) lines [-].
    slip_max : float
        Largest cage slip searched [-]; the bands cover slip in [0, slip_max].
    floor_halfwidth : float
        Half-width of a harmonic's noise-floor region, as a fraction of the carrier [-].
    guard_bins : int
        Bins next to every window left out of the floors [-].
    false_alarm_probability : float
        Probability that noise alone is called any fault [-].
    fault_types : tuple of str
        The fault types tested.
    """

    n_harmonics: int = 3
    n_sidebands: int = 1
    slip_max: float = 0.03
    floor_halfwidth: float = 0.5
    guard_bins: int = 2
    false_alarm_probability: float = 1e-3
    fault_types: tuple[str, ...] = CLASSIFIED_TYPES
    window: str = "hann"

    def __post_init__(self):
        if self.window not in WINDOWS:
            raise ValueError(f"signals.detector.window: unknown window '{self.window}'; use hann or rectangular")

    @property
    def alpha_per_type(self) -> float:
        """False-alarm probability of each type's test, pfa / n_types (Bonferroni) [-]."""
        return self.false_alarm_probability / len(self.fault_types)

    @classmethod
    def from_config(cls, sig: dict) -> "DetectorSettings":
        d = sig["detector"]
        return cls(
            n_harmonics=d["n_harmonics"],
            n_sidebands=d["n_sidebands"],
            slip_max=d["slip_max"],
            window=d["window"],
            floor_halfwidth=sig["floor_halfwidth"],
            guard_bins=sig["floor_guard_bins"],
            false_alarm_probability=sig["false_alarm_probability"],
        )


# --------------------------------------------------------------------------- null distribution


def per_bin_probability(window_probability: float, n_bins: int) -> float:
    """Per-bin exceedance p with 1 - (1 - p)^M = the window's probability (independent bins) [-]."""
    return float(-np.expm1(np.log1p(-window_probability) / n_bins))


def _gamma_nodes(n_floor_bins: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of E[h(Y)] for Y ~ Gamma(M_f, 1/M_f).

    Gauss-Legendre in probability, Y = F^{-1}(u): stable for any M_f (the
    generalised Laguerre rule overflows beyond M_f ~ 150), and its nodes
    crowd towards u = 0, the small floors that make the tail of R.
    """

    u, w = roots_legendre(_N_QUAD)
    return gamma_distribution.ppf(0.5 * (u + 1.0), n_floor_bins, scale=1.0 / n_floor_bins), 0.5 * w


def window_survival(t: np.ndarray, n_bins: int, n_floor_bins: int) -> np.ndarray:
    """P(max of M bin ratios > t) under noise alone, floor of M_f bins [-]."""
    y, w = _gamma_nodes(n_floor_bins)
    t = np.asarray(t, dtype=float)[..., None]
    return 1.0 - np.sum(w * (-np.expm1(-t * y)) ** n_bins, axis=-1)


def window_threshold(probability: float, n_bins: int, n_floor_bins: int) -> float:
    """Level t of R = max_j A_j^2 / floor with P(R > t) = ``probability`` under noise alone [-]."""

    if not 0 < probability < 1:
        raise ValueError("false-alarm probability must lie in (0, 1)")
    hi = 1.0
    while window_survival(hi, n_bins, n_floor_bins) > probability:
        hi *= 2.0
    return float(brentq(lambda t: float(window_survival(t, n_bins, n_floor_bins)) - probability, 0.0, hi,
                        xtol=1e-10, rtol=1e-12))


@dataclass(frozen=True)
class NullDistribution:
    """Distribution of I = sum_l R_l under noise alone, on a grid.

    Attributes
    ----------
    x : ndarray
        Grid of I [-].
    survival : ndarray
        P(I > x) [-].
    """

    x: np.ndarray
    survival: np.ndarray

    def threshold(self, alpha: float) -> float:
        """The (1 - alpha) quantile [-]."""
        s = self.survival
        if alpha <= s[-1]:
            raise ValueError(f"false-alarm probability {alpha:g} below the grid's reach {s[-1]:.3g}")
        i = int(np.flatnonzero(s > alpha)[-1])
        return float(self.x[i] + (s[i] - alpha) * (self.x[i + 1] - self.x[i]) / (s[i] - s[i + 1]))

    def p_value(self, value: float) -> float:
        """P(I > value) under noise alone (0 beyond the grid) [-]."""
        return float(np.interp(value, self.x, self.survival, right=0.0))


@lru_cache(maxsize=256)
def null_distribution(groups: tuple[tuple[tuple[int, ...], float], ...]) -> NullDistribution:
    """Null distribution of the indicator of lines grouped by shared floor.

    Parameters
    ----------
    groups : tuple
        Per harmonic: (window sizes M_l of its lines, floor bins M_f).
    """

    n_lines = sum(len(ms) for ms, _ in groups)
    xmax = 40.0 + 30.0 * n_lines
    x = np.linspace(0.0, xmax, _N_GRID)
    h = x[1]
    total = None
    for ms, mf in groups:
        s = None
        for m in ms:
            p = m * np.exp(-x) * (-np.expm1(-x)) ** (m - 1)
            s = p if s is None else fftconvolve(s, p)[: x.size] * h
        y, w = _gamma_nodes(mf)
        g = np.sum(w[:, None] * y[:, None] * np.interp(x[None, :] * y[:, None], x, s, right=0.0), axis=0)
        total = g if total is None else fftconvolve(total, g)[: x.size] * h
    total = np.clip(total, 0.0, None)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (total[1:] + total[:-1]) * h)])
    surv = np.clip(1.0 - cdf / max(cdf[-1], 1.0), 0.0, 1.0)  # mass beyond the grid is below 1e-12 here
    return NullDistribution(x, surv)


# --------------------------------------------------------------------------- indicator


@dataclass(frozen=True)
class LineResult:
    """One searched line: its window, the largest ratio there and where."""

    line: FaultLine
    bins: np.ndarray
    n_floor_bins: int
    ratio: float
    peak_frequency_Hz: float
    peak_amplitude_V: float
    floor_V: float


def _floors_mask(freq: np.ndarray, df: float, all_lines: list[FaultLine], guard: int) -> np.ndarray:
    """Bins outside every window and its guard bins (and above 0 Hz)."""
    ok = freq > 0
    for ln in all_lines:
        b = window_bins(ln, df, freq.size)
        ok[max(b[0] - guard, 0): b[-1] + guard + 1] = False
    return ok


def search_lines(spec: detection.EnvelopeSpectrum, lines: list[FaultLine], excluded: list[FaultLine],
                 carrier_Hz: float, settings: DetectorSettings) -> list[LineResult]:
    """The largest floor ratio in each line's window.

    The floor of harmonic k is the mean A^2 of the bins within
    floor_halfwidth x carrier of the harmonic's middle line, outside every
    window in ``excluded`` (the type's own lines) and its guard bins. Lines
    of another fault type in a floor raise it: that type's fault then
    weakens this type's test, which helps the classification.
    """
    f, a = spec.frequency_Hz, spec.amplitude_V
    df = spec.resolution_Hz
    free = _floors_mask(f, df, excluded, settings.guard_bins)
    out = []
    floors: dict[int, tuple[float, int]] = {}
    for ln in lines:
        if ln.harmonic not in floors:
            centre = ln.harmonic * carrier_Hz
            win = free & (np.abs(f - centre) <= settings.floor_halfwidth * carrier_Hz)
            nfl = int(win.sum())
            if nfl < 8:
                raise ValueError(
                    f"only {nfl} noise-floor bins around {centre:.6g} Hz ({ln.fault_type}); lengthen the record "
                    "(bearing.duration_s), widen signals.floor_halfwidth or narrow signals.detector.slip_max"
                )
            floors[ln.harmonic] = (float(np.mean(a[win] ** 2)), nfl)
        p_floor, nfl = floors[ln.harmonic]
        b = window_bins(ln, df, f.size)
        i = b[int(np.argmax(a[b]))]
        r = float(a[i] ** 2 / p_floor) if p_floor > 0 else float("inf")
        out.append(LineResult(ln, b, nfl, r, float(f[i]), float(a[i]), float(np.sqrt(p_floor))))
    return out


def _groups(results: list[LineResult], inflation: float) -> tuple:
    """Per harmonic: window sizes and the floor's effective bin count M_f / inflation."""
    by_k: dict[int, tuple[list[int], float]] = {}
    for r in results:
        by_k.setdefault(r.line.harmonic, ([], round(r.n_floor_bins / inflation, 6)))[0].append(int(r.bins.size))
    return tuple((tuple(ms), mf) for ms, mf in by_k.values())


def type_test(results: list[LineResult], alpha: float, window: str = "rectangular") -> dict:
    """Indicator sum_l R_l of some lines, its threshold at ``alpha`` and the decision.

    With a Hann window the floor's bins are correlated: its Gamma shape is
    M_f / 1.94 (same mean and variance); the window maxima are taken as
    independent, which overstates their tail (the threshold errs high).
    """
    if not results:
        return {"indicator": 0.0, "threshold": float("inf"), "detected": False, "p_value": 1.0, "n_lines": 0}
    null = null_distribution(_groups(results, WINDOWS[window]))
    value = float(sum(r.ratio for r in results))
    thr = null.threshold(alpha)
    return {"indicator": value, "threshold": thr, "detected": bool(value > thr), "p_value": null.p_value(value),
            "n_lines": len(results)}


def _overlaps(a: LineResult, others: list[np.ndarray]) -> bool:
    return any(a.bins[0] <= o[-1] and o[0] <= a.bins[-1] for o in others)


def _lines_to(kinematics: dict, fault_type: str, top_Hz: float, carrier_Hz: float,
              settings: DetectorSettings) -> list[FaultLine]:
    """Lines of a type with as many harmonics as reach ``top_Hz``: its impacts have harmonics beyond K.

    BPFO + BPFI = Z f_r, so high harmonics of one type fall on lines of
    another (5 BPFO = 3 BPFI + f_r for Z = 11): the own-line test must leave
    them out too.
    """
    k = max(settings.n_harmonics, int(np.ceil(top_Hz / ((1 - settings.slip_max) * carrier_Hz))) + 1)
    return fault_lines(kinematics, fault_type, k, settings.n_sidebands, settings.slip_max)


@dataclass(frozen=True)
class Detection:
    """Everything the detector found in one envelope spectrum."""

    fault_type: str
    per_type: dict = field(default_factory=dict)
    lines: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {"fault_type": self.fault_type, "per_type": self.per_type}
        out["lines"] = {
            t: [{"line": r.line.label, "band_Hz": [r.line.low_Hz, r.line.high_Hz], "n_bins": int(r.bins.size),
                 "ratio": r.ratio, "peak_frequency_Hz": r.peak_frequency_Hz, "peak_amplitude_V": r.peak_amplitude_V,
                 "floor_V": r.floor_V, "n_floor_bins": r.n_floor_bins} for r in res]
            for t, res in self.lines.items()
        }
        return out


def detect(spec: detection.EnvelopeSpectrum, kinematics: dict, settings: DetectorSettings) -> Detection:
    """Test every fault type in an envelope spectrum and classify the fault.

    Parameters
    ----------
    spec : EnvelopeSpectrum
        Envelope spectrum of the record (uniform bins from 0 Hz).
    kinematics : dict
        No-slip kinematic frequencies [Hz] (``shaft_Hz``, ``ftf_Hz``, ``bpfo_Hz``, ``bpfi_Hz``, ``bsf_Hz``).
    settings : DetectorSettings
    """
    bands = fault_bands(kinematics, settings.n_harmonics, settings.n_sidebands, settings.slip_max,
                        settings.fault_types)
    all_lines = [ln for t in settings.fault_types for ln in bands[t]]
    carriers = {"outer_race": kinematics["bpfo_Hz"], "inner_race": kinematics["bpfi_Hz"],
                "rolling_element": 2.0 * kinematics["bsf_Hz"], "cage": kinematics["ftf_Hz"]}
    alpha = settings.alpha_per_type
    res = {t: search_lines(spec, bands[t], bands[t], carriers[t], settings) for t in settings.fault_types}
    per_type = {t: type_test(res[t], alpha, settings.window) for t in settings.fault_types}
    detected = [t for t in settings.fault_types if per_type[t]["detected"]]
    top = max(ln.high_Hz for ln in all_lines)
    for t in settings.fault_types:
        others = [window_bins(ln, spec.resolution_Hz, spec.frequency_Hz.size)
                  for u in detected if u != t for ln in _lines_to(kinematics, u, top, carriers[u], settings)
                  if ln.low_Hz < spec.frequency_Hz[-1]]
        own = type_test([r for r in res[t] if not _overlaps(r, others)], alpha, settings.window)
        per_type[t]["own_lines"] = own
        per_type[t]["margin"] = per_type[t]["indicator"] / per_type[t]["threshold"]
    return Detection(classify(per_type, detected), per_type, res)


def classify(per_type: dict, detected: list[str]) -> str:
    """The fault type from the per-type tests (see the module docstring)."""
    if not detected:
        return "none"
    if len(detected) == 1:
        return detected[0]
    own = [t for t in detected if per_type[t]["own_lines"]["detected"]]
    if own:
        return max(own, key=lambda t: per_type[t]["own_lines"]["indicator"] / per_type[t]["own_lines"]["threshold"])
    return max(detected, key=lambda t: per_type[t]["margin"])


def analyse_record(x: np.ndarray, dt_s: float, kinematics: dict, envelope_settings: detection.EnvelopeSettings,
                   settings: DetectorSettings) -> tuple[detection.EnvelopeSpectrum, Detection]:
    """Band (fixed or kurtogram), envelope spectrum of the whole record, and :func:`detect`.

    The whole record is used: with slip there is no exact fault period to cut
    it to; the search windows absorb the leakage of a line between bins.
    """
    x = np.asarray(x, dtype=float)
    band, _ = detection.choose_band(x, dt_s, envelope_settings)
    spec = envelope.envelope_spectrum(x, dt_s, band, envelope_settings.filter_order, settings.window)
    return spec, detect(spec, kinematics, settings)
