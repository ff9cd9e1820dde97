"""The effect catalogue: physical effects the RC baseline leaves out.

Each effect is one module defining ``EFFECT``, an instance of a subclass of
:class:`~piezobearing.diagnosis.calibration.effects.base.Effect`, registered below under a stable
identifier. Adding an effect is adding one module and one entry in
``_MODULES`` (or calling :func:`register` at run time). Parameter names carry
a unit suffix from :data:`piezobearing.fitting.units.UNITS` and are unique
across the catalogue.

=====================  ==========================================================
identifier             what it models
=====================  ==========================================================
``channel_delay``      time offset between the force and voltage acquisitions
``ac_coupling``        first-order high-pass of an AC-coupled DAQ input
``reference_lag``      first-order lag of the reference force sensor
``d33_nonlinearity``   stress-dependent charge constant q = d33 (F + beta F^2)
``mains_pickup``       50/60 Hz interference and its odd harmonics
``baseline_drift``     slow additive drift (pyroelectric, thermal, offset)
``extra_capacitance``  capacitance across the electrodes beyond Cp + cable
``d33_scale``          d33 off the datasheet by a factor (same record as extra C)
``clock_drift``        sample-clock rate difference force/voltage (ppm)
``sensitivity_drift``  gain changing along the record
=====================  ==========================================================
"""

from __future__ import annotations

from ....fitting.params import Param
from ...effect import Catalogue
from .base import Effect, EffectError, ForceRecord, StartContext

#: The calibration subject's catalogue (an engine :class:`~piezobearing.diagnosis.effect.Catalogue`).
CATALOGUE = Catalogue("calibration")


def register(effect: Effect) -> Effect:
    """Add an effect to the catalogue under ``effect.name`` (the name must be new)."""
    return CATALOGUE.register(effect)


def unregister(name: str) -> None:
    """Remove an effect (for tests that register a temporary one)."""
    CATALOGUE.unregister(name)


def resolve(names, key: str = "model.effects") -> list[Effect]:
    """Effects for identifiers; an unknown or repeated name raises a one-line EffectError naming ``key``."""
    return CATALOGUE.resolve(names, key)


from . import (  # noqa: E402  (the modules import .base, registered in this order)
    ac_coupling,
    baseline_drift,
    channel_delay,
    clock_drift,
    d33_nonlinearity,
    d33_scale,
    extra_capacitance,
    mains_pickup,
    reference_lag,
    sensitivity_drift,
)

_MODULES = (
    channel_delay,
    ac_coupling,
    reference_lag,
    d33_nonlinearity,
    mains_pickup,
    baseline_drift,
    extra_capacitance,
    d33_scale,
    clock_drift,
    sensitivity_drift,
)
for _m in _MODULES:
    register(_m.EFFECT)

__all__ = [
    "CATALOGUE",
    "Effect",
    "EffectError",
    "Param",
    "ForceRecord",
    "StartContext",
    "register",
    "resolve",
    "unregister",
]
