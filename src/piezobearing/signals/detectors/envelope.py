"""The envelope detector: every fault family's lines searched in the envelope spectrum of a band.

The record's band (the configured fixed band or the kurtogram's), its
Hann-windowed envelope spectrum, and per family the search of
:mod:`piezobearing.signals.detector`: each line k x carrier + m x sideband
spacing searched over the bins its frequency covers for cage slip in
[0, slip_max], its largest power ratio over the harmonic's local floor; the
family's indicator is the sum of its lines' ratios, tested at
alpha = pfa / n_families against its distribution under noise alone
(computed, not bounded); several detected families are told apart by their
own lines. The whole record is used: with slip there is no exact fault
period to cut it to.

Evidence: per family statistic = the indicator, threshold = its
(1 - alpha) quantile; per line a :class:`~.result.LineEvidence` whose level is
10 log10 of its ratio and whose threshold is the level its window's largest
ratio passes with probability alpha under noise alone
(:func:`..detector.window_threshold`). ``details``: ``per_type`` (per family
indicator, threshold, detected, p_value, n_lines, own_lines, margin) and
``lines`` (per line its band, bins, ratio, peak and floor).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from .. import detection, detector
from .result import Detection, FamilyEvidence, LineEvidence, margin_dB

#: The carrier and sideband names of each family's line labels.
_CARRIER = {"outer_race": "BPFO", "inner_race": "BPFI", "rolling_element": "2BSF", "cage": "FTF"}
_SIDEBAND = {"inner_race": "fr", "rolling_element": "FTF"}


@dataclass(frozen=True)
class Settings:
    """The envelope detector: the band and the search.

    Parameters
    ----------
    envelope : EnvelopeSettings
        Band rule (fixed or kurtogram), band, kurtogram's narrowest band, filter order.
    search : DetectorSettings
        Harmonics, sidebands, slip range, floors, window, false-alarm probability, families tested.
    """

    envelope: detection.EnvelopeSettings
    search: detector.DetectorSettings

    @classmethod
    def from_config(cls, signals: dict) -> "Settings":
        """From the validated config's ``signals`` section."""
        return cls(detection.EnvelopeSettings.from_config(signals), detector.DetectorSettings.from_config(signals))

    def in_band(self, band_Hz: tuple[float, float]) -> "Settings":
        """The same settings with the band fixed to ``band_Hz`` [Hz]."""
        return replace(self, envelope=replace(self.envelope, band_rule="fixed", band_Hz=tuple(band_Hz)))


def line_label(line) -> str:
    """``"2xBPFO"``, ``"1xBPFI-1xfr"``: a :class:`..fault_bands.FaultLine`'s name."""
    label = f"{line.harmonic}x{_CARRIER[line.fault_type]}"
    if line.sideband:
        label += f"{line.sideband:+d}x{_SIDEBAND[line.fault_type]}"
    return label


@lru_cache(maxsize=1024)
def _line_threshold(alpha: float, n_bins: int, n_floor_bins: float) -> float:
    return detector.window_threshold(alpha, n_bins, n_floor_bins)


def to_detection(found: detector.Detection, spec: detection.EnvelopeSpectrum, kinematics: dict,
                 settings: Settings) -> Detection:
    """The :class:`Detection` of the search detector's result ``found`` in the spectrum ``spec``."""
    st = settings.search
    inflation = detector.WINDOWS[st.window]
    families = {}
    for t, p in found.per_type.items():
        lines = []
        for r in found.lines[t]:
            thr = _line_threshold(st.alpha_per_type, int(r.bins.size), round(r.n_floor_bins / inflation, 6))
            lines.append(LineEvidence(line_label(r.line), r.peak_frequency_Hz,
                                      10.0 * math.log10(r.ratio) if r.ratio > 0 else -math.inf,
                                      10.0 * math.log10(thr), bool(r.ratio > thr)))
        families[t] = FamilyEvidence(t, float(p["indicator"]), float(p["threshold"]),
                                     margin_dB(p["indicator"], p["threshold"]), p["detected"], tuple(lines))
    d = found.to_dict()
    return Detection.from_families("envelope", families, found.fault_type, spec.band_Hz, kinematics["shaft_Hz"],
                                   st.false_alarm_probability, {"per_type": d["per_type"], "lines": d["lines"]})


def detect(samples: np.ndarray, rate_Hz: float, kinematics: dict, settings: Settings, reference=None) -> Detection:
    """Every family of ``settings`` searched in the record's envelope spectrum (``reference`` is not used).

    Parameters
    ----------
    samples : ndarray
        The record [V] (any unit: the tests are ratios).
    rate_Hz : float
        Its sampling rate [Hz].
    kinematics : dict
        Kinematic frequencies without slip [Hz].
    settings : Settings
    """
    spec, found = detector.analyse_record(samples, 1.0 / rate_Hz, kinematics, settings.envelope, settings.search)
    return to_detection(found, spec, kinematics, settings)


def detect_many(records, rate_Hz: float, kinematics: dict, settings: Settings, reference=None) -> list[Detection]:
    """:func:`detect` of each record."""
    return [detect(x, rate_Hz, kinematics, settings) for x in records]
