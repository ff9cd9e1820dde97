"""The paper's detector: the envelope spectrum's exact BPFO bins over their local floor (Sec. IV, Fig. 10).

The chain of :mod:`piezobearing.signals.detection`: the record cut to whole
BPFO periods, band-passed (the configured fixed band or the kurtogram's),
enveloped, and the indicator I = sum_k r_k, r_k = A(k BPFO)^2 / floor_k,
k = 1..K, tested against K F_{1-pfa}(2K, 2M) (a constant false-alarm rate under
Gaussian noise). It tests the outer race only, at the kinematic BPFO without
slip: what the scorecard reproduces for Fig. 10. A cage that slips by more than
a bin loses the line; for a real machine use the ``envelope`` detector.

Evidence: one family, ``outer_race``: statistic I, its threshold, and per
harmonic a line ``kxBPFO`` whose level is 10 log10 r_k and whose threshold is
the level one r_k alone passes at the same false-alarm probability,
10 log10 F_{1-pfa}(2, 2 M_k). ``details`` is the indicator's own record
(:func:`piezobearing.signals.detection.fault_indicator`: fault_frequency_Hz,
harmonics, indicator, threshold, detected, false_alarm_probability, band_Hz,
resolution_Hz).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import fdtri

from .. import detection
from ..envelope import EnvelopeSettings
from .result import Detection, FamilyEvidence, LineEvidence, margin_dB


@dataclass(frozen=True)
class Settings:
    """The paper detector: how the band is chosen and the indicator.

    Parameters
    ----------
    envelope : EnvelopeSettings
        Band rule (fixed or kurtogram), band, kurtogram's narrowest band, filter order.
    indicator : IndicatorSettings
        Harmonics, floor half-width and guard bins, false-alarm probability.
    """

    envelope: EnvelopeSettings
    indicator: detection.IndicatorSettings

    @classmethod
    def from_config(cls, signals: dict) -> "Settings":
        """From the validated config's ``signals`` section."""
        return cls(EnvelopeSettings.from_config(signals), detection.IndicatorSettings.from_config(signals))

    def in_band(self, band_Hz: tuple[float, float]) -> "Settings":
        """The same settings with the band fixed to ``band_Hz`` [Hz]."""
        return replace(self, envelope=replace(self.envelope, band_rule="fixed", band_Hz=tuple(band_Hz)))


def line_threshold(false_alarm_probability: float, n_floor_bins: int) -> float:
    """The power ratio one exact-bin line alone passes with probability ``false_alarm_probability`` under
    noise alone, F_{1-pfa}(2, 2M) [-]."""
    return float(fdtri(2, 2 * n_floor_bins, 1.0 - false_alarm_probability))


def from_indicator(result: dict, kinematics: dict) -> Detection:
    """The :class:`Detection` of the indicator's record ``result`` (:func:`.detection.fault_indicator`)."""
    pfa = result["false_alarm_probability"]
    lines = []
    for h in result["harmonics"]:
        thr = line_threshold(pfa, h["n_floor_bins"])
        lines.append(LineEvidence(f"{h['k']}xBPFO", h["frequency_Hz"], h["ratio_dB"], 10.0 * math.log10(thr),
                                  bool(h["ratio"] > thr)))
    fam = FamilyEvidence("outer_race", result["indicator"], result["threshold"],
                         margin_dB(result["indicator"], result["threshold"]), result["detected"], tuple(lines))
    return Detection.from_families("paper", {"outer_race": fam}, "outer_race" if fam.detected else "none",
                                   tuple(result["band_Hz"]), kinematics["shaft_Hz"], pfa, result)


def detect(samples: np.ndarray, sample_rate_Hz: float, kinematics: dict, settings: Settings, reference=None) -> Detection:
    """The paper's indicator on one record (``reference`` is not used).

    Parameters
    ----------
    samples : ndarray
        The record [V] (any unit: the test is a ratio).
    sample_rate_Hz : float
        Its sampling rate [Hz].
    kinematics : dict
        Kinematic frequencies without slip [Hz] (``bpfo_Hz``, ``shaft_Hz`` read).
    settings : Settings
    """
    a = detection.analyse(samples, 1.0 / sample_rate_Hz, kinematics["bpfo_Hz"], settings.envelope, settings.indicator)
    return from_indicator(a.result, kinematics)


def detect_many(records, sample_rate_Hz: float, kinematics: dict, settings: Settings, reference=None) -> list[Detection]:
    """:func:`detect` of each record."""
    return [detect(x, sample_rate_Hz, kinematics, settings) for x in records]
