"""``cage_slip``: the cage turns slower than pure rolling makes it.

Physics
-------
Lightly loaded rollers outside the load zone lose traction, and the cage lags
the kinematic speed by 1-2% in normal running (more at high speed and light
load, NOTES-ENGINEERING). Every cage-borne frequency (FTF, BPFO, BSF) falls by
the slip, BPFI rises by Z x the lost FTF; on a record of seconds the roller
passages drift by whole periods against the kinematic prediction.

Model
-----
FTF = f_r / 2 (1 - D_r/D_p) (1 - s); the rollers' spin follows the cage
(they roll on the outer ring). Without a tachometer the shaft speed is
fitted within its tolerance too, and with an outer-race or no defect only
their product Z x FTF is seen: slip and speed are then one number (stated
in ``fault.non_separable``).

Parameter: ``cage_slip_ratio`` in [-0.02, 0.2] (0: rolling without slip).
"""

from __future__ import annotations

from ....fitting.params import Param
from .base import Effect


class CageSlip(Effect):
    name = "cage_slip"
    title = "cage slip"
    example = {"cage_slip_ratio": 0.015}
    example_reason = (
        "1.5% slip: the cage of a rolling bearing typically lags its kinematic speed by 1-2% (Randall and Antoni "
        "2011), more when lightly loaded"
    )
    physics = (
        "The cage lags the kinematic speed (rollers outside the load zone lose traction): FTF, BPFO and BSF "
        "fall by the slip, so the roller passages drift against the kinematic prediction."
    )

    def params(self, record) -> list[Param]:
        return [Param("cage_slip_ratio", 0.0, -0.02, 0.2, scale=0.005, description="cage slip [-]")]

    def starts(self, ctx):
        return [{"cage_slip_ratio": 0.01}, {"cage_slip_ratio": 0.03}]

    def summary(self, values):
        return f"slip {100 * values['cage_slip_ratio']:.2f}%"


EFFECT = CageSlip()
