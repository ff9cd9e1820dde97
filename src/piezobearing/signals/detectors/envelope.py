"""The envelope detector: any rolling bearing's faults in any record, by the field's envelope methods.

The chain (Randall & Antoni, MSSP 25 (2011) 485-520; Smith & Randall, MSSP 64-65 (2015) 100-131):

1. **Shaft rate.** Refined from the record where its harmonics show
   (:func:`..fault_bands.refine_shaft_rate`); otherwise the given rate with its tolerance.
2. **Pre-whitening** (:func:`..envelope.prewhiten`): the spectrum's magnitude set to one. Shaft
   harmonics, gear meshes and resonances are flattened; the defect's impulses stay impulses.
3. **Bands.** The band of largest spectral kurtosis of the fast kurtogram (:func:`..envelope.fast_kurtogram`,
   bands at least as wide as the highest line searched, above ``min_band_low_Hz``) and, as the alternative,
   the whole pre-whitened band above ``min_band_low_Hz``: both are tested, and the false-alarm probability
   is split between them. A fixed band (``band_Hz``) replaces both.
4. **Squared envelope spectrum** (:func:`..envelope.envelope_spectrum`, Hann window) of each band; its
   power over the local median of +-``floor_halfwidth_Hz`` (:func:`..fault_bands.peak_over_median`), scaled
   so that a bin of noise has an Exp(1) ratio. The median floor is not raised by the lines it is meant to
   measure against (a mean floor is, by every shaft harmonic and sideband near the line).
5. **Lines** (:mod:`..fault_bands`): per family its harmonics k = 1..K of the carrier (BPFO; BPFI with
   shaft-rate sidebands; 2 BSF with cage-rate sidebands; FTF for the cage) over the slip range [0, slip_max]
   and the shaft rate's tolerance in both directions. The bins at the shaft's harmonics (k f_r +- the
   rate's spread and ``shaft_guard_bins``) are left out of every window: a healthy machine's shaft lines
   are not a fault's.
6. **Decision.** Per family the statistic is the sum over its lines of R_l, the largest ratio in the line's
   window. Under noise alone R_l is the largest of M_l Exp(1) bins over a median floor of effective Gamma
   shape M_f = ln(2)^2 n_floor / 1.94 (the median's variance; Hann-correlated bins); the distribution of the
   sum is computed (densities convolved, the floor by quadrature), and the family is detected when its sum
   passes the (1 - alpha) quantile. The level alpha per test is the calibration table's for ``pfa`` and the
   record's length (:mod:`.null_calibration`: made on simulated records without a fault, so that such a
   record is called any fault with probability ``pfa``); with ``calibrated_null`` off it is
   pfa / (n_families n_bands) (Bonferroni over families and bands: an upper bound, which the tests'
   correlation and each test's conservative null leave far above the measured rate on records of a few
   seconds). Of several
   families detected, the call is the one with the largest margin (the statistic over its threshold,
   in dB), taken in its better band.

Evidence: per family statistic, threshold, margin_dB; per line its level (10 log10 R_l) against the level
one window alone passes with probability alpha under noise with an exact floor. ``details``: the shaft
rate found, both bands with their margins, the kurtogram and the chosen band's spectrum for a report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft
from scipy.special import gammaincinv, roots_legendre

from ..envelope import EnvelopeSpectrum, Kurtogram, envelope_spectrum, fast_kurtogram, prewhiten
from ..fault_bands import (
    FaultLine,
    ShaftRate,
    fault_lines,
    harmonic_ratio,
    peak_over_median,
    refine_shaft_rate,
    window_bins,
)
from . import null_calibration
from .result import FAULT_TYPES, Detection, FamilyEvidence, LineEvidence, margin_dB

#: The carrier and sideband names of each family's line labels.
_CARRIER = {"outer_race": "BPFO", "inner_race": "BPFI", "rolling_element": "2xBSF", "cage": "FTF"}
_SIDEBAND = {"inner_race": "fr", "rolling_element": "FTF"}
#: Variance inflation of a mean of Hann-windowed bins' powers, 1 + 2 sum |rho_k|^2 (rho = -2/3, 1/6).
_HANN_INFLATION = 1.0 + 2.0 * (4.0 / 9.0 + 1.0 / 36.0)
#: Harmonics of a supply frequency (of the first ten) that must show for its lines to be left out [-].
MIN_MAINS_HARMONICS = 5
#: Quadrature nodes over the floor's Gamma distribution, and grid points of the null densities.
_N_QUAD = 32
_N_GRID = 2**13
#: The smallest false-alarm probability a family's null distribution reaches, and its grid's growths at most.
NULL_REACH = 1e-7
#: Where a line's density of the largest bin is cut, beyond ln M + this: the mass left out is e^-40 = 4e-18,
#: far below NULL_REACH [nats].
_TAIL_NATS = 40.0
_MAX_GROWTH = 3
#: The circular convolution's length over the grid's [-].
_CONV_PAD = 3


@dataclass(frozen=True)
class Settings:
    """The envelope detector's settings.

    Parameters
    ----------
    n_harmonics : int
        Harmonics k = 1..K of each family's carrier [-].
    n_sidebands : int
        Sidebands m = -S..S (inner race: shaft rate; rolling element: cage rate) [-].
    slip_max : float
        Largest cage slip searched [-] (1-2 % is usual).
    speed_tolerance : float
        Relative uncertainty of the given shaft rate, both directions [-]; where the record's shaft
        harmonics refine the rate, the refined rate's own spread replaces it.
    frequency_tolerance : float
        Relative uncertainty of the fault frequencies at a known shaft rate, both directions [-]: the
        contact angle of a ball bearing under axial load, the geometry's tolerances.
    false_alarm_probability : float
        Probability that a record without a fault is called any fault [-].
    families : tuple of str
        The families tested.
    floor_halfwidth_Hz : float
        Half-width of the local median floor [Hz] (at least 8 bins).
    shaft_guard_bins : int
        Bins on each side of every shaft harmonic left out of the line windows [-].
    prewhiten : bool
        Cepstrum pre-whitening before the envelope.
    band_Hz : tuple of float or None
        A fixed band [Hz]; None: the fast kurtogram's band and the whole band.
    min_band_low_Hz : float or None
        Lowest band edge [Hz]; None: twice the highest line searched (the envelope's own lines stay
        out of the band).
    refine_speed : bool
        Refine the shaft rate from the record's harmonics.
    mains_Hz : tuple of float
        Candidate supply frequencies [Hz]: the one whose harmonics show in the record (at least
        ``MIN_MAINS_HARMONICS`` of the first ten, :func:`electrical_rate`) has its harmonics left out of the
        line windows as the shaft's are (an electric motor's lines are not a bearing fault's); () tests none.
    cage_lines : bool
        The rolling-element family includes the cage-rate harmonics k FTF (:func:`family_lines`).
    min_lines_above : int
        A family is detected only where at least this many of its lines also pass their own threshold: a
        fault shows as a family of lines, and one strong line (another machine element's, another
        bearing's) alone is not its signature. The condition can only lower the false-alarm probability.
    min_type_separation_dB : float or None
        A fault's type is called only where the winning family's margin stands at least this far above
        every other family's [dB]; nearer, the call is ``unknown`` with its candidates (:func:`type_call`).
        None turns the rule and its record in ``details`` off (the workflow's simulated records).
    calibrated_null : bool
        The level of each test from the calibration table (:mod:`.null_calibration`: made on simulated records
        without a fault, so that a record without a fault is called faulty at the stated probability);
        False: Bonferroni, ``false_alarm_probability`` over the families and bands (an upper bound, far
        above the measured rate).

    The defaults of ``frequency_tolerance``, ``mains_Hz``, ``cage_lines``, ``min_lines_above`` and
    ``min_type_separation_dB`` are chosen on the 46 records of the CWRU fan-end set, by the procedure whose
    worth grouped cross-validation measures (:mod:`piezobearing.signals.tuning`, ``scripts/tune_cwru.py``,
    docs/validation/cwru.md); the others were not chosen on real records.
    """

    n_harmonics: int = 3
    n_sidebands: int = 1
    slip_max: float = 0.02
    speed_tolerance: float = 0.02
    frequency_tolerance: float = 0.005
    false_alarm_probability: float = 1e-3
    families: tuple[str, ...] = FAULT_TYPES
    floor_halfwidth_Hz: float = 5.0
    shaft_guard_bins: int = 2
    prewhiten: bool = True
    band_Hz: tuple[float, float] | None = None
    min_band_low_Hz: float | None = None
    refine_speed: bool = True
    mains_Hz: tuple[float, ...] = (50.0, 60.0)
    cage_lines: bool = True
    min_lines_above: int = 1
    min_type_separation_dB: float | None = 1.0
    calibrated_null: bool = True

    def __post_init__(self):
        if not 0 < self.false_alarm_probability < 1:
            raise ValueError(f"false_alarm_probability = {self.false_alarm_probability}; give a probability in (0, 1)")
        unknown = [f for f in self.families if f not in FAULT_TYPES]
        if unknown:
            raise ValueError(f"family '{unknown[0]}' is not a call of the detector; use {', '.join(FAULT_TYPES)}")

    @classmethod
    def from_config(cls, signals: dict) -> "Settings":
        """From the validated config's ``signals`` section (the workflow's simulated records: its
        ``band_rule: fixed`` band, its harmonics, sidebands, slip range and false-alarm probability; two lines
        above their own threshold, and the family of largest margin called without the type rule).

        No pre-whitening there: a simulated defect strikes exactly periodically, so its impulses are
        lines of the spectrum, which pre-whitening would flatten with the rest (a real defect's impulses
        jitter with the slip and spread between the lines); the rate is the model's, exact."""
        d = signals["detector"]
        band = tuple(signals["band_Hz"]) if signals.get("band_rule") == "fixed" else None
        return cls(n_harmonics=d["n_harmonics"], n_sidebands=d["n_sidebands"], slip_max=d["slip_max"],
                   speed_tolerance=0.0, frequency_tolerance=0.0, false_alarm_probability=signals["false_alarm_probability"],
                   band_Hz=band, refine_speed=False, prewhiten=False, mains_Hz=(), cage_lines=False,
                   min_lines_above=2, min_type_separation_dB=None, calibrated_null=False)


# --------------------------------------------------------------------------- null distribution


@lru_cache(maxsize=64)
def _gamma_nodes(shape: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of E[h(Y)], Y ~ Gamma(shape, 1/shape): Gauss-Legendre in probability."""
    u, w = roots_legendre(_N_QUAD)
    # The quantiles as scipy.stats.gamma.ppf(p, shape, scale=1/shape) computes them, bit for bit (its _ppf is
    # gammaincinv, then times the scale): scipy.stats costs about 0.6 s of import that detection needs for nothing else.
    return gammaincinv(shape, 0.5 * (u + 1.0)) * (1.0 / shape), 0.5 * w


@dataclass(frozen=True)
class NullDistribution:
    """Distribution of a family's statistic sum_l R_l under noise alone, on a grid.

    Attributes
    ----------
    x : ndarray
        Grid of the statistic [-].
    survival : ndarray
        P(statistic > x) [-].
    """

    x: np.ndarray
    survival: np.ndarray
    window_bins: tuple[int, ...] = ()
    floor_shape: float = 0.0

    def threshold(self, alpha: float) -> float:
        """The (1 - alpha) quantile [-]; beyond the grid's reach, :meth:`union_bound`'s threshold."""
        s = self.survival
        if alpha <= s[-1]:
            if not self.window_bins:
                raise ValueError(f"false-alarm probability {alpha:g} below the grid's reach {s[-1]:.3g}")
            return self.union_bound(alpha)
        i = int(np.flatnonzero(s > alpha)[-1])
        return float(self.x[i] + (s[i] - alpha) * (self.x[i + 1] - self.x[i]) / (s[i] - s[i + 1]))

    def union_bound(self, alpha: float) -> float:
        """:func:`union_bound_threshold` of this distribution's lines, for probabilities the grid cannot reach
        (few floor bins put the smallest quadrature node's mass beyond any grid) [-]."""
        return union_bound_threshold(self.window_bins, self.floor_shape, alpha)

    def p_value(self, value: float) -> float:
        """P(statistic > value) under noise alone (0 beyond the grid) [-]."""
        return float(np.interp(value, self.x, self.survival, right=0.0))


@lru_cache(maxsize=512)
def null_distribution(window_bins: tuple[int, ...], floor_shape: float) -> NullDistribution:
    """Null distribution of sum_l Z_l / Y_l: Z_l the largest of M_l Exp(1) bins, Y_l ~ Gamma(M_f, 1/M_f)
    independent floors (each line its own median).

    Parameters
    ----------
    window_bins : tuple of int
        M_l of each line [-].
    floor_shape : float
        M_f, the floors' effective Gamma shape [-].
    """
    # The grid spans 40 + 25 per line; where the floors are few (a small M_f gives Z/Y a power-law tail)
    # that span leaves more than NULL_REACH of the probability beyond it, and it grows fourfold at the same
    # step until it does not, so that every false-alarm probability down to NULL_REACH has its threshold.
    span, n_grid = 40.0 + 25.0 * len(window_bins), _N_GRID
    for _ in range(_MAX_GROWTH):
        null = _null_on_grid(window_bins, floor_shape, span, n_grid)
        if null.survival[-1] <= NULL_REACH:
            break
        span, n_grid = 4.0 * span, 4 * (n_grid - 1) + 1
    return null


def union_bound_threshold(window_bins: tuple[int, ...], floor_shape: float, alpha: float) -> float:
    """A threshold t with P(sum_l R_l > t) <= alpha, conservative [-].

    P(sum of L ratios > t) <= sum_l P(R_l > t / L), and P(Z/Y > r) <= M E[exp(-r Y)] = M (1 + r / M_f)^-M_f
    for Z the largest of M Exp(1) bins over a Gamma(M_f, 1/M_f) floor Y; equal to alpha at
    t = L M_f ((sum_l M_l / alpha)^(1 / M_f) - 1).
    """
    n, m_f = len(window_bins), floor_shape
    return float(n * m_f * ((sum(window_bins) / alpha) ** (1.0 / m_f) - 1.0))


def _null_on_grid(window_bins: tuple[int, ...], floor_shape: float, span: float, n_grid: int) -> NullDistribution:
    """:func:`null_distribution` on the grid of ``n_grid`` points over [0, ``span``]."""
    x = np.linspace(0.0, span, n_grid)
    h = x[1]
    if len(window_bins) == 1:
        total = np.array(_line_ratio_density(window_bins[0], floor_shape, span, n_grid))
    else:
        # the densities' product in the frequency domain (each line's transform cached): the circular convolution
        # of length _CONV_PAD n folds only sums beyond _CONV_PAD - 1 spans onto the grid, whose probability is far
        # below the span's own, NULL_REACH at most
        n_fft = next_fast_len(_CONV_PAD * n_grid, real=True)
        spectrum = np.ones(n_fft // 2 + 1, dtype=complex)
        for m in window_bins:
            spectrum = spectrum * _line_ratio_spectrum(m, floor_shape, span, n_grid, n_fft)
        total = irfft(spectrum, n_fft)[:n_grid] * h ** (len(window_bins) - 1)
    total = np.clip(total, 0.0, None)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (total[1:] + total[:-1]) * h)])
    return NullDistribution(x, np.clip(1.0 - cdf / max(cdf[-1], 1.0), 0.0, 1.0), tuple(window_bins), float(floor_shape))


@lru_cache(maxsize=256)
def _line_ratio_density(m: int, floor_shape: float, span: float, n_grid: int) -> np.ndarray:
    """Density of one line's ratio Z / Y on the grid of ``n_grid`` points over [0, ``span``]: Z the largest of
    ``m`` Exp(1) bins, density m e^-z (1 - e^-z)^(m-1); Y ~ Gamma(M_f, 1/M_f) by its quadrature nodes,
    f(r) = E_Y[Y f_Z(r Y)] (read-only: shared by every family with a line of ``m`` bins)."""
    x = np.linspace(0.0, span, n_grid)
    y, w = _gamma_nodes(round(floor_shape, 3))
    # f_Z(v) = exp(ln m - v + (m - 1) ln(1 - e^-v)) is below e^-_TAIL_NATS of its peak beyond v = ln m + _TAIL_NATS
    # (the mass beyond, e^-_TAIL_NATS): each node's sum runs over the grid points below that only, a tenth of the grid
    # or less
    v_max = math.log(m) + _TAIL_NATS
    g = np.zeros(n_grid)
    ends = np.minimum(np.searchsorted(x, v_max / y, side="right"), n_grid)
    with np.errstate(divide="ignore"):  # ln(1 - e^0) = -inf at v = 0: the density's exact 0 there
        for yj, wj, k in zip(y, w, ends, strict=True):
            v = x[:k] * yj
            z = np.exp(-v) if m == 1 else np.exp(math.log(m) - v + (m - 1) * np.log(-np.expm1(-v)))
            g[:k] += (wj * yj) * z
    g.setflags(write=False)
    return g


@lru_cache(maxsize=128)
def _line_ratio_spectrum(m: int, floor_shape: float, span: float, n_grid: int, n_fft: int) -> np.ndarray:
    """The real FFT of :func:`_line_ratio_density` zero-padded to ``n_fft`` points (read-only)."""
    g = rfft(_line_ratio_density(m, floor_shape, span, n_grid), n_fft)
    g.setflags(write=False)
    return g


def line_threshold(alpha: float, n_bins: int) -> float:
    """Level t with P(largest of M Exp(1) bins > t) = alpha (an exact floor) [-]."""
    return float(-np.log(-np.expm1(np.log1p(-alpha) / n_bins)))


# --------------------------------------------------------------------------- the search


def line_label(line: FaultLine) -> str:
    """``"2xBPFO"``, ``"1xBPFI-1xfr"``, ``"1x2xBSF+1xFTF"``: a line's name."""
    label = f"{line.harmonic}x{_CARRIER[line.fault_type]}"
    if line.sideband:
        label += f"{line.sideband:+d}x{_SIDEBAND[line.fault_type]}"
    return label


def family_lines(kinematics: dict, family: str, settings: Settings, tolerance: float) -> list[FaultLine]:
    """The lines a family is tested on (:func:`..fault_bands.fault_lines`); the rolling-element family's
    include the cage-rate harmonics k FTF: a damaged rolling element strikes hard only while the cage
    carries it through the load zone, once per cage revolution, so its impacts' envelope is modulated at
    FTF, and the FTF harmonics often stand out where the 2 x BSF lines do not (Randall & Antoni 2011)."""
    lines = fault_lines(kinematics, family, settings.n_harmonics, settings.n_sidebands, settings.slip_max, tolerance)
    if family == "rolling_element" and settings.cage_lines:
        lines = fault_lines(kinematics, "cage", settings.n_harmonics, 0, settings.slip_max, tolerance) + lines
    return lines


def scaled_kinematics(kinematics: dict, shaft_Hz: float) -> dict:
    """The kinematic frequencies at another shaft rate (all scale with it) [Hz]."""
    scale = shaft_Hz / kinematics["shaft_Hz"]
    return {k: v * scale for k, v in kinematics.items()}


def harmonic_mask(frequency_Hz: np.ndarray, rate: ShaftRate, guard_bins: int) -> np.ndarray:
    """Bins within a rate's spread and ``guard_bins`` of one of its harmonics k f (k >= 1)."""
    f = frequency_Hz
    df = float(f[1] - f[0])
    k = np.maximum(np.rint(f / rate.shaft_Hz), 1.0)
    return np.abs(f - k * rate.shaft_Hz) <= k * rate.shaft_Hz * rate.tolerance + (guard_bins + 0.5) * df


def electrical_rate(x: np.ndarray, dt_s: float, candidates_Hz: tuple[float, ...],
                    ratio: np.ndarray | None = None) -> ShaftRate | None:
    """The supply frequency among ``candidates_Hz`` whose harmonics show most in the record's spectrum
    (at least :data:`MIN_MAINS_HARMONICS` of the first ten, within +-0.5 %), or None. ``ratio``: the record's
    :func:`..fault_bands.harmonic_ratio`, where the caller has it."""
    ratio = harmonic_ratio(x, dt_s) if ratio is None else ratio
    found = [refine_shaft_rate(x, dt_s, f, 0.005, n_harmonics=10, min_harmonics=MIN_MAINS_HARMONICS, ratio=ratio)
             for f in candidates_Hz]
    found = [r for r in found if r.refined]
    return max(found, key=lambda r: len(r.harmonics)) if found else None


@dataclass(frozen=True)
class LineRatio:
    """One line's measurement in one band: the largest ratio over the floor in its window, where, and how
    many bins the window held (the shaft and supply harmonics' bins left out)."""

    label: str
    frequency_Hz: float
    ratio: float
    n_bins: int


@dataclass(frozen=True)
class BandRatios:
    """What one band's squared envelope spectrum shows at every family's lines, before any threshold."""

    band_Hz: tuple[float, float]
    spectrum: EnvelopeSpectrum
    ratio: np.ndarray
    floor_shape: float
    lines: dict[str, tuple[LineRatio, ...]]


@dataclass(frozen=True)
class BandTest:
    """The families tested in one band's squared envelope spectrum."""

    band_Hz: tuple[float, float]
    spectrum: EnvelopeSpectrum
    ratio: np.ndarray
    families: dict[str, FamilyEvidence]
    p_values: dict[str, float]


def band_ratios(spectrum: EnvelopeSpectrum, lines: dict[str, list[FaultLine]], excluded_rates: list[ShaftRate],
                settings: Settings) -> BandRatios:
    """Every family's lines read in one squared envelope spectrum (steps 4-5 of the module docstring)."""
    f = spectrum.frequency_Hz
    df = spectrum.resolution_Hz
    half = max(8, int(round(settings.floor_halfwidth_Hz / df)))
    ratio = peak_over_median(spectrum.amplitude_V**2, half)
    excluded = np.zeros(f.size, dtype=bool)
    for rate in excluded_rates:
        excluded |= harmonic_mask(f, rate, settings.shaft_guard_bins)
    floor_shape = math.log(2.0) ** 2 * (2 * half + 1) / _HANN_INFLATION
    found = {}
    for family, family_lines in lines.items():
        measured = []
        for line in family_lines:
            if line.high_Hz >= f[-1]:
                continue
            bins = window_bins(line, df, f.size)
            bins = bins[~excluded[bins]]
            if bins.size == 0:
                continue  # the line lies on a shaft harmonic: no evidence either way
            i = int(bins[np.argmax(ratio[bins])])
            measured.append(LineRatio(line_label(line), float(f[i]), float(ratio[i]), int(bins.size)))
        found[family] = tuple(measured)
    return BandRatios(tuple(float(b) for b in spectrum.band_Hz), spectrum, ratio, floor_shape, found)


def judge_band(band: BandRatios, alpha: float, settings: Settings) -> BandTest:
    """Every family of one band against its null distribution at ``alpha`` (step 6 of the module docstring)."""
    families, p_values = {}, {}
    for family, measured in band.lines.items():
        evidence, sizes, total = [], [], 0.0
        for m in measured:
            r = m.ratio
            t = line_threshold(alpha, m.n_bins)
            evidence.append(LineEvidence(m.label, m.frequency_Hz, 10.0 * math.log10(r) if r > 0 else -math.inf,
                                         10.0 * math.log10(t), bool(r > t)))
            sizes.append(m.n_bins)
            total += r
        if not sizes:
            families[family] = FamilyEvidence(family, 0.0, math.inf, -math.inf, False, ())
            p_values[family] = 1.0
            continue
        null = null_distribution(tuple(sizes), round(band.floor_shape, 3))
        threshold = null.threshold(alpha)
        detected = total > threshold and sum(e.above for e in evidence) >= settings.min_lines_above
        families[family] = FamilyEvidence(family, total, threshold, margin_dB(total, threshold), bool(detected),
                                          tuple(evidence))
        p_values[family] = null.p_value(total)
    return BandTest(band.band_Hz, band.spectrum, band.ratio, families, p_values)


def test_band(spectrum: EnvelopeSpectrum, lines: dict[str, list[FaultLine]], excluded_rates: list[ShaftRate],
              alpha: float, settings: Settings) -> BandTest:
    """Every family's lines searched in one squared envelope spectrum (steps 4-6 of the module docstring)."""
    return judge_band(band_ratios(spectrum, lines, excluded_rates, settings), alpha, settings)


def candidate_bands(w: np.ndarray, dt_s: float, top_line_Hz: float, settings: Settings
                    ) -> tuple[list[tuple[float, float]], Kurtogram | None]:
    """The fixed band, or the fast kurtogram's band and the whole band above the lowest edge [Hz]."""
    if settings.band_Hz is not None:
        return [(float(settings.band_Hz[0]), float(settings.band_Hz[1]))], None
    nyquist = 0.5 / dt_s
    low = settings.min_band_low_Hz if settings.min_band_low_Hz is not None else 2.0 * top_line_Hz
    if low + top_line_Hz >= nyquist:
        raise ValueError(
            f"the lines searched reach {top_line_Hz:.4g} Hz: no band above {low:.4g} Hz and that wide fits below "
            f"Nyquist {nyquist:.4g} Hz; record at a higher rate or search fewer harmonics"
        )
    kurtogram = fast_kurtogram(w, dt_s, min_bandwidth_Hz=top_line_Hz, min_low_Hz=low)
    best = kurtogram.best_band_Hz
    whole = (float(low), float(nyquist))
    bands = [best] if np.allclose(best, whole) else [best, whole]
    return bands, kurtogram


@dataclass(frozen=True)
class Reading:
    """What a record shows at a bearing's lines before any decision (:func:`measure`): the shaft and supply
    rates found, the bands with every line's ratio, the kurtogram. :func:`decide` turns it into a
    :class:`Detection` at any false-alarm probability and call rule, without reading the record again."""

    shaft: ShaftRate
    mains: ShaftRate | None
    bands: tuple[BandRatios, ...]
    kurtogram: Kurtogram | None
    lines: dict[str, list[FaultLine]]
    top_Hz: float
    #: The record's length [s] (the calibrated null's level depends on it); unknown: infinite, whose level is
    #: the longest calibrated length's, at most Bonferroni's.
    seconds: float = math.inf


def measure(samples: np.ndarray, sample_rate_Hz: float, kinematics: dict, settings: Settings) -> Reading:
    """Steps 1-5 of the module docstring: the rate, the bands, every family's line ratios (``settings``'
    decision fields, ``false_alarm_probability``, ``min_lines_above`` and ``min_type_separation_dB``, are
    not read)."""
    x = np.asarray(samples, dtype=float)
    dt = 1.0 / float(sample_rate_Hz)
    nominal = float(kinematics["shaft_Hz"])
    # the shaft's and the supply's harmonics are read in one spectrum of the record
    ratio = harmonic_ratio(x, dt) if settings.refine_speed or settings.mains_Hz else None
    if settings.refine_speed:
        shaft = refine_shaft_rate(x, dt, nominal, settings.speed_tolerance, ratio=ratio)
    else:
        shaft = ShaftRate(nominal, nominal, False, (), settings.speed_tolerance)
    kin = scaled_kinematics(kinematics, shaft.shaft_Hz)
    tolerance = shaft.tolerance + settings.frequency_tolerance
    lines = {fam: family_lines(kin, fam, settings, tolerance) for fam in settings.families}
    top = max(ln.high_Hz for fam in lines.values() for ln in fam)
    w = prewhiten(x) if settings.prewhiten else x - x.mean()
    bands, kurtogram = candidate_bands(w, dt, top, settings)
    mains = electrical_rate(x, dt, settings.mains_Hz, ratio) if settings.mains_Hz else None
    excluded_rates = [shaft] + ([mains] if mains is not None else [])
    spectrum = rfft(w)  # every band's envelope from the one transform
    measured = tuple(band_ratios(envelope_spectrum(w, dt, band, window="hann", squared=True, spectrum=spectrum),
                                 lines, excluded_rates, settings) for band in bands)
    return Reading(shaft, mains, measured, kurtogram, lines, top, x.size * dt)


def decide(m: Reading, settings: Settings) -> Detection:
    """Step 6 of the module docstring and the call: each family judged in each band at the false-alarm
    probability split over families and bands; the call is the detected family of largest margin
    (:func:`type_call`), or ``unknown`` where another family's margin lies within ``min_type_separation_dB``
    of it, or ``none``."""
    alpha, tests, call, chosen = _judge(m, settings)
    families = tests[chosen].families
    if call == "none":
        # the families' evidence from the band where each came closest
        families = {fam: max((t.families[fam] for t in tests), key=lambda e: e.margin_dB) for fam in settings.families}
    typed = type_call(tests, call, settings.min_type_separation_dB)
    spectrum = tests[chosen].spectrum
    keep = spectrum.frequency_Hz <= 1.1 * m.top_Hz
    kurtogram = m.kurtogram
    details = {
        "shaft": m.shaft.to_dict(),
        "mains": None if m.mains is None else m.mains.to_dict(),
        "bands": [{"band_Hz": list(t.band_Hz), "margins_dB": {f: e.margin_dB for f, e in t.families.items()},
                   "p_values": t.p_values} for t in tests],
        "chosen_band": chosen,
        "alpha_per_test": alpha,
        "prewhitened": settings.prewhiten,
        "kurtogram": None if kurtogram is None else {
            "level": kurtogram.level.tolist(), "low_Hz": kurtogram.low_Hz.tolist(),
            "high_Hz": kurtogram.high_Hz.tolist(), "kurtosis": kurtogram.kurtosis.tolist()},
        "spectrum": {"frequency_Hz": spectrum.frequency_Hz[keep].tolist(),
                     "ratio": tests[chosen].ratio[keep].tolist()},
        "lines": {fam: [{"label": line_label(ln), "low_Hz": ln.low_Hz, "high_Hz": ln.high_Hz} for ln in fam_lines]
                  for fam, fam_lines in m.lines.items()},
    }
    if typed is not None:
        details["type_call"] = typed
        call = typed["call"]
    return Detection.from_families("envelope", families, call, tests[chosen].band_Hz, m.shaft.shaft_Hz,
                                   settings.false_alarm_probability, details)


def _judge(m: Reading, settings: Settings) -> tuple[float, list[BandTest], str, int]:
    """Every band judged: the level per test, the band tests, the detected family of largest margin (or none)
    and its band."""
    alpha = alpha_per_test(settings, len(m.bands), m.seconds)
    tests = [judge_band(b, alpha, settings) for b in m.bands]
    call, chosen = _call(tests)
    return alpha, tests, call, chosen


def call_of(m: Reading, settings: Settings) -> tuple[str, dict[str, float], dict | None]:
    """The call :func:`decide` makes, without its report: the call, each family's best margin over the bands
    [dB] and the :func:`type_call` record (None where no fault is detected or the type rule is off)."""
    _, tests, call, _ = _judge(m, settings)
    margins = {fam: max(t.families[fam].margin_dB for t in tests) for fam in settings.families}
    typed = type_call(tests, call, settings.min_type_separation_dB)
    return (call if typed is None else typed["call"]), margins, typed


def without_spectra(m: Reading) -> Reading:
    """The reading with its bands' spectra and the kurtogram dropped: what :func:`call_of` needs, a few
    kilobytes instead of megabytes (for a settings search over many records)."""
    bands = tuple(BandRatios(b.band_Hz, None, None, b.floor_shape, b.lines) for b in m.bands)
    return Reading(m.shaft, m.mains, bands, None, m.lines, m.top_Hz, m.seconds)


def type_call(tests: list[BandTest], call: str, separation_dB: float | None) -> dict | None:
    """The fault type's call where a fault is detected: the winning family (largest margin of any band), each
    other family's best margin and its distance below the winner, and ``unknown`` where the runner-up lies
    within ``separation_dB`` of it (its candidates: the winner and every family within that distance).

    None where no family is detected (the call is ``none``) or ``separation_dB`` is None (the rule is off: the
    workflow's simulated records, whose calls stay the detected family of largest margin)."""
    if call == "none" or separation_dB is None:
        return None
    best = {fam: max(t.families[fam].margin_dB for t in tests) for fam in tests[0].families}
    detected = {fam: any(t.families[fam].detected for t in tests) for fam in best}
    others = sorted((f for f in best if f != call), key=lambda f: -best[f])
    runner = others[0] if others else None
    gap = math.inf if runner is None else best[call] - best[runner]
    candidates = [call] + [f for f in others if best[call] - best[f] < separation_dB]
    why = {}
    for f in others:
        reason = f"{best[call] - best[f]:.1f} dB below the {call.replace('_', ' ')}"
        reason += ", detected but not the largest" if detected[f] else ", not detected"
        why[f] = reason
    return {
        "call": "unknown" if gap < separation_dB else call,
        "winner": call,
        "runner_up": runner,
        "separation_dB": gap,
        "required_separation_dB": separation_dB,
        "candidates": candidates if gap < separation_dB else [call],
        "margins_dB": best,
        "detected": detected,
        "why_not": why,
    }


def alpha_per_test(settings: Settings, n_bands: int, seconds: float) -> float:
    """The level of each family's test in each band: the calibration table's level for the stated false-alarm
    probability and a record of ``seconds`` (:func:`.null_calibration.alpha_per_test`), or, with ``calibrated_null`` off, the probability
    split over the families and bands (Bonferroni)."""
    if settings.calibrated_null:
        return null_calibration.alpha_per_test(settings.false_alarm_probability, seconds,
                                               len(settings.families) * n_bands)
    return settings.false_alarm_probability / (len(settings.families) * n_bands)


def critical_alpha(m: Reading, settings: Settings) -> float:
    """The level per test below which the record raises no alarm: at any level ``alpha`` above it some family
    is detected in some band (its sum passes its threshold and at least ``min_lines_above`` of its lines
    pass theirs), at any level below, none [-].

    Per family and band it is the larger of the sum's p-value (beyond the grid: the union bound's level) and
    the ``min_lines_above``-th smallest p-value of a line, 1 - (1 - e^-R)^M; the record's is the smallest over
    families and bands. What :mod:`.null_calibration` is made of: the stated probability's level is the
    quantile of this over records without a fault."""
    best = math.inf
    for band in m.bands:
        for measured in band.lines.values():
            if len(measured) < max(settings.min_lines_above, 1):
                continue
            sizes = tuple(x.n_bins for x in measured)
            total = sum(x.ratio for x in measured)
            null = null_distribution(sizes, round(band.floor_shape, 3))
            if total <= null.x[-1]:
                p_sum = null.p_value(total)
            else:  # beyond the grid the threshold is the union bound's: its level at this sum
                m_f = null.floor_shape or round(band.floor_shape, 3)
                p_sum = min(float(null.survival[-1]), sum(sizes) * (1.0 + total / (len(sizes) * m_f)) ** -m_f)
            p_lines = sorted(float(-np.expm1(x.n_bins * np.log1p(-np.exp(-x.ratio)))) for x in measured)
            p_line = p_lines[settings.min_lines_above - 1] if settings.min_lines_above >= 1 else 0.0
            best = min(best, max(p_sum, p_line))
    return best


def detect(samples: np.ndarray, sample_rate_Hz: float, kinematics: dict, settings: Settings, reference=None) -> Detection:
    """Detect and classify a bearing fault in one record (``reference`` is not used): :func:`decide` of
    :func:`measure`.

    Parameters
    ----------
    samples : ndarray
        The record (any unit: every test is a ratio).
    sample_rate_Hz : float
        Its sampling rate [Hz].
    kinematics : dict
        The bearing's kinematic frequencies at the given shaft rate, without slip [Hz]
        (``shaft_Hz``, ``ftf_Hz``, ``bpfo_Hz``, ``bpfi_Hz``, ``bsf_Hz``).
    settings : Settings

    Returns
    -------
    Detection
        ``details``: ``shaft`` (the rate found), ``bands`` (per band tested its families' margins),
        ``chosen_band`` (index), ``type_call`` (where a fault is detected and the type rule is on: the
        winner, its runner-up and their separation, the candidates of an ``unknown`` call, per family why it
        lost), and, for a report, ``kurtogram`` and ``spectrum`` (the chosen band's squared envelope spectrum
        up to the highest line) as lists.
    """
    return decide(measure(samples, sample_rate_Hz, kinematics, settings), settings)


def _call(tests: list[BandTest]) -> tuple[str, int]:
    """The detected family with the largest margin over every band, and its band; else none and the band
    of the largest margin of any family."""
    best = (-math.inf, "none", 0)
    for b, t in enumerate(tests):
        for fam, e in t.families.items():
            if e.detected and e.margin_dB > best[0]:
                best = (e.margin_dB, fam, b)
    if best[1] != "none":
        return best[1], best[2]
    margins = [max((e.margin_dB for e in t.families.values()), default=-math.inf) for t in tests]
    return "none", int(np.argmax(margins))


def detect_many(records, sample_rate_Hz: float, kinematics: dict, settings: Settings, reference=None) -> list[Detection]:
    """:func:`detect` of each record."""
    return [detect(x, sample_rate_Hz, kinematics, settings) for x in records]
