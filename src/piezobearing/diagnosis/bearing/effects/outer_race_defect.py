"""``outer_race_defect``: a groove across the outer raceway, at an angle from the sensor.

Physics
-------
A spall or an indentation on the stationary outer raceway: each roller that
rolls over it sinks into it (it bridges the groove on its edges, the drop
limited by the relative radius of roller and concave raceway, 1/(1/r - 1/R_o),
NOTES-ENGINEERING), its load falls and the neighbours take it over. The
sensor sees the redistribution through the housing's influence line: a dip
once per roller passage over the defect, at BPFO, largest when the defect is
in the load zone near the sensor. Widths from 0.1 mm (a fresh pit) to a few
millimetres (a spalled track).

Model
-----
The drop d_j = rho - sqrt(rho^2 - m^2) of the roller whose centre is inside
the groove (m: its distance to the nearer edge) enters the rings'
quasi-static equilibrium (:func:`piezobearing.bearing.surrogate.outer_race_drop`);
the configuration repeats every roller pitch, so the chain stays a table
look-up. Outside the load zone the defect carries no load and cannot be
seen: its angle is then not identifiable (wide interval).

Parameters: ``outer_defect_width_m`` in [0, 3] mm (0: none);
``outer_defect_angle_rad`` in [-pi, pi] from the sensor (the load direction).
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import MAX_DEFECT_WIDTH_M, Effect, cage_phase_of, fold_peak, scan

TRIAL_WIDTH_M = 0.5e-3


class OuterRaceDefect(Effect):
    name = "outer_race_defect"
    title = "outer-race defect (groove)"
    example = {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.15}
    example_reason = (
        "an early spall, narrower than the paper's seeded 0.9 mm groove, in the load zone 0.15 rad (8.6 deg) from "
        "the sensor, where the paper puts its defect"
    )
    physics = (
        "A groove or spall on the stationary outer raceway: each roller sinks into it as it passes, its load "
        "drops and its neighbours take the load over; the sensor sees a dip once per roller passage (BPFO), "
        "largest with the defect in the load zone near the sensor."
    )

    def params(self, record) -> list[Param]:
        return [
            Param("outer_defect_width_m", 0.0, 0.0, MAX_DEFECT_WIDTH_M, scale=1e-4, description="groove width along the raceway [m]"),
            Param("outer_defect_angle_rad", 0.0, -np.pi, np.pi, scale=0.05, description="groove centre from the sensor [rad]"),
        ]

    def starts(self, ctx):
        """The groove's angle modulo a pitch from where the residual's energy piles up over the cage phase
        (a roller stands in it), then each such angle within +-100 deg of the sensor (the load zone),
        scanned with a 0.5 mm groove."""
        pitch = ctx.record.rig.pitch_rad
        phi = cage_phase_of(ctx)
        a0 = fold_peak(ctx.residual_V, phi, pitch, 180)
        angles = [a0 + k * pitch for k in range(-6, 7) if abs(a0 + k * pitch) <= np.radians(100.0)]
        trials = [{"outer_defect_width_m": TRIAL_WIDTH_M, "outer_defect_angle_rad": float(a)} for a in angles]
        return [_width_start(s, "outer_defect_width_m") for s in scan(ctx, trials)] or [
            {"outer_defect_width_m": TRIAL_WIDTH_M}
        ]

    def summary(self, values):
        return (
            f"width {values['outer_defect_width_m'] * 1e3:.3f} mm at "
            f"{np.degrees(values['outer_defect_angle_rad']):.1f} deg from the sensor"
        )


def _width_start(s: dict, key: str) -> dict:
    """A width start from a scan's amplitude: the dip grows about as the width squared."""
    a = s.pop("_amplitude")
    s[key] = float(np.clip(s[key] * np.sqrt(max(a, 0.05)), 0.05e-3, 2.9e-3))
    return s


EFFECT = OuterRaceDefect()
