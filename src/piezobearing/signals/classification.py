"""The detector over noise seeds: confusion matrix of the fault type, ROC curves across SNR.

Each case is one noiseless record on the DAQ clock with a known true type
(``none`` for the healthy bearing). Replicate j of a case draws its noise
from the generator ``rng(case, j)`` (the stage passes
:func:`..detection.noise_rng`, so replicate 0 is the ``noisy`` stage's
record).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import baseline as B
from . import clipped as CL
from . import daq
from . import detection as det
from . import detector as D

#: signals.detector.statistic: the detectors one record can go through.
STATISTICS = ("baseline", "envelope")


@dataclass(frozen=True)
class Analyser:
    """One record through the configured detector (``signals.detector.statistic``).

    ``envelope``: the search detector on the band's envelope spectrum
    (:func:`.detector.analyse_record`); ``baseline``: the roller-passage part
    removed and the record tested against the healthy ``baseline``
    (:func:`.clipped.detect`: :func:`.baseline.detect`, or on a record the ADC clipped, against the clipped
    healthy record's expectation).
    """

    statistic: str
    envelope_settings: det.EnvelopeSettings
    settings: D.DetectorSettings
    baseline_settings: B.BaselineSettings
    baseline: B.Baseline | None = None
    end_codes: tuple[float, float, float] | None = None  # the DAQ's ADC end codes (:func:`.daq.end_codes_V`)

    def __call__(self, x: np.ndarray, dt_s: float, kinematics: dict):
        """The detection (``fault_type``, ``per_type``, ``to_dict()``) of record ``x`` [V] at step ``dt_s`` [s]."""
        if self.statistic == "envelope":
            return D.analyse_record(x, dt_s, kinematics, self.envelope_settings, self.settings)[1]
        if self.baseline is None:
            raise ValueError("signals.detector.statistic = baseline needs the healthy record; none was given")
        return self.many([x], dt_s, kinematics)[0]

    def many(self, records, dt_s: float, kinematics: dict) -> list:
        """The detections of several records [V] at step ``dt_s`` [s], each the record's alone (the baseline
        detector's outer-race searches of all records run together: :func:`.clipped.detect_many`)."""
        if self.statistic == "envelope":
            return [D.analyse_record(x, dt_s, kinematics, self.envelope_settings, self.settings)[1] for x in records]
        if self.baseline is None:
            raise ValueError("signals.detector.statistic = baseline needs the healthy record; none was given")
        return CL.detect_many(records, dt_s, kinematics, self.baseline, self.baseline_settings, self.end_codes)


def analyser(sig: dict, kinematics: dict, healthy: tuple[np.ndarray, float] | None) -> Analyser:
    """The detector of ``signals`` config ``sig``; ``healthy``: the healthy bearing's noiseless record on the
    DAQ clock (v [V], dt [s]), the baseline of statistic ``baseline``."""
    stat = sig["detector"].get("statistic", "envelope")
    if stat not in STATISTICS:
        raise ValueError(f"signals.detector.statistic: unknown '{stat}'; use {' or '.join(STATISTICS)}")
    bs = B.BaselineSettings.from_config(sig)
    base = None
    if stat == "baseline" and healthy is not None:
        base = B.Baseline.from_record(healthy[0], healthy[1], kinematics, bs)
    ends = daq.end_codes_V(daq.NoiseSettings.from_config(sig)) if "noise" in sig else None
    return Analyser(stat, det.EnvelopeSettings.from_config(sig), D.DetectorSettings.from_config(sig), bs, base,
                    ends)


def classify_seeds(records: dict, kinematics: dict, analyse: Analyser, noise: daq.NoiseSettings,
                   rng: Callable[[str, int], np.random.Generator], n_seeds: int) -> tuple[dict, list[dict]]:
    """Classify every case over ``n_seeds`` noise replicates.

    Parameters
    ----------
    records : dict
        case -> (true_type, noiseless voltage on the DAQ clock [V], step [s]).
    kinematics : dict
        No-slip kinematic frequencies [Hz].
    analyse : Analyser
        The detector.
    noise : NoiseSettings
        The DAQ noise.
    rng : callable
        (case, replicate) -> the replicate's generator.
    n_seeds : int

    Returns
    -------
    confusion : dict
        :func:`.detector.confusion_matrix` over all cases and seeds.
    rows : list of dict
        Per case and seed: the classification, and per type indicator, threshold, detected.
    """
    rows = []
    for case, (true_type, v, dt) in records.items():
        acqs = [daq.add_noise(v, dt, noise, rng(case, j)) for j in range(n_seeds)]
        for j, (acq, d) in enumerate(zip(acqs, analyse.many([a.voltage_V for a in acqs], dt, kinematics),
                                         strict=True)):
            row = {"case": case, "true_type": true_type, "seed": j, "fault_type": d.fault_type,
                   "clipped_fraction": acq.clipped_fraction}
            for t, r in d.per_type.items():
                row.update({f"{t}_indicator": r["indicator"], f"{t}_threshold": r["threshold"],
                            f"{t}_detected": r["detected"]})
            rows.append(row)
    cm = D.confusion_matrix([r["true_type"] for r in rows], [r["fault_type"] for r in rows])
    return cm, rows


def roc_over_snr(faulty: tuple[str, np.ndarray], healthy: np.ndarray, dt_s: float, kinematics: dict,
                 analyse: Analyser, snr_dB: list[float],
                 rng: Callable[[str, int], np.random.Generator], n_seeds: int) -> list[dict]:
    """ROC of the true type's test (score I / threshold) at each SNR, faulty against healthy.

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
            sig = float(np.sqrt(np.mean(x * x) / 10.0 ** (s / 10.0)))
            scores[c] = np.array([d.per_type[true_type]["margin"]
                                  for d in analyse.many([x + sig * z for z in shapes[c]], dt_s, kinematics)])
        pfa, pd_ = D.roc_points(scores["faulty"], scores["healthy"])
        out.append({"snr_dB": float(s), "fault_type": true_type, "auc": D.roc_auc(pfa, pd_),
                    "detection_rate": float(np.mean(scores["faulty"] > 1.0)),
                    "false_alarm_rate": float(np.mean(scores["healthy"] > 1.0)),
                    "pfa": pfa.tolist(), "pd": pd_.tolist()})
    return out
