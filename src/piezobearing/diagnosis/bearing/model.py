"""The running bearing's forward model as the engine sees it (a :class:`~piezobearing.diagnosis.model.Model`).

Baseline: the healthy bearing at the nominal operating point through the
chain of :mod:`.chain`. Nuisance parameters, fitted in every model because
every record needs them: the roller set's phase at the first sample
(``start_phase_rad``), the shaft speed within its tolerance
(``shaft_speed_Hz``; taken from the tachometer when the record has one) and
the DAQ's DC level (``dc_offset_V``). Effects add their parameters; the
chain reads them from the values. The model has no measured input: its
noise floor is the voltage channel's alone (response 0).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ...bearing.surrogate import NoEquilibriumError
from ...fitting.least_squares import InfeasibleError
from ...fitting.params import Param
from ..model import EffectList
from ..record import Record
from . import chain
from .effects import CATALOGUE, Effect


@dataclass(frozen=True, eq=False)
class RigRecord(Record):
    """The engine's record of a running bearing: its clock and the :class:`~.chain.Rig` it runs on."""

    rig: chain.Rig = None
    speed_tolerance_ratio: float = 0.02


@dataclass(frozen=True)
class BearingModel(EffectList):
    """Baseline (healthy, nominal) + nuisance parameters + effects.

    Parameters
    ----------
    effects : tuple of Effect
        Effects switched on, in the order they were added.
    """

    effects: tuple[Effect, ...] = ()

    @classmethod
    def build(cls, names=(), key: str = "bearing.effects") -> "BearingModel":
        return cls(tuple(CATALOGUE.resolve(list(names), key)))

    def with_effect(self, effect: Effect) -> "BearingModel":
        return BearingModel((*self.effects, effect))

    def release(self) -> None:
        """Nothing to drop: the model holds no arrays (the chain's voltage cache lives on the record's
        rig, bounded to 64 MB, and serves every model of the diagnosis)."""

    def nuisance(self, record: RigRecord) -> list[Param]:
        """Start phase, speed within tolerance (no tachometer) and DC level."""
        rig = record.rig
        out = [
            Param("start_phase_rad", 0.0, -2 * np.pi, 4 * np.pi, scale=0.01,
                  description="angle of roller 0 from the sensor at the first sample [rad]"),
        ]
        if rig.tach_Hz is None:
            f0, tol = rig.shaft_speed_Hz, record.speed_tolerance_ratio
            out.append(
                Param("shaft_speed_Hz", f0, f0 * (1 - tol), f0 * (1 + tol), scale=1e-3 * f0,
                      description="shaft speed within its tolerance [Hz]")
            )
        out.append(Param("dc_offset_V", 0.0, -1e3, 1e3, scale=1e-2, description="DAQ offset [V]"))
        return out

    def defaults(self, record: RigRecord) -> dict[str, float]:
        out = {p.name: p.value for p in self.nuisance(record)}
        for e in self.effects:
            out.update(e.defaults(record))
        return out

    def params(self, record: RigRecord, start: dict[str, float] | None = None) -> list[Param]:
        """Nuisance and effect parameters at ``start``; a nuisance parameter an effect takes over
        (``Effect.holds``, e.g. the speed within tolerance under ``shaft_speed``) is held at its nominal value."""
        start = {**self.defaults(record), **(start or {})}
        held = {n for e in self.effects for n in getattr(e, "holds", ())}
        out = [replace(p, vary=False) if p.name in held else p.with_value(start.get(p.name)) for p in self.nuisance(record)]
        return out + [p.with_value(start.get(p.name)) for e in self.effects for p in e.params(record)]

    def simulate(self, values: dict, record: RigRecord, input_: np.ndarray | None = None) -> np.ndarray:
        """The chain's voltage at ``values`` [V]; values without an equilibrium of the rings raise
        :class:`~piezobearing.fitting.least_squares.InfeasibleError` (the fit steps back)."""
        add = None
        for e in self.effects:
            a = e.additive(values, record)
            if a is not None:
                add = a if add is None else add + a
        try:
            return chain.voltage(record.rig, values, add)
        except NoEquilibriumError as e:
            raise InfeasibleError(str(e)) from e

    def response(self, values: dict, record: Record) -> np.ndarray:
        """No measured input carries noise into the residual: G = 0 at every bin."""
        return np.zeros(record.freq_Hz.size)

    def fit_input(self, record: Record) -> None:
        return None

    def fit_weight(self, record: Record) -> float:
        return 1.0
