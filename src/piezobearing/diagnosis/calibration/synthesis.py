"""The calibration subject's synthesiser: catalogue effects hidden in a synthetic calibration record.

The press protocol (:mod:`piezobearing.diagnosis.calibration.presses`) makes the true force and
its recorded, noisy copy; :func:`hidden_voltage` turns the true force into
the voltage with the diagnosis's own forward model (the RC baseline plus the
hidden effects, ``synthesis.hidden_effects``), so that a test can check that
the engine finds what was hidden.
"""

from __future__ import annotations

import numpy as np

from ...sensor.calibration import SensorCircuit
from .model import model_from_specs
from .record import ForceRecord


def hidden_voltage(
    circuit: SensorCircuit,
    hidden_effects: list[dict],
    time_s: np.ndarray,
    recorded_force_N: np.ndarray,
    true_force_N: np.ndarray,
) -> np.ndarray:
    """The noise-free voltage [V] of the circuit with ``hidden_effects`` ([{name, params}]) switched on.

    The effects see the record the diagnosis will see (e.g. its force band, from the recorded force)
    and are driven by the true force. Parameters not given take the effect's neutral default; an
    unknown effect or parameter raises a one-line EffectError naming ``synthesis.hidden_effects``.
    """
    record = ForceRecord(time_s, recorded_force_N)
    model, values = model_from_specs(circuit, list(hidden_effects), record)
    return model.simulate(values, record, true_force_N)
