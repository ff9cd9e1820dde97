"""``ac_coupling``: an extra first-order high-pass at the DAQ input.

Physics
-------
A DAQ input set to AC coupling (or a coupling capacitor in a signal
conditioner) blocks DC with a first-order high-pass of corner f_c, typically
0.1 to 1 Hz (e.g. 0.5 Hz on common dynamic-signal DAQs). It acts on the
voltage after the PZT's own RC high-pass (tau = RC, 13 ms): the impulses,
which last about a second, lose part of their slow content and each one is
followed by a slow undershoot of the opposite sign that R alone cannot
produce. The input is assumed buffered, so the coupling stage does not load
the PZT circuit.

Model
-----
.. math::  \\tau_c \\dot V_{DAQ} + V_{DAQ} = \\tau_c \\dot V,\\quad \\tau_c = 1/(2\\pi f_c),

integrated exactly like the RC model (voltage piecewise linear between
samples). Response factor: the same filter's discrete frequency response.

Parameter: ``corner_Hz`` in [1e-6, 20] Hz (log scale; 1e-6 Hz is no coupling).
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from ....sensor.calibration import rc_response, rc_voltage, unit_delay
from .base import Effect, ForceRecord, StartContext


def _tau(values) -> float:
    return 1.0 / (2 * np.pi * values["corner_Hz"])


class ACCoupling(Effect):
    name = "ac_coupling"
    title = "AC-coupled DAQ input (high-pass)"
    order = 200
    example = {"corner_Hz": 0.5}
    example_reason = (
        "an AC-coupled DAQ input: corners of 0.1-1 Hz are typical (0.5 Hz on dynamic-signal DAQs)"
    )
    physics = (
        "An AC-coupled DAQ input blocks DC with a first-order high-pass of corner f_c (typically 0.1-1 Hz), "
        "in series with the PZT's own RC high-pass. Impulses lasting about a second lose slow content and "
        "each is followed by a slow undershoot that R alone cannot produce."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "corner_Hz",
                1e-6,
                1e-6,
                20.0,
                log=True,
                description="corner frequency of the AC coupling high-pass [Hz]",
            )
        ]

    def voltage(self, voltage_V, values, record):
        return rc_voltage(voltage_V, record.dt_s, 1.0, _tau(values))

    def response(self, values, record):
        if "unit_delay" not in record._cache:  # z^-1 on the record's bins (the model's cache)
            record._cache["unit_delay"] = unit_delay(record.freq_Hz, record.dt_s)
        return rc_response(record.freq_Hz, record.dt_s, 1.0, _tau(values), record._cache["unit_delay"])

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        return [{"corner_Hz": 1e-6}, {"corner_Hz": 0.05}, {"corner_Hz": 0.5}]

    def summary(self, values):
        return f"corner = {values['corner_Hz']:.3g} Hz (tau_c = {_tau(values):.3g} s)"


EFFECT = ACCoupling()
