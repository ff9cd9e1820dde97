"""The detector over noise seeds: confusion matrix of the fault type, ROC curves across SNR.

Each case is one noiseless record on the DAQ clock with a known true type
(``none`` for the healthy bearing). Replicate j of a case draws its noise
from the generator ``rng(case, j)`` (the stage passes
:func:`.detection.noise_rng`, so replicate 0 is the ``noisy`` stage's record).
Every record goes through :func:`.detectors.detect_many` with the configured
method (``signals.detector.statistic``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import daq, detection, detectors
from .detectors.result import CALLS, UNKNOWN, Detection


@dataclass(frozen=True)
class Detector:
    """The configured detector: method, its settings and (baseline) the healthy reference.

    Attributes
    ----------
    method : str
        A :data:`.detectors.METHODS` entry.
    settings : object
        The method's ``Settings``.
    reference : detectors.baseline.Baseline or None
        The healthy baseline of the ``baseline`` method.
    """

    method: str
    settings: object
    reference: detectors.baseline.Baseline | None = None

    def many(self, records, dt_s: float, kinematics: dict) -> list[Detection]:
        """The detections of several records [V] at step ``dt_s`` [s], each the record's alone."""
        return detectors.detect_many(records, 1.0 / dt_s, kinematics, self.method, self.settings, self.reference)


def configured_detector(sig: dict, kinematics: dict, healthy: tuple[np.ndarray, float] | None) -> Detector:
    """The detector of ``signals`` config ``sig`` (``sig["detector"]["statistic"]``); ``healthy``: the healthy
    bearing's noiseless record on the DAQ clock (v [V], dt [s]), the reference of the ``baseline`` method."""
    method = sig["detector"]["statistic"]
    settings = detectors.settings_from_config(method, sig)
    reference = None
    if method == "baseline":
        if healthy is None:
            raise ValueError("signals.detector.statistic = baseline needs the healthy record; none was given")
        reference = detectors.baseline.Baseline.from_record(healthy[0], healthy[1], kinematics, settings)
    return Detector(method, settings, reference)


def confusion_matrix(true_types: list[str], classified: list[str], classes: tuple[str, ...] | None = None) -> dict:
    """Counts with rows the true type and columns the classified type, and the per-class rates.

    ``classes``: default, every fault type and ``none``, with ``unknown`` (a fault whose type was not called:
    an alarm, right for no true type) where some record is called so."""
    if classes is None:
        classes = tuple(c for c in CALLS if c != UNKNOWN or UNKNOWN in classified)
    idx = {c: i for i, c in enumerate(classes)}
    m = np.zeros((len(classes), len(classes)), dtype=int)
    for t, c in zip(true_types, classified, strict=True):
        m[idx[t], idx[c]] += 1
    n = m.sum(axis=1)
    correct = {c: (float(m[i, i] / n[i]) if n[i] else None) for i, c in enumerate(classes)}
    return {"classes": list(classes), "rows": "true type", "columns": "classified type", "counts": m.tolist(),
            "correct_rate": correct}


def roc_points(faulty_scores: np.ndarray, healthy_scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Detection rate against false-alarm rate over every threshold on a score [-], [-].

    Scores are e.g. statistic / threshold of a family; the curve runs from (1, 1) to (0, 0).
    """
    f, h = np.asarray(faulty_scores, float), np.asarray(healthy_scores, float)
    levels = np.concatenate([[-np.inf], np.unique(np.concatenate([f, h])), [np.inf]])
    pd_ = np.array([(f > c).mean() for c in levels])
    pfa = np.array([(h > c).mean() for c in levels])
    return pfa, pd_


def roc_auc(pfa: np.ndarray, pd_: np.ndarray) -> float:
    """Area under the ROC curve [-] (0.5: chance, 1: perfect)."""
    o = np.lexsort((pd_, pfa))
    x, y = pfa[o], pd_[o]
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def classify_seeds(records: dict, kinematics: dict, detector: Detector, noise: daq.NoiseSettings,
                   rng: Callable[[str, int], np.random.Generator], n_seeds: int) -> tuple[dict, list[dict]]:
    """Classify every case over ``n_seeds`` noise replicates.

    Parameters
    ----------
    records : dict
        case -> (true_type, noiseless voltage on the DAQ clock [V], step [s]).
    kinematics : dict
        No-slip kinematic frequencies [Hz].
    detector : Detector
    noise : NoiseSettings
        The DAQ noise.
    rng : callable
        (case, replicate) -> the replicate's generator.
    n_seeds : int

    Returns
    -------
    confusion : dict
        :func:`confusion_matrix` over all cases and seeds.
    rows : list of dict
        Per case and seed: the classification, and per family its statistic (column ``{family}_indicator``),
        threshold and detected.
    """
    rows = []
    for case, (true_type, v, dt) in records.items():
        acqs = [daq.add_noise(v, dt, noise, rng(case, j)) for j in range(n_seeds)]
        for j, (acq, d) in enumerate(zip(acqs, detector.many([a.voltage_V for a in acqs], dt, kinematics),
                                         strict=True)):
            row = {"case": case, "true_type": true_type, "seed": j, "fault_type": d.fault_type,
                   "clipped_fraction": acq.clipped_fraction}
            for t, f in d.families.items():
                row.update({f"{t}_indicator": f.statistic, f"{t}_threshold": f.threshold,
                            f"{t}_detected": f.detected})
            rows.append(row)
    cm = confusion_matrix([r["true_type"] for r in rows], [r["fault_type"] for r in rows])
    return cm, rows


def roc_over_snr(faulty: tuple[str, np.ndarray], healthy: np.ndarray, dt_s: float, kinematics: dict,
                 detector: Detector, snr_dB: list[float],
                 rng: Callable[[str, int], np.random.Generator], n_seeds: int) -> list[dict]:
    """ROC of the true type's test (score statistic / threshold) at each SNR, faulty against healthy.

    Noise is relative (``snr_dB`` over each record's own mean square), one
    shape per replicate scaled to every SNR (common random numbers).

    Returns
    -------
    list of dict
        Per SNR: snr_dB, auc, the detection and false-alarm rates at the
        configured threshold (score > 1), and the curve (pfa, pd).
    """
    true_type, vf = faulty
    shapes = {c: [rng(c, j).standard_normal(x.size) for j in range(n_seeds)]
              for c, x in (("faulty", vf), ("healthy", healthy))}
    out = []
    for s in snr_dB:
        scores = {}
        for c, x in (("faulty", vf), ("healthy", healthy)):
            sigma = detection.noise_std_for_snr(x, s)
            scores[c] = np.array([d.families[true_type].statistic / d.families[true_type].threshold
                                  for d in detector.many([x + sigma * z for z in shapes[c]], dt_s, kinematics)])
        pfa, pd_ = roc_points(scores["faulty"], scores["healthy"])
        out.append({"snr_dB": float(s), "fault_type": true_type, "auc": roc_auc(pfa, pd_),
                    "detection_rate": float(np.mean(scores["faulty"] > 1.0)),
                    "false_alarm_rate": float(np.mean(scores["healthy"] > 1.0)),
                    "pfa": pfa.tolist(), "pd": pd_.tolist()})
    return out
