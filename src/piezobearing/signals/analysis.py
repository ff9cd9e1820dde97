"""Result tables of the fault detection (Sec. IV; Fig. 10 and the SNR study): the envelope analysis of one
noisy record beside its noiseless one, and the detection statistics of the SNR sweep.

Pure functions of arrays and the validated ``signals`` config section; the stages in
:mod:`piezobearing.stages.signals` read and write the files.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from . import detection
from .envelope import EnvelopeSettings, amplitude_spectrum, band_power_V2, envelope_spectrum


def envelope_analysis(y: np.ndarray, v: np.ndarray, dt: float, f0: float, s: dict) -> tuple[pd.DataFrame, dict]:
    """Band (kurtogram or fixed) and envelope spectrum of the noisy record ``y`` [V], and of the noiseless ``v``
    [V] in the same band, at step ``dt`` [s] against the BPFO ``f0`` [Hz].

    Returns the spectrum table (frequency_Hz, amplitude_V, noiseless_amplitude_V) and the record (band,
    resolution, in-band SNR, the naive test on the raw spectrum, the kurtogram).
    """
    es = EnvelopeSettings.from_config(s)
    a = detection.analyse(y, dt, f0, es, detection.IndicatorSettings.from_config(s))
    spec = a.spectrum
    n = spec.n_samples
    clean = envelope_spectrum(v[:n], dt, spec.band_Hz, es.filter_order)
    p_clean = band_power_V2(v[:n], dt, spec.band_Hz, es.filter_order)
    p_noise = band_power_V2(y[:n] - v[:n], dt, spec.band_Hz, es.filter_order)
    naive = detection.fault_indicator(amplitude_spectrum(y[:n], dt), f0, detection.IndicatorSettings.from_config(s))
    table = pd.DataFrame(
        {"frequency_Hz": spec.frequency_Hz, "amplitude_V": spec.amplitude_V,
         "noiseless_amplitude_V": clean.amplitude_V}
    )
    kg = a.kurtogram
    record = {
        "band_Hz": list(spec.band_Hz),
        "band_rule": s["band_rule"],
        "n_samples": spec.n_samples,
        "n_periods": int(round(spec.n_samples * dt * f0)),
        "duration_s": spec.n_samples * dt,
        "resolution_Hz": spec.resolution_Hz,
        "bpfo_Hz": f0,
        "bpfo_bin_offset": float(f0 / spec.resolution_Hz - round(f0 / spec.resolution_Hz)),
        "noiseless_in_band_power_V2": p_clean,
        "noise_in_band_power_V2": p_noise,
        "in_band_snr_dB": float(10 * np.log10(p_clean / p_noise)),
        "raw_spectrum_test": {k: naive[k] for k in ("indicator", "threshold", "detected")},
        "kurtogram": None if kg is None else {
            "low_Hz": kg.low_Hz.tolist(), "high_Hz": kg.high_Hz.tolist(), "kurtosis": kg.kurtosis.tolist()
        },
    }
    return table, record


INDICATOR_DEFINITION = (
    "r_k = A(k BPFO)^2 / mean A^2 of the local floor (bins within floor_halfwidth BPFO of k BPFO, guard bins "
    "around every BPFO harmonic left out); indicator = sum_k r_k, k = 1..n_harmonics; threshold = "
    "n_harmonics F_{1-pfa}(2 n_harmonics, 2 M), M = smallest floor count (CFAR under Gaussian noise); "
    "the 'noiseless' entries apply the same test to the noiseless record in the same band (reference only); "
    "in_band_snr_dB: band-passed noiseless power over band-passed noise power; raw_spectrum_test: the same "
    "test on the voltage's own amplitude spectrum (no band-pass, no envelope), the naive check"
)

SNR_STUDY_DEFINITION = (
    "detection_limit_dB: lowest grid SNR from which upward the detection rate stays >= required_detection_rate; "
    "snr_50pct_dB: SNR where the rate last rises through 0.5 (linear interpolation); "
    "first_snr_rate_above_dB: lowest grid SNR with a rate above 1 - required_detection_rate (for the healthy "
    "bearing: where false alarms begin); top level: the configured band rule, other_band_rule: the other one "
    "on the same noise records"
)


def snr_grid(s: dict) -> list[float]:
    """The SNR grid of the study [dB]: study_snr_min_dB..study_snr_max_dB by study_snr_step_dB, plus snr_dB."""
    lo, hi, step = s["study_snr_min_dB"], s["study_snr_max_dB"], s["study_snr_step_dB"]
    if hi < lo:
        raise ValueError("signals.study_snr_max_dB must not be below signals.study_snr_min_dB")
    grid = list(np.round(np.arange(lo, hi + step / 2, step), 9))
    if not any(abs(g - s["snr_dB"]) < 1e-9 for g in grid):
        grid = sorted(grid + [float(s["snr_dB"])])  # the configured SNR is always on the grid
    return [float(g) for g in grid]


def band_rules(s: dict) -> list[str]:
    """The configured band rule first, then the other one (compared on the same noise records)."""
    return [s["band_rule"]] + [r for r in ("fixed", "kurtogram") if r != s["band_rule"]]


def snr_summary(df: pd.DataFrame) -> pd.DataFrame:
    """Detection rate and indicator statistics per band rule, case and SNR of the sweep's rows."""
    return (
        df.groupby(["band_rule", "case", "snr_dB"], sort=False)
        .agg(detection_rate=("detected", "mean"), n_seeds=("detected", "size"),
             indicator_median=("indicator", "median"), indicator_min=("indicator", "min"),
             indicator_max=("indicator", "max"), threshold=("threshold", "min"))
        .reset_index()
    )


