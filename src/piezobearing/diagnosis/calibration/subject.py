"""The calibration record as a diagnosis subject (:data:`SUBJECT`).

- record: time, reference force and PZT voltage (:mod:`.record`: reader,
  validator, impulse detection);
- forward model: the RC circuit of Eq. 6 driven by the recorded force, its
  baseline parameter R (:class:`.model.ForwardModel`); no nuisance parameters;
- catalogue: :mod:`.effects` (channel delay, AC coupling, reference lag, d33
  nonlinearity, mains, drift, extra capacitance);
- representations: the engine's whitened time residual, and the error per
  impulse (:class:`PerImpulse`);
- synthesiser: :mod:`piezobearing.diagnosis.calibration.presses` with the effects hidden by
  :func:`.synthesis.hidden_voltage`;
- answer: the most likely missing effect (``winner``), when the search kept it first.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

import numpy as np

from ...io import Measurement
from ...numerics.threads import single_blas_thread
from ...sensor.calibration import Impulse, SensorCircuit, detect_impulses
from ..engine import Diagnosis, diagnose
from ..fit import ModelFit
from ..noise import estimate_noise_floor
from ..settings import DiagnosticsSettings
from ..subject import Judgement, Problem
from ..verdict import segment_stats
from . import report
from .effects import CATALOGUE, resolve
from .model import ForwardModel, model_from_specs
from .presses import PressProtocol, synthesize
from .record import ForceRecord, gap_memory_s, impulse_segments, read_record


class PerImpulse:
    """The error of a fit within each impulse: NRMSE, rms residual and whitened mean square."""

    key = "per_impulse"

    def __init__(self, impulses: list[Impulse]) -> None:
        self.impulses = list(impulses)

    def judge(self, fit: ModelFit, problem: Problem, settings: DiagnosticsSettings) -> Judgement:
        t = problem.record.time_s
        rows = [
            {
                "impulse": j + 1,
                "time_force_peak_s": float(t[imp.force_peak_index]),
                "force_peak_N": imp.force_peak_N,
                **segment_stats(fit, problem.voltage_V, imp.start, imp.stop),
            }
            for j, imp in enumerate(self.impulses)
        ]
        return Judgement(rows)


def calibration_problem(
    record: ForceRecord,
    voltage_V: np.ndarray,
    circuit: SensorCircuit,
    configured_effects: list[str] | tuple = (),
    settings: DiagnosticsSettings | None = None,
    impulses: list[Impulse] | None = None,
) -> Problem:
    """The engine's problem for a calibration record.

    Parameters
    ----------
    record : ForceRecord
        Time axis and recorded force.
    voltage_V : ndarray
        Measured voltage [V].
    circuit : SensorCircuit
        Nominal circuit; its R starts the baseline fit (a second start at 10 R).
    configured_effects : list of str
        Effects switched on in the config (``model.effects``).
    settings : DiagnosticsSettings
        For the noise floor's settling time (``quiet_settle_s`` + 5 RC after each press).
    impulses : list of Impulse
        Detected impulses (segments of the report, rows of the per-impulse table).
    """
    settings = settings or DiagnosticsSettings()
    v = np.asarray(voltage_V, dtype=float)
    impulses = impulses or []
    r0 = circuit.resistance_ohm
    settle = 5 * circuit.with_resistance(r0).tau_s
    if record.filled is not None:
        # the fit's low-passed force before a gap, the circuit's settling after it (gap_memory_s)
        tau = circuit.with_resistance(r0).tau_s
        record = replace(record, memory_s=gap_memory_s(settings.quiet_settle_s, tau), _cache={})
    floor = estimate_noise_floor(record, v, settings, settle)
    return Problem(
        record=record,
        voltage_V=v,
        baseline=ForwardModel(circuit),
        baseline_start={"resistance_ohm": r0},
        baseline_starts=[{}, {"resistance_ohm": 10 * r0}],
        configured=tuple(resolve(list(configured_effects))),
        catalogue=CATALOGUE,
        floor=floor,
        segments=impulse_segments(impulses),
        representations=(PerImpulse(impulses),),
    )


def diagnose_record(
    record: ForceRecord,
    voltage_V: np.ndarray,
    circuit: SensorCircuit,
    configured_effects: list[str] | tuple = (),
    settings: DiagnosticsSettings | None = None,
    impulses: list[Impulse] | None = None,
    progress: Callable[[str], None] | None = None,
) -> tuple[Diagnosis, dict]:
    """The engine on one calibration record (arguments of :func:`calibration_problem`); returns the
    diagnosis and its JSON-ready dict with the subject's answer."""
    settings = settings or DiagnosticsSettings()
    # the fits' linear algebra is on n x (a few) matrices: a second BLAS thread only waits and spins (the
    # clean default record's diagnosis took 2x the CPU with OpenBLAS's threads on the loaded 2-core machine)
    with single_blas_thread():
        d = diagnose(
            calibration_problem(record, voltage_V, circuit, configured_effects, settings, impulses),
            settings,
            progress,
        )
        return d, d.to_dict(winner(d))


