"""What every catalogue effect of every subject is, and the catalogue that holds them.

An effect is a small, documented change to a subject's forward model (a
channel delay, mains pickup, a defect's load drop). The engine only needs
what this base class declares: its identifier, title and physics for the
report, its parameters (:class:`~piezobearing.fitting.params.Param`, unit
suffix from :mod:`~piezobearing.fitting.units`, the declared value
neutral), data-driven start values and a one-line summary. How an effect
changes the simulation is the subject's business: the subject's effect base
class (e.g. :class:`piezobearing.diagnosis.calibration.effects.base.Effect`)
adds the hooks its forward model calls.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from ..fitting.params import Param
from .record import Record


class EffectError(ValueError):
    """An unknown effect name or parameter in the configuration."""


@dataclass(frozen=True, eq=False)
class StartContext:
    """What an effect may look at to propose start values.

    Attributes
    ----------
    record : Record
    voltage_V : ndarray
        Measured voltage [V].
    model_V : ndarray
        Voltage of the current model (without this effect) [V].
    values : dict
        Fitted values of the current model.
    """

    record: Record
    voltage_V: np.ndarray
    model_V: np.ndarray
    values: dict

    @property
    def residual_V(self) -> np.ndarray:
        return self.voltage_V - self.model_V


class Effect:
    """Base class of a catalogue effect (see the module docstring).

    Class attributes
    ----------------
    name : str
        Stable identifier (used in config lists such as ``model.effects``).
    title : str
        A few words for tables.
    physics : str
        A paragraph for the report: the mechanism, the model, plausible sizes.
    equivalent_to : dict[str, str]
        Effects this one is exactly equivalent to on any record (identifier ->
        the statement of the equivalence: which combinations a record
        determines, which it cannot separate). The declaring effect yields
        the tie in the ranking to the other, and the diagnosis states the
        equivalence whenever either of the two is selected or ranked first.
    example : dict[str, float]
        A plausible size of the effect in a real record (parameter -> value, the others at their
        neutral values), chosen for the physics before looking at any diagnosis: the one home of
        the value the tests hide, the error-rate study hides (``benchmarks/bench_diagnosis_seeds.py``)
        and ``piezobearing hide-and-find`` hides when no ``--param`` is given.
    example_reason : str
        Why that size is plausible (a sentence; docs/validation/hide_and_find.md quotes the sizes).
    """

    name: str = ""
    title: str = ""
    physics: str = ""
    equivalent_to: dict[str, str] = {}
    example: dict[str, float] = {}
    example_reason: str = ""

    def params(self, record: Record) -> list[Param]:
        """The parameters for a record (some depend on its sampling rate); declared values are neutral."""
        return []

    def defaults(self, record: Record) -> dict[str, float]:
        return {p.name: p.value for p in self.params(record)}

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        """Start values for this effect's parameters (each dict one start; {} = defaults)."""
        return [{}]

    def variants(self, ctx: StartContext) -> list["Effect"]:
        """The forms of this effect the search fits in turn, keeping the one of lowest BIC (default: itself).

        For an effect with a structural choice the evidence should make (the knot count of a spline
        drift): each variant has the same ``name`` and its own parameters.
        """
        return [self]

    def refinements(self, ctx: StartContext) -> list["Effect"]:
        """Forms built on this one (the variant the search kept), tried in turn once :meth:`variants` has
        chosen, each kept while it lowers BIC (default: none).

        For a second structural choice that is not a step of the first (a spline drift's knot count,
        then a kink at a fitted time on the chosen spline): the greedy search over the variants stops at
        the first that does not lower BIC and would never reach it.
        """
        return []

    def summary(self, values: dict) -> str:
        """One line with the fitted parameters in readable units."""
        return ", ".join(f"{p} = {values[p]:.4g}" for p in values)


class Catalogue(Mapping):
    """A subject's effects by identifier, in registration order (the order the engine tries them).

    Parameters
    ----------
    subject : str
        The subject's name, for error messages.
    """

    def __init__(self, subject: str) -> None:
        self.subject = subject
        self._effects: dict[str, Effect] = {}

    def __getitem__(self, name: str) -> Effect:
        return self._effects[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._effects)

    def __len__(self) -> int:
        return len(self._effects)

    def register(self, effect: Effect) -> Effect:
        """Add an effect under ``effect.name`` (the name must be new)."""
        if not effect.name or effect.name in self._effects:
            raise EffectError(f"effect identifier '{effect.name}' is empty or already registered")
        self._effects[effect.name] = effect
        return effect

    def unregister(self, name: str) -> None:
        """Remove an effect (for tests that register a temporary one)."""
        self._effects.pop(name, None)

    def resolve(self, names, key: str) -> list[Effect]:
        """Effects for identifiers; an unknown or repeated name raises a one-line EffectError naming ``key``."""
        out = []
        for i, name in enumerate(names):
            if name not in self._effects:
                raise EffectError(
                    f"{key}[{i}]: unknown effect '{name}'; the catalogue has: {', '.join(self._effects)}"
                )
            if self._effects[name] in out:
                raise EffectError(f"{key}[{i}]: effect '{name}' is listed twice; list each effect once")
            out.append(self._effects[name])
        return out

    def describe(self) -> dict[str, dict[str, str]]:
        """Identifier -> title and physics (for the diagnosis JSON)."""
        return {name: {"title": e.title, "physics": e.physics} for name, e in self._effects.items()}