def snr_study_record(df: pd.DataFrame, summ: pd.DataFrame, cases, grid: list[float], s: dict) -> dict:
    """Detection rate at the configured SNR, detection limit, 50% SNR, onset of false alarms, per rule and case."""
    need = s["study_required_detection_rate"]
    out = {"snr_grid_dB": grid, "n_seeds": s["study_n_seeds"], "required_detection_rate": need,
           "snr_dB": s["snr_dB"], "band_rule": s["band_rule"]}
    for rule in band_rules(s):
        res = {}
        for case in cases:
            sel = (df["band_rule"] == rule) & (df["case"] == case)
            at = sel & np.isclose(df["snr_dB"], s["snr_dB"])
            c = summ[(summ["band_rule"] == rule) & (summ["case"] == case)]
            snr, rate = c["snr_dB"].to_numpy(), c["detection_rate"].to_numpy()
            res[case] = {
                "detection_rate_at_snr": float(df[at]["detected"].mean()),
                "detected_all_seeds_at_snr": bool(df[at]["detected"].all()),
                "detected_no_seed_at_snr": bool(not df[at]["detected"].any()),
                "detection_limit_dB": detection.detection_limit_dB(snr, rate, need),
                "snr_50pct_dB": crossing(snr, rate, 0.5),
                "first_snr_rate_above_dB": first_above(snr, rate, 1 - need),
                "max_rate": float(rate.max()),
            }
        if rule == s["band_rule"]:
            out.update(res)
        else:
            out["other_band_rule"] = {"band_rule": rule, **res}
    out["definition"] = SNR_STUDY_DEFINITION
    return out


def first_above(x: np.ndarray, y: np.ndarray, level: float) -> float:
    """Lowest x with y > level (NaN if none)."""
    hit = np.asarray(x)[np.asarray(y) > level]
    return float(hit.min()) if hit.size else float("nan")


def crossing(x: np.ndarray, y: np.ndarray, level: float) -> float:
    """Last upward crossing of ``level`` by y(x), linearly interpolated (NaN if none)."""
    o = np.argsort(x)
    x, y = x[o], y[o]
    if y[-1] < level:
        return float("nan")
    if y[0] >= level:
        return float(x[0])
    i = int(np.flatnonzero(y < level)[-1])
    return float(x[i] + (level - y[i]) * (x[i + 1] - x[i]) / (y[i + 1] - y[i]))
