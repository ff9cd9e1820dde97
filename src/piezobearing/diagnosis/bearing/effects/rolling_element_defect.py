"""``rolling_element_defect``: a groove on one roller.

Physics
-------
A pit on a roller's surface meets the outer raceway once per spin turn and
the inner raceway half a turn later: two dips per turn (2 x BSF), each only
while that roller is in the load zone, so they come in bursts once per cage
turn (FTF sidebands). Against the outer raceway the roller bridges the pit
with the relative radius 1/(1/r - 1/R_o), against the inner one with
1/(1/r + 1/R_i).

Model
-----
The spin angle beta(t) = beta_0 + (R_o / r) (phi(t) - phi_0) follows the
cage angle phi (the roller rolls on the stationary outer ring); the drop
(:func:`piezobearing.bearing.surrogate.rolling_element_drop`) enters the
equilibrium on the fine grid as for the inner race. Which roller carries the
pit (``roller_defect_index``, counted from the roller at ``start_phase_rad``
in the sense of rotation) is chosen among the starts, not fitted.

Parameters: ``roller_defect_width_m`` in [0, 3] mm (0: none);
``roller_defect_spin_rad``: the pit's spin angle at the first sample (0 faces
the outer race); ``roller_defect_index`` (fixed) in 0..Z-1.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import MAX_DEFECT_WIDTH_M, Effect, cage_phase_of, fold_peak, scan
from .outer_race_defect import TRIAL_WIDTH_M, _width_start


class RollingElementDefect(Effect):
    name = "rolling_element_defect"
    title = "rolling-element defect (pit on a roller)"
    example = {"roller_defect_width_m": 0.8e-3, "roller_defect_spin_rad": 1.0, "roller_defect_index": 3.0}
    example_reason = (
        "a pit of about the paper's seeded defect size (0.9 mm) on roller 3 of the 11; its spin angle at the "
        "record's start (1 rad) is arbitrary"
    )
    physics = (
        "A pit on one roller meets the outer and the inner raceway once each per spin turn (2 x BSF), and "
        "dips the load only while that roller is in the load zone: bursts once per cage turn (FTF)."
    )

    def params(self, record) -> list[Param]:
        z = record.rig.geometry.n_rollers
        return [
            Param("roller_defect_width_m", 0.0, 0.0, MAX_DEFECT_WIDTH_M, scale=1e-4, description="pit width around the roller [m]"),
            Param("roller_defect_spin_rad", 0.0, -2 * np.pi, 2 * np.pi, scale=0.05,
                  description="pit's spin angle at the first sample, 0 facing the outer race [rad]"),
            Param("roller_defect_index", 0.0, 0.0, z - 1.0, vary=False,
                  description="which roller, counted from the one at start_phase_rad [-]"),
        ]

    def starts(self, ctx):
        """The pit's spin angle modulo half a turn from where the residual's energy piles up over the spin,
        both contacts (beta_0 and beta_0 + pi), and the three rollers whose passages through the load zone
        carry most of that energy; scanned with a 0.5 mm pit."""
        rig = ctx.record.rig
        g = rig.geometry
        phi = cage_phase_of(ctx)
        phi0 = ctx.values.get("start_phase_rad", 0.0)
        spin = (g.outer_raceway_radius_m / (0.5 * g.roller_diameter_m)) * (phi - phi0)
        s0 = fold_peak(ctx.residual_V, spin, np.pi, 360)
        b0 = -s0  # the pit faces a race where beta_0 + spin = 0 mod pi
        # which roller: the residual energy near the events, weighted by each roller's load-zone presence
        events = np.abs(np.angle(np.exp(2j * (b0 + spin)))) < 0.1
        e = ctx.residual_V**2 * events
        score = [float(np.sum(e * np.maximum(np.cos(phi + k * rig.pitch_rad), 0.0) ** 3)) for k in range(g.n_rollers)]
        best = np.argsort(score)[::-1][:3]
        trials = [
            {"roller_defect_width_m": TRIAL_WIDTH_M, "roller_defect_spin_rad": float(np.angle(np.exp(1j * (b0 + c)))),
             "roller_defect_index": float(k)}
            for k in best
            for c in (0.0, np.pi)
        ]
        return [_width_start(s, "roller_defect_width_m") for s in scan(ctx, trials)] or [
            {"roller_defect_width_m": TRIAL_WIDTH_M}
        ]

    def summary(self, values):
        return (
            f"width {values['roller_defect_width_m'] * 1e3:.3f} mm on roller {int(values['roller_defect_index'])}, "
            f"spin angle {np.degrees(values['roller_defect_spin_rad']):.1f} deg at t = 0"
        )


EFFECT = RollingElementDefect()
