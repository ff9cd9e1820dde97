"""The one result type of every fault detector: a :class:`Detection` with per-family evidence.

A detector tests fault *families* (outer race, inner race, rolling element),
each by one statistic against a threshold set at a false-alarm probability,
and calls the record one of :data:`FAULT_TYPES`, ``"unknown"`` (a fault whose type the evidence does not
settle: an alarm all the same) or ``"none"``. What each
detector's statistic is, and how it sets its threshold, is the detector's own
(:mod:`.paper`, :mod:`.envelope`, :mod:`.baseline`); the shape of the answer is
the same for all, so that a simulated record in the workflow and a user's
recording are judged and reported alike.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

#: The fault families a detector calls; a call is one of these, ``"unknown"`` or ``"none"``.
FAULT_TYPES = ("outer_race", "inner_race", "rolling_element")
#: The call of a fault whose type the families' margins do not separate: an alarm, of no type.
UNKNOWN = "unknown"
#: The calls a detector can make.
CALLS = FAULT_TYPES + (UNKNOWN, "none")
#: The kinematic frequencies a detector reads [Hz] (``kinematics.json``'s keys).
KINEMATIC_KEYS = ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")


def is_alarm(call: str) -> bool:
    """Whether a call is an alarm: any fault, of a type or ``unknown`` (every call but ``none``)."""
    return call != "none"


def margin_dB(statistic: float, threshold: float) -> float:
    """10 log10(statistic / threshold) [dB]: above 0 dB the family is detected (-inf for a zero statistic)."""
    if statistic <= 0.0:
        return -math.inf
    return 10.0 * math.log10(statistic / threshold)


@dataclass(frozen=True)
class LineEvidence:
    """One harmonic or sideband of one family.

    Attributes
    ----------
    label : str
        The line, e.g. ``"2xBPFO"``, ``"1xBPFI-1xfr"``.
    frequency_Hz : float
        Where it was found (the peak of its search window, or the exact bin) [Hz].
    level_dB : float
        Its power over the local floor [dB].
    threshold_dB : float
        The level a line alone must pass at the call's false-alarm probability [dB].
    above : bool
        level_dB > threshold_dB.
    """

    label: str
    frequency_Hz: float
    level_dB: float
    threshold_dB: float
    above: bool

    def to_dict(self) -> dict:
        return {"label": self.label, "frequency_Hz": self.frequency_Hz, "level_dB": self.level_dB,
                "threshold_dB": self.threshold_dB, "above": self.above}


@dataclass(frozen=True)
class FamilyEvidence:
    """The test of one fault family.

    Attributes
    ----------
    family : str
        A :data:`FAULT_TYPES` entry.
    statistic : float
        The detector's test statistic for this family [-].
    threshold : float
        Its threshold at the family's false-alarm probability [-].
    margin_dB : float
        10 log10(statistic / threshold) [dB] (:func:`margin_dB`).
    detected : bool
        The detector's decision for the family: statistic > threshold, and where the detector asks more
        (the envelope detector: enough lines above their own thresholds) that too, documented in its module.
    lines : tuple of LineEvidence
        The lines the statistic is made of, where the detector reads lines (empty where it tests a waveform).
    """

    family: str
    statistic: float
    threshold: float
    margin_dB: float
    detected: bool
    lines: tuple[LineEvidence, ...] = ()

    def to_dict(self) -> dict:
        return {"family": self.family, "statistic": self.statistic, "threshold": self.threshold,
                "margin_dB": self.margin_dB, "detected": self.detected,
                "lines": [ln.to_dict() for ln in self.lines]}


@dataclass(frozen=True)
class Detection:
    """What one detector found in one record.

    Attributes
    ----------
    method : str
        ``"paper"``, ``"envelope"`` or ``"baseline"``.
    fault_type : str
        A :data:`FAULT_TYPES` entry, ``"unknown"`` (a fault, its type not settled) or ``"none"``.
    families : dict
        Family name -> :class:`FamilyEvidence`, for every family tested.
    band_Hz : tuple of float or None
        The demodulation band [low, high] [Hz]; None for a detector that does not demodulate a band.
    shaft_rate_Hz : float
        The shaft rate the fault frequencies were computed from [Hz].
    false_alarm_probability : float
        Probability that a record without a fault is called any fault, at the thresholds used [-].
    margin_dB : float
        The called family's margin, or the largest margin when the call is ``"none"`` or ``"unknown"`` [dB].
    details : dict
        The detector's own numbers (JSON-ready), documented in its module.
    """

    method: str
    fault_type: str
    families: dict[str, FamilyEvidence]
    band_Hz: tuple[float, float] | None
    shaft_rate_Hz: float
    false_alarm_probability: float
    margin_dB: float
    details: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.fault_type not in CALLS:
            raise ValueError(f"fault_type '{self.fault_type}' is none of {', '.join(CALLS)}")

    @classmethod
    def from_families(cls, method: str, families: dict[str, FamilyEvidence], fault_type: str,
                      band_Hz: tuple[float, float] | None, shaft_rate_Hz: float, false_alarm_probability: float,
                      details: dict) -> "Detection":
        """A detection whose ``margin_dB`` is the called family's (the largest of all when ``"none"`` or
        ``"unknown"``)."""
        if fault_type in families:
            margin = families[fault_type].margin_dB
        else:
            margin = max((f.margin_dB for f in families.values()), default=-math.inf)
        band = None if band_Hz is None else (float(band_Hz[0]), float(band_Hz[1]))
        return cls(method, fault_type, dict(families), band, float(shaft_rate_Hz), float(false_alarm_probability),
                   float(margin), details)

    def to_dict(self) -> dict:
        """JSON-ready: plain dicts, lists, strings, floats and bools (inf stays a float: the workflow's JSON
        writer makes it null)."""
        return {"method": self.method, "fault_type": self.fault_type,
                "families": {k: f.to_dict() for k, f in self.families.items()},
                "band_Hz": None if self.band_Hz is None else list(self.band_Hz),
                "shaft_rate_Hz": self.shaft_rate_Hz, "false_alarm_probability": self.false_alarm_probability,
                "margin_dB": self.margin_dB, "details": self.details}

    @classmethod
    def from_dict(cls, d: Mapping) -> "Detection":
        """The detection :meth:`to_dict` wrote (a JSON round trip gives an equal detection)."""
        fams = {k: FamilyEvidence(f["family"], f["statistic"], f["threshold"], _float(f["margin_dB"]),
                                  f["detected"], tuple(LineEvidence(**ln) for ln in f["lines"]))
                for k, f in d["families"].items()}
        band = None if d["band_Hz"] is None else tuple(d["band_Hz"])
        return cls(d["method"], d["fault_type"], fams, band, d["shaft_rate_Hz"], d["false_alarm_probability"],
                   _float(d["margin_dB"]), d["details"])


def _float(x) -> float:
    """A margin read back from JSON, where the writer made -inf null."""
    return -math.inf if x is None else float(x)


def kinematics_dict(kinematics) -> dict:
    """The kinematic frequencies [Hz] of a bearing as the detectors read them (:data:`KINEMATIC_KEYS`).

    ``kinematics``: a mapping with those keys (``kinematics.json``), or an object with those attributes
    (:class:`piezobearing.bearing.kinematics.Kinematics`, :class:`piezobearing.bearing.lpm.KinematicFrequencies`).
    """
    if isinstance(kinematics, Mapping):
        missing = [k for k in KINEMATIC_KEYS if k not in kinematics]
        if missing:
            raise ValueError(f"kinematics: key(s) {', '.join(missing)} missing; give {', '.join(KINEMATIC_KEYS)} [Hz]")
        return {k: float(kinematics[k]) for k in KINEMATIC_KEYS}
    missing = [k for k in KINEMATIC_KEYS if not hasattr(kinematics, k)]
    if missing:
        raise ValueError(f"kinematics: {type(kinematics).__name__} has no {', '.join(missing)}; give a bearing's "
                         "Kinematics or a dict of " + ", ".join(KINEMATIC_KEYS) + " [Hz]")
    return {k: float(getattr(kinematics, k)) for k in KINEMATIC_KEYS}
