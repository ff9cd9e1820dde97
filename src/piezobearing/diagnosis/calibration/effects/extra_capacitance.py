"""``extra_capacitance``: capacitance across the electrodes beyond Cp + the cable.

Physics
-------
Everything in parallel with the disk adds to C = Cp + Ccable: a longer or
different cable than configured (90 pF/m for PCB-003), a BNC adapter, the
DAQ's input capacitance (tens to a few hundred picofarads). With
d33 = 400 pC/N and C = 261 pF nominal, an extra 100 pF lowers the
open-circuit gain d33/C from 1.53 to 1.11 V/N and lengthens tau = RC by 38%.
A fit of R alone can match the time constant but not the gain: the
voltage comes out too large by the same factor at every impulse.

Model
-----
The circuit's extra capacitance (``SensorCircuit.extra_capacitance_F``) is
the parameter; gain and time constant follow from it, and so does the
force-noise response (through the circuit). Negative values mean less
capacitance than configured (e.g. a shorter cable).

Parameter: ``extra_capacitance_F`` in [-100e-12, 5e-9] F.
"""

from __future__ import annotations

from dataclasses import replace

from ....fitting.params import Param
from .base import Effect, ForceRecord


class ExtraCapacitance(Effect):
    name = "extra_capacitance"
    title = "extra capacitance across the electrodes"
    order = 100
    example = {"extra_capacitance_F": 100e-12}
    example_reason = (
        "the DAQ input capacitance, or 1.1 m more of the 90 pF/m cable: 100 pF"
    )
    physics = (
        "Capacitance in parallel with the disk beyond Cp + the nominal cable (a longer cable, adapters, the "
        "DAQ's input capacitance) lowers the gain d33/C and lengthens tau = RC. R alone can match tau but not "
        "the gain, so every impulse comes out too large by the same factor."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "extra_capacitance_F",
                0.0,
                -100e-12,
                5e-9,
                scale=1e-12,
                description="capacitance across the electrodes beyond Cp + cable [F]",
            )
        ]

    def circuit(self, circuit, values):
        return replace(
            circuit, extra_capacitance_F=circuit.extra_capacitance_F + values["extra_capacitance_F"]
        )

    def summary(self, values):
        return f"extra C = {values['extra_capacitance_F'] * 1e12:.1f} pF"


EFFECT = ExtraCapacitance()
