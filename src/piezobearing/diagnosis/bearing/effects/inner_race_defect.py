"""``inner_race_defect``: a groove across the inner raceway, turning with the shaft.

Physics
-------
A defect on the rotating inner ring meets a roller at BPFI = Z (f_r - FTF);
it dips the load only while it is in the load zone, so the dips are
modulated once per shaft turn (sidebands at BPFI +- k f_r in the spectrum, the
classical signature). The roller bridges the groove on the convex inner
raceway with the relative radius 1/(1/r + 1/R_i), so it sinks less than into
an outer-race groove of the same width (NOTES-ENGINEERING).

Model
-----
The groove's angle is theta(t) = theta_0 + 2 pi integral of f_r dt; the roller
nearest to it sinks by the groove's drop (:func:`piezobearing.bearing.surrogate.inner_race_drop`),
and the rings' quasi-static equilibrium is solved on a fine grid (3 sub-samples
across the narrowest groove's passage) wherever a loaded roller stands in
it, then averaged over each sample.

Parameters: ``inner_defect_width_m`` in [0, 3] mm (0: none);
``inner_defect_angle_rad``: the groove's angle from the sensor at the first sample.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import MAX_DEFECT_WIDTH_M, Effect, cage_phase_of, fold_peak, scan
from .outer_race_defect import TRIAL_WIDTH_M, _width_start


class InnerRaceDefect(Effect):
    name = "inner_race_defect"
    title = "inner-race defect (groove)"
    example = {"inner_defect_width_m": 0.8e-3, "inner_defect_angle_rad": 0.7}
    example_reason = (
        "a groove of about the paper's seeded size (0.9 mm wide) on the rotating inner race; its angle at the "
        "record's start (0.7 rad) is arbitrary, since it turns with the shaft"
    )
    physics = (
        "A groove or spall on the rotating inner raceway: it meets a roller at BPFI and dips the load only "
        "while it passes through the load zone, so its dips come in bursts once per shaft turn (sidebands "
        "BPFI +- f_r)."
    )

    def params(self, record) -> list[Param]:
        return [
            Param("inner_defect_width_m", 0.0, 0.0, MAX_DEFECT_WIDTH_M, scale=1e-4, description="groove width along the raceway [m]"),
            Param("inner_defect_angle_rad", 0.0, -2 * np.pi, 2 * np.pi, scale=0.05,
                  description="groove angle from the sensor at the first sample [rad]"),
        ]

    def starts(self, ctx):
        """The groove's start angle modulo a pitch from where the residual's energy piles up over the
        roller-to-groove angle, then each of the Z angles one pitch apart, scanned with a 0.5 mm groove.

        A roller meets the groove where phi + j pitch = theta(t), theta = theta_0 + (phi - phi_0) / r
        (r = FTF / f_r): the events sit at one value of y = phi (1 - 1/r) + phi_0 / r modulo a pitch,
        namely theta_0.
        """
        rig = ctx.record.rig
        pitch = rig.pitch_rad
        phi = cage_phase_of(ctx)
        r = rig.ftf_ratio() * (1 - ctx.values.get("cage_slip_ratio", 0.0))
        phi0 = ctx.values.get("start_phase_rad", 0.0)
        y = phi * (1 - 1 / r) + phi0 / r
        a0 = fold_peak(ctx.residual_V, y, pitch, 180)
        trials = [
            {"inner_defect_width_m": TRIAL_WIDTH_M, "inner_defect_angle_rad": float(np.angle(np.exp(1j * (a0 + k * pitch))))}
            for k in range(rig.geometry.n_rollers)
        ]
        return [_width_start(s, "inner_defect_width_m") for s in scan(ctx, trials)] or [
            {"inner_defect_width_m": TRIAL_WIDTH_M}
        ]

    def summary(self, values):
        return (
            f"width {values['inner_defect_width_m'] * 1e3:.3f} mm, at "
            f"{np.degrees(values['inner_defect_angle_rad']):.1f} deg from the sensor at t = 0"
        )


EFFECT = InnerRaceDefect()
