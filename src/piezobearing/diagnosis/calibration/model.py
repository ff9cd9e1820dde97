"""The forward model the diagnosis fits: the RC baseline of Eq. 6 plus effects.

The baseline maps the recorded reference force F to the voltage V by

.. math::  C \\dot V + V / R = d_{33} \\dot F,\\qquad C = C_p + C_{cable},

integrated exactly for a force piecewise linear between samples
(:func:`piezobearing.sensor.calibration.circuit_voltage`, response
:func:`piezobearing.sensor.calibration.rc_response`). Its free parameter is R.
Each effect of the catalogue (:mod:`piezobearing.diagnosis.calibration.effects`) changes one link
of the chain (recorded force -> force on the disk -> circuit -> DAQ input ->
additive interference) and brings its own parameters.

The model also gives its response G(f) from the recorded force to the
voltage (the discrete response of the circuit times each effect's factor):
white noise of the force channel reaches the residual through G, so the
noise floor of a model is S(f) = s_v^2 + s_f^2 |G(f)|^2.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...fitting.params import Param
from ...sensor.calibration import SensorCircuit, circuit_voltage, rc_response, resistance_param, unit_delay
from ..model import EffectList
from .effects import Effect, EffectError, ForceRecord, resolve
from .effects.base import denoised_force, prefilter_response

#: Samples at the initial force level put before the record (see :meth:`ForwardModel.simulate`).
PAD = 16
#: Entries of a model's cache of stages (force, voltage, response), least recently used dropped first: a fit's
#: point and its finite-difference steps.
CACHE_ENTRIES = 16


@dataclass(frozen=True)
class ForwardModel(EffectList):
    """The RC baseline with a tuple of effects (a :class:`piezobearing.diagnosis.model.Model`).

    Parameters
    ----------
    circuit : SensorCircuit
        Nominal circuit (its R is replaced by the parameter ``resistance_ohm``).
    effects : tuple of Effect
        Effects switched on, in the order they were added.
    """

    circuit: SensorCircuit
    effects: tuple[Effect, ...] = ()
    _cache: dict = field(default_factory=dict, compare=False, repr=False, hash=False)
    #: The names of the additive and of the force hooks' parameters per record (``id`` -> (record, names)),
    #: :meth:`_keys`.
    _additive: dict = field(default_factory=dict, compare=False, repr=False, hash=False)

    @classmethod
    def build(
        cls, circuit: SensorCircuit, names: list[str] | tuple[str, ...] = (), key: str = "model.effects"
    ) -> "ForwardModel":
        """A model from effect identifiers; an unknown name raises a one-line EffectError naming ``key``."""
        return cls(circuit, tuple(resolve(names, key)))

    def with_effect(self, effect: Effect) -> "ForwardModel":
        return ForwardModel(self.circuit, (*self.effects, effect))

    def _chain(self) -> list[Effect]:
        return sorted(self.effects, key=lambda e: e.order)

    # ----------------------------------------------------------------- parameters
    def effect_params(self, record: ForceRecord) -> list[Param]:
        return [p for e in self.effects for p in e.params(record)]

    def defaults(self, record: ForceRecord) -> dict[str, float]:
        """Values that leave every effect neutral, with the nominal R."""
        out = {"resistance_ohm": self.circuit.resistance_ohm}
        for e in self.effects:
            out.update(e.defaults(record))
        return out

    def params(self, record: ForceRecord, start: dict[str, float] | None = None) -> list[Param]:
        """The free parameters (R first) with start values from ``start`` (else defaults)."""
        start = {**self.defaults(record), **(start or {})}
        return [resistance_param(start["resistance_ohm"])] + [
            p.with_value(start.get(p.name)) for p in self.effect_params(record)
        ]

    def complete(self, values: dict, record: ForceRecord, key: str = "params") -> dict[str, float]:
        """Defaults overridden by ``values``; an unknown name raises a one-line EffectError."""
        full = self.defaults(record)
        unknown = sorted(set(values) - set(full))
        if unknown:
            raise EffectError(f"{key}: unknown parameter '{unknown[0]}'; the model has {', '.join(full)}")
        full.update({k: float(v) for k, v in values.items()})
        return full

    # ----------------------------------------------------------------- simulation
    def fitted_circuit(self, values: dict) -> SensorCircuit:
        c = self.circuit.with_resistance(values["resistance_ohm"])
        for e in self._chain():
            c = e.circuit(c, values)
        return c

    def simulate(self, values: dict, record: ForceRecord, force_N: np.ndarray | None = None) -> np.ndarray:
        """Voltage [V] for the recorded force (or ``force_N`` on the record's clock).

        The circuit starts at rest at the force's initial level, the median of
        its first 10 ms (``PAD`` samples at that level precede the record and
        are dropped): starting at the first, noisy sample instead would put
        that sample's noise (amplified by a lead, if any) into a decaying
        transient that the measured voltage does not have.
        """
        chain = self._chain()
        f0 = record.force_N if force_N is None else np.asarray(force_N, dtype=float)
        v = self._voltage(f0, values, record, chain)[PAD:]
        for e in chain:
            add = e.additive(values, record)
            if add is not None:
                v = v + add
        return v

    @staticmethod
    def _unit_delay(record: ForceRecord) -> np.ndarray:
        if "unit_delay" not in record._cache:  # z^-1 on the record's bins: the same at every R
            record._cache["unit_delay"] = unit_delay(record.freq_Hz, record.dt_s)
        return record._cache["unit_delay"]

    def _forced(self, f0: np.ndarray, values: dict, record: ForceRecord, chain: list[Effect]) -> np.ndarray:
        """The force on the disk with ``PAD`` samples before the record, by the values of the force hooks'
        parameters (a finite difference in R or the circuit reuses it)."""

        def compute():
            level = record._cache.get("start_level")  # the median of the force's first 10 ms, once per force array
            if level is None or level[0] is not f0:
                level = (f0, np.median(f0[: max(int(round(0.01 / record.dt_s)), 1)]))
                record._cache["start_level"] = level
            f = np.concatenate([np.full(PAD, level[1]), f0])
            for e in chain:
                f = e.force(f, values, record)
            return f

        return self._cached("force", f0, values, record, compute, self._keys(record)[1])

    def _voltage(self, f0: np.ndarray, values: dict, record: ForceRecord, chain: list[Effect]) -> np.ndarray:
        """The voltage of the force path with the ``PAD`` samples before the record, by the values of the
        non-additive parameters."""

        def compute():
            v = circuit_voltage(self._forced(f0, values, record, chain), record.dt_s, self.fitted_circuit(values))
            for e in chain:
                v = e.voltage(v, values, record)
            return v

        return self._cached("voltage", f0, values, record, compute)

    def _keys(self, record: ForceRecord) -> tuple[frozenset, tuple[str, ...]]:
        """The additive parameters' names and the force hooks' parameters' names, once per record: the
        effects' parameter lists (a spline's knots) took a tenth of a calibration fit's time."""
        hit = self._additive.get(id(record))
        if hit is None or hit[0] is not record:
            additive = frozenset(p.name for e in self.effects if e.additive_only for p in e.params(record))
            force = tuple(
                p.name for e in self._chain() if type(e).force is not Effect.force for p in e.params(record)
            )
            hit = (record, (additive, force))
            self._additive[id(record)] = hit
        return hit[1]

    def _cached(self, what: str, obj, values: dict, record: ForceRecord, compute, names: tuple | None = None):
        """Results of the force path (and response) by the values of the non-additive parameters (or of
        ``names``, those a stage depends on).

        A fit's finite differences in an additive parameter (mains, drift) then
        reuse the force path, and those in R or the circuit the force hooks'
        output. Entries hold their input array, so a key cannot meet a
        different array with a recycled id.
        """
        if names is None:
            additive = self._keys(record)[0]
            key = (what, id(obj), tuple(sorted((k, v) for k, v in values.items() if k not in additive)))
        else:
            key = (what, id(obj), tuple(values[k] for k in names))
        hit = self._cache.get(key)
        if hit is not None and hit[0] is obj:
            self._cache[key] = self._cache.pop(key)  # the most recently used last
            return hit[1]
        out = compute()
        self._cache[key] = (obj, out)
        while len(self._cache) > CACHE_ENTRIES:
            self._cache.pop(next(iter(self._cache)))
        return out

    def linear_basis(self, values: dict, record: ForceRecord) -> list[tuple[tuple[str, ...], np.ndarray, tuple]]:
        """The effects' additive terms linear in their parameters: (names, d voltage / d parameter (n, k), key)
        blocks (:func:`~piezobearing.diagnosis.fit.likelihood_residual` takes their Jacobian columns exactly)."""
        return [b for e in self.effects for b in e.linear_basis(values, record)]

    def release(self) -> None:
        """Empty the cache of :meth:`_cached` (a finished fit needs it no more)."""
        self._cache.clear()

    def fit_input(self, record: ForceRecord) -> np.ndarray:
        """The force the likelihood fit drives the model with: its noise removed above twice its band
        (:func:`~piezobearing.diagnosis.calibration.effects.base.denoised_force`) [N]."""
        return denoised_force(record)

    def fit_weight(self, record: ForceRecord) -> np.ndarray:
        """W(f) of :meth:`fit_input` at ``record.freq_Hz`` [-]."""
        return prefilter_response(record.freq_Hz, record)

    def response(self, values: dict, record: ForceRecord) -> np.ndarray:
        """G(f) from recorded force to voltage at ``record.freq_Hz`` [V/N] (complex)."""
        return self._cached("response", record, values, record, lambda: self._response(values, record))

    def noise_envelope(self, values: dict, record: ForceRecord) -> np.ndarray | None:
        """a(t): the product of the effects' gains on the force noise along the record [-] (None: constant).

        The engine's optional hook of a model whose input-noise gain changes
        with time (:func:`piezobearing.diagnosis.fit.noise_scale`).
        """
        out = None
        for e in self.effects:
            a = e.noise_envelope(values, record)
            if a is not None:
                out = a if out is None else out * a
        return out

    def _response(self, values: dict, record: ForceRecord) -> np.ndarray:
        c = self.fitted_circuit(values)
        g = rc_response(record.freq_Hz, record.dt_s, c.open_circuit_gain_V_per_N, c.tau_s, self._unit_delay(record))
        for e in self.effects:
            g = g * e.response(values, record)
        return g


def model_from_specs(
    circuit: SensorCircuit, specs: list[dict], record: ForceRecord, key: str = "synthesis.hidden_effects"
) -> tuple[ForwardModel, dict[str, float]]:
    """A model and its parameter values from ``[{name: id, params: {key_unit: value}}]``.

    Parameters not given take the effect's default; R is the circuit's. An
    unknown effect or parameter raises a one-line EffectError naming the key.
    """
    model = ForwardModel.build(circuit, [s["name"] for s in specs], key=key)
    return model, model.spec_values(specs, record, key)
