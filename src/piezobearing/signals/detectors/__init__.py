"""Fault detectors behind one interface: samples, a rate and a bearing's kinematics in, a :class:`Detection` out.

>>> detection = detect(samples, sample_rate_Hz, kinematics, "envelope")            # doctest: +SKIP
>>> detection.fault_type, detection.families["outer_race"].margin_dB          # doctest: +SKIP

Three methods (:data:`METHODS`), each a module with a frozen ``Settings``
(``Settings.from_config(config["signals"])``), ``detect`` and ``detect_many``:

``paper`` (:mod:`.paper`)
    The paper's exact-bin indicator at BPFO in a band's envelope spectrum: the
    outer race only, no slip. What the scorecard reproduces for Fig. 10.
``envelope`` (:mod:`.envelope`)
    Every family's harmonics and sidebands searched over a slip range in a
    band's envelope spectrum, with a search-corrected threshold. Needs nothing
    but the record and the bearing.
``baseline`` (:mod:`.baseline`)
    The roller-passage part removed and the record tested against a healthy
    reference (the model's, or a recording in good order); clipped ADC records
    handled inside. For this project's sensor, where the roller passage
    dominates.

``kinematics``: a bearing's :class:`piezobearing.bearing.kinematics.Kinematics`,
or the dict the workflow writes to ``kinematics.json`` (keys ``shaft_Hz``,
``ftf_Hz``, ``bpfo_Hz``, ``bpfi_Hz``, ``bsf_Hz``, no slip) [Hz]. The default
method is the config's ``signals.detector.statistic``; :func:`settings_from_config`
builds a method's settings from a config.
"""

from __future__ import annotations

from ... import config
from . import envelope, paper
from .result import (
    CALLS,
    FAULT_TYPES,
    KINEMATIC_KEYS,
    UNKNOWN,
    Detection,
    FamilyEvidence,
    LineEvidence,
    is_alarm,
    kinematics_dict,
    margin_dB,
)

__all__ = ["CALLS", "FAULT_TYPES", "KINEMATIC_KEYS", "METHODS", "UNKNOWN", "Detection", "FamilyEvidence",
           "LineEvidence", "detect", "detect_many", "is_alarm", "kinematics_dict", "margin_dB", "settings_from_config"]

#: The detectors by name.
METHODS = ("paper", "envelope", "baseline")


def __getattr__(name: str):
    # The baseline detector is loaded on first use (``detectors.baseline``): its scipy.optimize costs about
    # 0.2 s of import, which a detection with the envelope detector (``piezobearing detect``) does not need.
    # (An absolute import: ``from . import baseline`` would ask this very ``__getattr__`` first.)
    if name == "baseline":
        import piezobearing.signals.detectors.baseline as baseline

        return baseline
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _module(method: str):
    if method not in METHODS:
        raise ValueError(f"detector method '{method}' unknown; use one of {', '.join(METHODS)}")
    return envelope if method == "envelope" else paper if method == "paper" else __getattr__(method)


def settings_from_config(method: str, signals: dict):
    """The ``method``'s settings from a validated config's ``signals`` section."""
    return _module(method).Settings.from_config(signals)


def _settings(method: str, settings):
    if settings is not None:
        if not isinstance(settings, _module(method).Settings):
            raise TypeError(f"settings for the {method} detector must be piezobearing.signals.detectors."
                            f"{method}.Settings, not {type(settings).__name__}")
        return settings
    return settings_from_config(method, config.load()["signals"])


def detect(samples, sample_rate_Hz: float, kinematics, method: str, settings=None, reference=None) -> Detection:
    """Detect a bearing fault in one record.

    Parameters
    ----------
    samples : array_like
        The record, one channel [V] (or any unit: every test is a ratio).
    sample_rate_Hz : float
        Its sampling rate [Hz].
    kinematics : Kinematics or dict
        The bearing's kinematic frequencies at its shaft speed, without slip [Hz].
    method : str
        ``"paper"``, ``"envelope"`` or ``"baseline"`` (:data:`METHODS`).
    settings : optional
        The method's ``Settings``; None: from the package's default config.
    reference : array_like or baseline.Baseline, optional
        The healthy record [V] at ``sample_rate_Hz`` (or its :class:`.baseline.Baseline`); the baseline method's,
        not read by the others.

    Returns
    -------
    Detection
    """
    return detect_many([samples], sample_rate_Hz, kinematics, method, settings, reference)[0]


def detect_many(records, sample_rate_Hz: float, kinematics, method: str, settings=None, reference=None) -> list[Detection]:
    """:func:`detect` of each record (a sequence of arrays, or the rows of an array), all at ``sample_rate_Hz``; each
    detection is the record's alone (the baseline method runs its searches of all records together)."""
    if not sample_rate_Hz > 0:
        raise ValueError(f"sample_rate_Hz = {sample_rate_Hz!r}: give the record's sampling rate in Hz (> 0)")
    module = _module(method)
    return module.detect_many(records, float(sample_rate_Hz), kinematics_dict(kinematics), _settings(method, settings),
                              reference)
