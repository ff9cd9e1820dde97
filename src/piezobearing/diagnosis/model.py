"""What the engine needs of a subject's forward model (:class:`Model`).

A forward model predicts the recorded voltage from the record (its measured
input, if any) and a dict of parameter values. It has baseline parameters
(the calibration's R; a bearing's load) and nuisance parameters (a start
phase, the speed within its tolerance), all in :meth:`Model.params` and so
fitted in every model, and a tuple of catalogue effects on top. The engine
never builds a model itself: the subject gives it the baseline model, and
the engine grows it with :meth:`Model.with_effect`.

Optional: ``noise_envelope(values, record) -> ndarray | None``, the gain of
the input-noise path at each sample when it changes along the record (a
force-dependent sensitivity); the engine then lets the residual's std follow
it (:func:`piezobearing.diagnosis.fit.noise_scale`). A model without it (or
returning None) has stationary noise. It is not part of the Protocol, so
models without it still satisfy ``isinstance(m, Model)``.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ..fitting.params import Param
from .effect import Effect, EffectError
from .record import Record


@runtime_checkable
class Model(Protocol):
    """A forward model: baseline + nuisance parameters + effects (the engine's view of it)."""

    effects: tuple[Effect, ...]

    @property
    def names(self) -> list[str]:
        """Identifiers of the effects switched on, in the order they were added."""

    @property
    def label(self) -> str:
        """``baseline + effect + ...`` for progress messages."""

    def with_effect(self, effect: Effect) -> "Model":
        """The same model with one more effect (a new object; the model is immutable)."""

    def params(self, record: Record, start: dict[str, float] | None = None) -> list[Param]:
        """Every free parameter (baseline, nuisance, then each effect's), starting at ``start`` or defaults."""

    def simulate(self, values: dict, record: Record, input_: np.ndarray | None = None) -> np.ndarray:
        """Voltage [V] on the record's clock, driven by the record's input (or ``input_`` in its place)."""

    def response(self, values: dict, record: Record) -> np.ndarray | float:
        """G(f) from the measured input to the voltage at ``record.freq_Hz`` (complex), which carries the
        input channel's noise into the residual; 0 for a model without a measured input."""

    def fit_input(self, record: Record) -> np.ndarray | None:
        """The input the likelihood fit drives the model with (the measured one, or a denoised copy; None:
        the record's own)."""

    def fit_weight(self, record: Record) -> np.ndarray | float:
        """W(f): the filter :meth:`fit_input` applied to the input, at ``record.freq_Hz`` (1: none)."""

    def release(self) -> None:
        """Drop whatever the model cached during one fit (the engine calls it when the fit is done, so
        the many models of a ranking hold no full-length arrays)."""


class EffectList:
    """What a subject's model inherits for the listing part of :class:`Model`: ``names`` and ``label`` from its
    ``effects``, and :meth:`spec_values` (a dataclass's fields are its own; this class has none)."""

    effects: tuple[Effect, ...]

    @property
    def names(self) -> list[str]:
        return [e.name for e in self.effects]

    @property
    def label(self) -> str:
        return " + ".join(["baseline", *self.names])

    def spec_values(self, specs: list[dict], record: Record, key: str) -> dict[str, float]:
        """The model's default values (``self.defaults(record)``) with those ``specs`` give: ``specs`` is
        ``[{name, params: {parameter: value}}]``, one per effect in order; a parameter the effect does not have,
        or a value outside its bounds, raises a one-line EffectError naming ``key``."""
        values = self.defaults(record)
        for i, (spec, effect) in enumerate(zip(specs, self.effects, strict=True)):
            allowed = {p.name: p for p in effect.params(record)}
            for name, val in (spec.get("params") or {}).items():
                if name not in allowed:
                    raise EffectError(
                        f"{key}[{i}].params.{name}: unknown parameter of '{effect.name}'; "
                        f"it has: {', '.join(allowed) or 'none'}"
                    )
                p = allowed[name]
                if not p.lower <= float(val) <= p.upper:
                    raise EffectError(f"{key}[{i}].params.{name}: {val} outside [{p.lower:g}, {p.upper:g}]")
                values[name] = float(val)
        return values
