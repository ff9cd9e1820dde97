"""Low-frequency sensitivity of the calibrated sensor (Sec. III-C, Fig. 8a).

The sensitivity S(f) = |H(j 2 pi f)| of the RC model is swept over the
paper's frequencies (1, 10, 20, ..., 100 Hz). Its deviation at sweep point k
is the relative change to the next sweep point, |S_{k+1} - S_k| / S_k; the
response counts as linear from the first frequency after which every
deviation stays below the threshold (5% in the paper). This reading of the
paper's "sensitivity deviation percentage" reproduces its 30 Hz with its
constants; the deviation from the open-circuit asymptote d33/C, 1 - S/S_inf,
is reported beside it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .calibration import SensorCircuit, frequency_response


@dataclass(frozen=True)
class LowFreqResult:
    frequency_Hz: np.ndarray
    sensitivity_V_per_N: np.ndarray
    deviation_next: np.ndarray  # |S_{k+1} - S_k| / S_k, NaN at the last point
    deviation_asymptote: np.ndarray  # 1 - S / (d33/C)
    linear_from_Hz: float
    reference_sensitivity_V_per_N: float
    asymptote_V_per_N: float


def linearity_onset(frequency_Hz: np.ndarray, deviation: np.ndarray, threshold: float) -> int:
    """Index of the first sweep point from which every (finite) deviation is below ``threshold``.

    Returns -1 when no such point exists.
    """
    dev = np.asarray(deviation, dtype=float)
    ok = ~(dev >= threshold)  # NaN (last point) counts as ok
    for k in range(len(dev)):
        if ok[k:].all() and np.isfinite(dev[k]):
            return k
    return -1


def lowfreq_sensitivity(frequency_Hz, circuit: SensorCircuit, threshold: float) -> LowFreqResult:
    """Sensitivity, deviation curves and the onset of linearity of ``circuit``."""
    f = np.asarray(frequency_Hz, dtype=float)
    if np.any(np.diff(f) <= 0):
        raise ValueError("lowfreq.frequencies_Hz must increase")
    s = np.abs(frequency_response(f, circuit))
    dev = np.full_like(s, np.nan)
    dev[:-1] = np.abs(np.diff(s)) / s[:-1]
    s_inf = circuit.open_circuit_gain_V_per_N
    k = linearity_onset(f, dev, threshold)
    f_lin = float(f[k]) if k >= 0 else float("nan")
    s_ref = float(s[k]) if k >= 0 else float("nan")
    return LowFreqResult(f, s, dev, 1 - s / s_inf, f_lin, s_ref, s_inf)


def asymptote_onset_Hz(circuit: SensorCircuit, threshold: float) -> float:
    """Frequency above which S(f) stays within ``threshold`` of d33/C (closed form).

    S/S_inf = x / sqrt(1 + x^2) with x = omega tau >= 1 - threshold gives
    x = (1 - t) / sqrt(1 - (1 - t)^2).
    """
    r = 1 - threshold
    return float(r / np.sqrt(1 - r * r) / (2 * np.pi * circuit.tau_s))
