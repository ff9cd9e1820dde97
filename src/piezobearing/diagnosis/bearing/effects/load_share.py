"""``load_share``: the share of the housing's force that reaches the PZT through its mounting.

Physics
-------
The sensor sits in a threaded hole against the outer ring: the thread's
preload, the contact of the alumina tip on the ring, any gap or adhesive in
the stack decide how much of the force the housing model puts on the sensor
actually passes through the PZT. It is uncertain by a factor of 2-3 on a
real rig.

Model
-----
The sensor force is multiplied by s before the circuit. For a single record
s is one number with everything else that scales the voltage: d33, the
capacitance C (gain d33/C), and any gain of the circuit or the DAQ. The fit
finds their product; it cannot tell them apart (``fault.non_separable``).

Parameter: ``load_share_ratio`` in [0.05, 5] (1: the housing model's force).
"""

from __future__ import annotations

from ....fitting.params import Param
from .base import Effect


class LoadShare(Effect):
    name = "load_share"
    title = "sensor mounting's load share"
    example = {"load_share_ratio": 0.5}
    example_reason = (
        "half of the housing's force through the PZT: a thread preload lost or a gap beside the sensor that lets "
        "force pass around it"
    )
    physics = (
        "How much of the housing's force passes through the PZT (thread preload, tip contact, gaps): a gain on "
        "the sensor force, one number with d33, C and any circuit gain for a single record."
    )

    def params(self, record) -> list[Param]:
        return [Param("load_share_ratio", 1.0, 0.05, 5.0, log=True, description="share of the sensor force [-]")]

    def starts(self, ctx):
        return [{"load_share_ratio": 0.5}, {"load_share_ratio": 2.0}]

    def summary(self, values):
        return f"load share {values['load_share_ratio']:.3f}"


EFFECT = LoadShare()
