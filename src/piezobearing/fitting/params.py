"""The one parameter class of every diagnosis model, effect and fit.

A :class:`Param` is a named, bounded quantity with its unit in its name (a
suffix from :mod:`piezobearing.fitting.units`). A forward model or an
effect declares its parameters with the value that leaves the model neutral
(or its nominal start); the fit (:mod:`piezobearing.fitting.least_squares`)
receives copies with start values (:meth:`Param.with_value`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .units import SUFFIXES


class ParamError(ValueError):
    """A parameter declared without a unit suffix, or with bounds that do not hold its value."""


@dataclass(frozen=True)
class Param:
    """A model parameter.

    Parameters
    ----------
    name : str
        Identifier with a unit suffix from :data:`~piezobearing.fitting.units.UNITS`,
        e.g. ``resistance_ohm``; unique within a subject's model and catalogue.
    value : float
        Start (or fixed) value; in a declaration, the value that switches an
        effect off (its neutral default) [unit of name].
    lower, upper : float
        Bounds [unit of name].
    log : bool
        Fit log10(value) instead of the value (for quantities spanning decades; requires lower > 0).
    vary : bool
        Whether the fit may change it.
    scale : float
        Typical magnitude [unit of name] (linear parameters only): the fit
        works on value / scale, so that finite-difference steps suit
        quantities such as 100 pF or 10 ms.
    description : str
        One line: what it is, with its unit.
    """

    name: str
    value: float
    lower: float = -np.inf
    upper: float = np.inf
    log: bool = False
    vary: bool = True
    scale: float = 1.0
    description: str = ""

    def __post_init__(self) -> None:
        if not self.name.endswith(SUFFIXES):
            raise ParamError(
                f"parameter '{self.name}': its name must end with a unit suffix ({', '.join(SUFFIXES)}); "
                "add the unit to piezobearing.fitting.units.UNITS if it is new"
            )
        if self.log and not self.lower > 0:
            raise ParamError(f"parameter '{self.name}': a log-scale parameter needs lower > 0")

    @property
    def default(self) -> float:
        """The declared value (the neutral default of an effect's parameter) [unit of name]."""
        return self.value

    def with_value(self, value: float | None = None) -> "Param":
        """A copy starting at ``value`` (None: the declared value), clipped into the bounds."""
        v = self.value if value is None else float(value)
        return replace(self, value=float(np.clip(v, self.lower, self.upper)))

    def to_internal(self, x: float) -> float:
        return float(np.log10(x)) if self.log else float(x) / self.scale

    def to_physical(self, u: float) -> float:
        return float(10.0 ** np.clip(u, -300.0, 300.0)) if self.log else float(u) * self.scale
