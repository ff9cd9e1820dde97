"""``radial_load``: the bearing carries another radial load than believed.

Physics
-------
The load on a bearing of a rig is rarely measured: shaft weight, belt
tension, misalignment and unbalance add to or take from the nominal. The
load sets how deep the rings press into the rollers and how wide the load
zone is, so both the roller bumps' height and their shape change (with
clearance, a heavier load widens the zone: more rollers share it).

Model
-----
F_r in the rings' quasi-static equilibrium (:mod:`piezobearing.bearing.surrogate`).
Trades off partly with ``radial_clearance_m`` and ``load_share_ratio``: a
heavier load and a smaller share give similar bumps, told apart only by the
load zone's shape (stated in ``fault.non_separable``).

Parameter: ``radial_load_N`` in [10 N, 50 kN], neutral at the config's
``bearing.radial_load_N``.
"""

from __future__ import annotations

from ....fitting.params import Param
from .base import Effect


class RadialLoad(Effect):
    name = "radial_load"
    title = "radial load"
    example = {"radial_load_N": 800.0}
    example_reason = (
        "800 N where 500 N (the paper's case) is believed: a belt tensioned harder or a misaligned coupling, "
        "well within an N305's rating"
    )
    physics = (
        "The radial load is rarely measured on a rig (weight, belt tension, misalignment): it sets the "
        "rollers' deflection and the width of the load zone, so the bumps' height and shape."
    )

    def params(self, record) -> list[Param]:
        f0 = record.rig.radial_load_N
        return [Param("radial_load_N", f0, 10.0, 5e4, log=True, description="radial load on the bearing [N]")]

    def starts(self, ctx):
        f0 = ctx.record.rig.radial_load_N
        return [{"radial_load_N": 0.5 * f0}, {"radial_load_N": 2.0 * f0}]

    def summary(self, values):
        return f"radial load {values['radial_load_N']:.1f} N"


EFFECT = RadialLoad()