def winner(d: Diagnosis) -> dict:
    """The most likely missing effect: the first ranked, when the search also added it first (else None)."""
    if d.ranking and d.selected and d.selected[0] == d.ranking[0].effect.name:
        best = d.ranking[0]
        return {"winner": {**best.summary(d.configured), "physics": best.effect.physics}}
    return {"winner": None}


def nominal_circuit(config: dict) -> SensorCircuit:
    """The configured circuit with the initial R of the fits (``calibration.initial_resistance_ohm``)."""
    return SensorCircuit.from_config(config["sensor"], config["calibration"]["initial_resistance_ohm"])


class CalibrationSubject:
    """The calibration record (see the module docstring); satisfies :class:`~piezobearing.diagnosis.subject.Subject`."""

    name = "calibration"
    catalogue = CATALOGUE
    figures = report.FIGURES

    def check_config(self, config: dict) -> None:
        """Raise a one-line EffectError if ``model.effects`` or ``synthesis.hidden_effects`` names an unknown
        effect or parameter."""
        resolve(config["model"]["effects"])
        probe = ForceRecord(np.arange(1000) / 1000.0, np.zeros(1000))
        circuit = SensorCircuit.from_config(config["sensor"], config["synthesis"]["resistance_ohm"])
        model_from_specs(circuit, config["synthesis"]["hidden_effects"], probe)

    def read(self, path: str, config: dict) -> tuple[Measurement, list[Impulse]]:
        return read_record(path, config)

    @staticmethod
    def _engine_inputs(observation: tuple[Measurement, list[Impulse]], config: dict) -> tuple:
        """The record, voltage, nominal circuit, configured effects, settings and impulses the engine takes."""
        m, imps = observation
        return (
            ForceRecord(m.time_s, m.force_N, filled=m.filled),
            m.voltage_V,
            nominal_circuit(config),
            config["model"]["effects"],
            DiagnosticsSettings.from_config(config.get("diagnostics")),
            imps,
        )

    def problem(self, observation: tuple[Measurement, list[Impulse]], config: dict) -> Problem:
        return calibration_problem(*self._engine_inputs(observation, config))

    def synthesise(
        self, config: dict, seed: int, hidden_effects: list[dict]
    ) -> tuple[Measurement, list[Impulse]]:
        syn = config["synthesis"]
        circuit = SensorCircuit.from_config(config["sensor"], syn["resistance_ohm"])
        m = synthesize(PressProtocol.from_config(syn), circuit, seed, hidden_effects)
        c = config["calibration"]
        return m, detect_impulses(
            m.force_N, m.voltage_V, m.dt_s, c["min_prominence_fraction"], c["min_separation_s"]
        )

    def answer(self, diagnosis: Diagnosis) -> dict:
        return winner(diagnosis)

    def report(self, d: dict, figures: dict[str, str]) -> str:
        return report.render(d, figures)

    def diagnose(
        self, observation, config: dict, progress: Callable[[str], None] | None = None
    ) -> tuple[Diagnosis, dict]:
        """Run the engine on a record read by :meth:`read`; returns the diagnosis and its JSON-ready dict."""
        return diagnose_record(*self._engine_inputs(observation, config), progress)


#: The calibration subject.
SUBJECT = CalibrationSubject()
