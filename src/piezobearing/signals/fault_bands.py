"""Fault frequencies and fault bands of every fault type, with cage slip.

The role of MATLAB's ``bearingFaultBands`` and ``faultBandMetrics``: from the
bearing's kinematic frequencies (no slip: shaft f_r, cage FTF_0, BPFO_0,
BPFI_0, BSF_0 [Hz], as ``bearing.geometry.kinematic_frequencies`` writes them to
``kinematics.json``) the frequencies of the lines a defect puts into the
envelope spectrum, and for each line the band in which a detector must look
for it when the cage slip is only known to lie in [0, s_max].

Slip. The cage lags the rolling-without-slip speed by a fraction s (1-2 % is
usual). With the outer ring fixed and the shaft rate f_r measured,

.. math::

    FTF(s) = (1 - s)\\,FTF_0,\\quad BPFO(s) = Z\\,FTF(s),\\quad
    BPFI(s) = Z\\,(f_r - FTF(s)),\\quad BSF(s) = (1 - s)\\,BSF_0 ,

the last the usual approximation that the rollers' spin slows with the cage
(Randall & Antoni 2011). Every line is affine in s, f(s) = f(0) + s f'(s),
so its band over s in [0, s_max] is the interval between f(0) and f(s_max):
BPFO, BSF and FTF lines move down, BPFI lines move up.

Speed. Where the shaft rate is only known to within a fraction +-v (a nominal
speed 1-2 % off), every line scales with it: the band spans f(s) (1 - v) to
f(s) (1 + v) as well, in both directions. :func:`refine_shaft_rate` finds the
shaft rate in the record's spectrum where its harmonics show, so that v can
shrink to the estimate's own spread.

Lines of each type (k = 1..K harmonics, m = -S..S sidebands):

- ``outer_race``: k BPFO. A fixed defect in a fixed load zone: no sidebands.
- ``inner_race``: k BPFI + m f_r. The defect turns with the shaft through the
  load zone once per revolution: sidebands at the shaft rate.
- ``rolling_element``: k 2 BSF + m FTF. A flat on one roller strikes both
  races once per spin each (2 BSF) and is loaded only while its cage pocket
  passes the load zone: sidebands at the cage rate.
- ``cage``: k FTF (a cage defect modulates at the cage rate; no sidebands).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft
from scipy.ndimage import median_filter

#: Fault types with their lines; ``none`` is the healthy class of the classifier.
FAULT_TYPES = ("outer_race", "inner_race", "rolling_element", "cage")
#: The kinematic key of each line family's carrier and of its sideband spacing.
_CARRIER = {"outer_race": "bpfo_Hz", "inner_race": "bpfi_Hz", "rolling_element": "2bsf_Hz", "cage": "ftf_Hz"}
_SIDEBAND = {"outer_race": None, "inner_race": "shaft_Hz", "rolling_element": "ftf_Hz", "cage": None}


def slipped_frequencies(kinematics: dict, slip: float) -> dict:
    """Fault frequencies at cage slip ``slip`` (fraction) from the no-slip kinematics [Hz].

    Parameters
    ----------
    kinematics : dict
        ``shaft_Hz``, ``ftf_Hz``, ``bpfo_Hz``, ``bpfi_Hz``, ``bsf_Hz`` without slip [Hz].
    slip : float
        Fraction by which the cage lags rolling without slip [-], 0 <= slip < 1.

    Returns
    -------
    dict
        The same keys at that slip, plus ``2bsf_Hz`` [Hz].
    """
    if not 0.0 <= slip < 1.0:
        raise ValueError(f"slip {slip} must lie in [0, 1)")
    fr = float(kinematics["shaft_Hz"])
    ftf = (1.0 - slip) * float(kinematics["ftf_Hz"])
    z = float(kinematics["bpfo_Hz"]) / float(kinematics["ftf_Hz"])  # number of rollers
    bsf = (1.0 - slip) * float(kinematics["bsf_Hz"])
    return {"shaft_Hz": fr, "ftf_Hz": ftf, "bpfo_Hz": z * ftf, "bpfi_Hz": z * (fr - ftf), "bsf_Hz": bsf,
            "2bsf_Hz": 2.0 * bsf}


@dataclass(frozen=True)
class FaultLine:
    """One line of a fault type and its search band.

    Attributes
    ----------
    fault_type : str
    harmonic : int
        k of k x carrier [-].
    sideband : int
        m of + m x sideband spacing [-] (0: the carrier harmonic itself).
    frequency_Hz : float
        The line at the slip of the middle of the search range [Hz].
    low_Hz, high_Hz : float
        The line's frequency over slip in [0, s_max] [Hz].
    """

    fault_type: str
    harmonic: int
    sideband: int
    frequency_Hz: float
    low_Hz: float
    high_Hz: float

    @property
    def label(self) -> str:
        return f"{self.harmonic}x" + ("" if self.sideband == 0 else f"{self.sideband:+d}sb")


def fault_lines(kinematics: dict, fault_type: str, n_harmonics: int, n_sidebands: int, slip_max: float,
                speed_tolerance: float = 0.0) -> list[FaultLine]:
    """Lines of ``fault_type`` (k = 1..n_harmonics, m = -S..S where it has sidebands) and their bands.

    Parameters
    ----------
    kinematics : dict
        No-slip kinematic frequencies [Hz] (see :func:`slipped_frequencies`).
    fault_type : str
        One of :data:`FAULT_TYPES`.
    n_harmonics, n_sidebands : int
        K and S [-].
    slip_max : float
        Largest cage slip searched [-].
    speed_tolerance : float
        The shaft rate's relative uncertainty v, in both directions [-]: each band widens to
        [low (1 - v), high (1 + v)].
    """
    if not 0.0 <= speed_tolerance < 0.5:
        raise ValueError(f"speed tolerance {speed_tolerance} must lie in [0, 0.5)")
    if fault_type not in FAULT_TYPES:
        raise ValueError(f"fault type '{fault_type}' unknown; use one of {', '.join(FAULT_TYPES)}")
    f0 = slipped_frequencies(kinematics, 0.0)
    f1 = slipped_frequencies(kinematics, slip_max)
    fm = slipped_frequencies(kinematics, 0.5 * slip_max)
    car, sb = _CARRIER[fault_type], _SIDEBAND[fault_type]
    s_range = range(-n_sidebands, n_sidebands + 1) if sb else (0,)
    lines = []
    for k in range(1, n_harmonics + 1):
        for m in s_range:
            a = k * f0[car] + (m * f0[sb] if sb else 0.0)
            b = k * f1[car] + (m * f1[sb] if sb else 0.0)
            mid = k * fm[car] + (m * fm[sb] if sb else 0.0)
            if min(a, b) <= 0.0:
                continue  # a lower sideband below 0 Hz
            low, high = min(a, b) * (1.0 - speed_tolerance), max(a, b) * (1.0 + speed_tolerance)
            lines.append(FaultLine(fault_type, k, m, float(mid), float(low), float(high)))
    return lines


def fault_bands(kinematics: dict, n_harmonics: int, n_sidebands: int, slip_max: float,
                fault_types: tuple[str, ...] = FAULT_TYPES, speed_tolerance: float = 0.0) -> dict[str, list[FaultLine]]:
    """The lines and bands of every fault type (Python's ``bearingFaultBands``)."""
    return {t: fault_lines(kinematics, t, n_harmonics, n_sidebands, slip_max, speed_tolerance) for t in fault_types}


def window_bins(line: FaultLine, resolution_Hz: float, n_bins: int) -> np.ndarray:
    """Indices of the spectrum bins that bracket the line's band [low, high].

    From the bin at or below ``low`` to the bin at or above ``high``: a line
    anywhere in the band, between two bins, leaks into the two bins around it
    and both are searched.
    """
    lo = int(np.floor(line.low_Hz / resolution_Hz + 1e-9))
    hi = int(np.ceil(line.high_Hz / resolution_Hz - 1e-9))
    lo, hi = max(lo, 1), min(hi, n_bins - 1)
    if hi < lo:
        raise ValueError(f"line {line.fault_type} {line.label} at {line.frequency_Hz:.6g} Hz lies outside the "
                         f"spectrum (top {(n_bins - 1) * resolution_Hz:.6g} Hz); lower the number of harmonics")
    return np.arange(lo, hi + 1)


def band_metrics(frequency_Hz: np.ndarray, amplitude_V: np.ndarray, lines: list[FaultLine]) -> list[dict]:
    """Peak amplitude, its frequency and the total power in each line's band (``faultBandMetrics``).

    Parameters
    ----------
    frequency_Hz, amplitude_V : ndarray
        A single-sided amplitude spectrum, uniform bins from 0 Hz [Hz], [V].
    lines : list of FaultLine

    Returns
    -------
    list of dict
        Per line: label, band_Hz, peak_amplitude_V, peak_frequency_Hz,
        band_power_V2 (sum of A^2/2 over the band's bins, the mean-square of
        the sinusoids there).
    """
    f, a = np.asarray(frequency_Hz, dtype=float), np.asarray(amplitude_V, dtype=float)
    df = float(f[1] - f[0])
    out = []
    for ln in lines:
        b = window_bins(ln, df, f.size)
        i = b[int(np.argmax(a[b]))]
        out.append({"fault_type": ln.fault_type, "line": ln.label, "band_Hz": [ln.low_Hz, ln.high_Hz],
                    "peak_amplitude_V": float(a[i]), "peak_frequency_Hz": float(f[i]),
                    "band_power_V2": float(np.sum(a[b] ** 2) / 2.0)})
    return out


# --------------------------------------------------------------------------- the shaft rate from the record


@dataclass(frozen=True)
class ShaftRate:
    """The shaft rate found in a record's spectrum.

    Attributes
    ----------
    shaft_Hz : float
        The estimate (the nominal rate where ``refined`` is False) [Hz].
    nominal_Hz : float
        The rate given [Hz].
    refined : bool
        Whether at least ``min_harmonics`` shaft harmonics stood out at a common rate.
    harmonics : tuple of int
        The harmonics k whose line stood out at k x shaft_Hz [-].
    tolerance : float
        The estimate's relative uncertainty, for the fault bands (the given tolerance where not refined) [-].
    """

    shaft_Hz: float
    nominal_Hz: float
    refined: bool
    harmonics: tuple[int, ...]
    tolerance: float

    def to_dict(self) -> dict:
        return {"shaft_Hz": self.shaft_Hz, "nominal_Hz": self.nominal_Hz, "refined": self.refined,
                "harmonics": list(self.harmonics), "tolerance": self.tolerance}


def peak_over_median(power: np.ndarray, half_width_bins: int) -> np.ndarray:
    """Each bin's power over the local median of +-``half_width_bins`` bins, scaled so that noise gives
    Exp(1) ratios (the median of Exp(1) is ln 2) [-]."""
    floor = median_filter(np.asarray(power, dtype=float), size=2 * half_width_bins + 1, mode="reflect")
    return np.divide(power * np.log(2.0), floor, out=np.zeros_like(power, dtype=float), where=floor > 0)


def harmonic_ratio(x: np.ndarray, dt_s: float) -> np.ndarray:
    """The record's Hann-windowed power spectrum over its local median (:func:`peak_over_median`, +-2 Hz) [-]:
    where :func:`refine_shaft_rate` reads a rate's harmonics (bins of 1 / (N dt)).

    Parameters
    ----------
    x : ndarray
        The record (raw, not pre-whitened).
    dt_s : float
        Its sampling step [s].
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    df = 1.0 / (n * dt_s)
    window = np.hanning(n + 1)[:n]
    power = np.abs(scipy.fft.rfft(window * (x - x.mean()))) ** 2
    return peak_over_median(power, max(8, int(round(2.0 / df))))


def refine_shaft_rate(x: np.ndarray, dt_s: float, nominal_Hz: float, tolerance: float, n_harmonics: int = 10,
                      min_harmonics: int = 3, level: float = 30.0, ratio: np.ndarray | None = None) -> ShaftRate:
    """The shaft rate from the harmonics k f_r (k = 1..``n_harmonics``) of the record's spectrum.

    The Hann-windowed power spectrum over its local median (:func:`harmonic_ratio`) is read at
    k f for every candidate f within +-``tolerance`` of the nominal rate (steps of a tenth of a bin over the
    highest harmonic); f scores the number of harmonics whose ratio passes ``level`` (noise alone passes
    30 with probability e^-30 per bin), ties broken by the sum of their log ratios. Where fewer than
    ``min_harmonics`` pass, the nominal rate and tolerance stand. A refined rate is good to about a
    bin over the highest harmonic found: its tolerance is the larger of that and 0.1 %.

    Parameters
    ----------
    x : ndarray
        The record (raw, not pre-whitened).
    dt_s : float
        Its sampling step [s].
    nominal_Hz : float
        The shaft rate given (rig file, tachometer, --rpm) [Hz].
    tolerance : float
        Its relative uncertainty [-].
    ratio : ndarray, optional
        ``harmonic_ratio(x, dt_s)``, to save the transform when several rates are sought in one record.
    """
    n = np.asarray(x).size
    df = 1.0 / (n * dt_s)
    ratio = harmonic_ratio(x, dt_s) if ratio is None else ratio
    top = min(n_harmonics, int((0.5 / dt_s) / (nominal_Hz * (1 + tolerance))) - 1)
    if top < min_harmonics or tolerance <= 0:
        return ShaftRate(float(nominal_Hz), float(nominal_Hz), False, (), float(tolerance))
    step = 0.1 * df / top
    candidates = nominal_Hz * (1.0 + np.arange(-tolerance, tolerance + 1e-12, step / nominal_Hz))
    ks = np.arange(1, top + 1)
    bins = np.rint(np.outer(candidates, ks) / df).astype(int)
    # a line between bins of the Hann-windowed spectrum: the larger of the two nearest bins
    near = np.maximum(ratio[bins], ratio[np.minimum(bins + 1, ratio.size - 1)])
    near = np.maximum(near, ratio[np.maximum(bins - 1, 0)])
    passed = near > level
    score = passed.sum(axis=1) + 1e-3 * np.sum(np.where(passed, np.log(np.maximum(near, 1.0)), 0.0), axis=1)
    best = int(np.argmax(score))
    found = tuple(int(k) for k in ks[passed[best]])
    if len(found) < min_harmonics:
        return ShaftRate(float(nominal_Hz), float(nominal_Hz), False, found, float(tolerance))
    # centre of the candidates with the best score: the plateau's middle
    plateau = np.flatnonzero(score >= score[best] - 1e-12)
    estimate = float(np.mean(candidates[plateau]))
    spread = max(1e-3, df / (max(found) * estimate))
    return ShaftRate(estimate, float(nominal_Hz), True, found, float(spread))
