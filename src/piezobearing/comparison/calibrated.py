"""The comparison's calibrated test: both sensors judged by one statistic at a false-alarm rate set on seeds.

Each seed is an independent realisation of the rig (:func:`piezobearing.comparison.rig.compare` with the
healthy bearing's floor on, ``sensor_comparison.bearing_floor``): the bearing's surfaces and unbalance phase,
the base motion and both DAQs' noise drawn anew. The statistic of a record is the envelope detector's margin
of the true fault family (its statistic over its own noise threshold, in dB): the same for both sensors. Per
sensor (:mod:`piezobearing.comparison.statistics`):

* the threshold at ``sensor_comparison.false_alarm_rate`` from the healthy seeds, and the faulty seeds' detection
  probability there with its Clopper-Pearson interval (95 %);
* the threshold at ``sensor_comparison.tail_false_alarm_rate`` from a generalized Pareto fit of the healthy
  statistic's top ``tail_fraction`` (its shape, and the Kolmogorov-Smirnov check), and the detection probability
  there;
* the ROC curve and its area;
* the detector's own calls: how often it calls the faulty seeds' type right (``type_correct_rate``), how often it
  alarms on them (any fault or ``unknown``: ``alarm_rate_faulty``) and on the healthy seeds
  (``false_alarm_rate``, in :func:`~piezobearing.comparison.rig.compare`'s summary).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..signals.detectors import is_alarm
from . import statistics

#: The confidence level of the detection probabilities' intervals.
LEVEL = 0.95


def sensor_test(healthy_dB, faulty_dB, called_faulty: list[str], fault_type: str, settings: dict) -> dict:
    """The calibrated test of one sensor (JSON-ready); ``settings``: the config's ``sensor_comparison``."""
    h, f = np.asarray(healthy_dB, dtype=float), np.asarray(faulty_dB, dtype=float)
    t05 = statistics.threshold_at(h, settings["false_alarm_rate"])
    d05 = statistics.detection(f, t05, LEVEL)
    out = {
        "n_healthy_seeds": int(h.size),
        "n_faulty_seeds": int(f.size),
        "calibrated_false_alarm_rate": settings["false_alarm_rate"],
        "calibrated_threshold_dB": t05,
        "calibrated_detection_probability": d05.probability,
        "calibrated_detection_ci_low": d05.ci_low,
        "calibrated_detection_ci_high": d05.ci_high,
        "type_correct_rate": float(np.mean([c == fault_type for c in called_faulty])),
        "alarm_rate_faulty": float(np.mean([is_alarm(c) for c in called_faulty])),
        "healthy_statistic_median_dB": float(np.median(h)),
        "faulty_statistic_median_dB": float(np.median(f)),
        "roc_auc": statistics.roc(h, f).auc,
    }
    tail = {"tail_false_alarm_rate": settings["tail_false_alarm_rate"], "tail_threshold_dB": None,
            "tail_detection_probability": None, "tail_detection_ci_low": None, "tail_detection_ci_high": None,
            "tail_shape": None, "tail_scale_dB": None, "tail_excesses": 0, "tail_ks_statistic": None,
            "tail_ks_p_value": None}
    if np.isfinite(h).sum() * settings["tail_fraction"] >= 5:
        fit = statistics.tail_threshold(h, settings["tail_false_alarm_rate"], settings["tail_fraction"])
        d01 = statistics.detection(f, fit.threshold, LEVEL)
        tail.update(tail_threshold_dB=fit.threshold, tail_detection_probability=d01.probability,
                    tail_detection_ci_low=d01.ci_low, tail_detection_ci_high=d01.ci_high, tail_shape=fit.shape,
                    tail_scale_dB=fit.scale, tail_excesses=fit.n_excesses, tail_ks_statistic=fit.ks_statistic,
                    tail_ks_p_value=fit.ks_p_value)
    return {**out, **tail}


def evaluate(result: dict, settings: dict) -> dict:
    """Per sensor, the calibrated test of :func:`~piezobearing.comparison.rig.compare`'s ``result`` (its
    per-seed margins and calls); ``settings``: the config's ``sensor_comparison``."""
    out = {}
    for s, r in result["sensors"].items():
        out[s] = sensor_test(r["healthy_margin_dB_per_seed"], r["margin_dB_per_seed"], r["called_faulty"],
                             result["fault_type"], settings)
    return out


#: The detection probability at the calibrated threshold a width must reach to count as detected.
DETECTED_AT = 0.5
#: The columns that make a width sweep: every case of the same sensor, fault, speed, level, mounting, roughness.
SWEEP_KEYS = ("sensor", "fault_type", "shaft_speed_rpm", "disturbance_level", "accelerometer_position",
              "roughness_rms_m")


def smallest_detected_width(df: pd.DataFrame) -> pd.Series:
    """Per row of the study's table, the smallest defect width of its sweep (the rows alike in
    :data:`SWEEP_KEYS`) whose calibrated detection probability reaches :data:`DETECTED_AT` [m]; NaN where no
    width of the sweep does."""
    keys = [k for k in SWEEP_KEYS if k in df]
    hit = df["defect_width_m"].where(df["calibrated_detection_probability"] >= DETECTED_AT)
    return hit.groupby([df[k] for k in keys]).transform("min")
