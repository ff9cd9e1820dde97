"""``roller_scatter``: the rollers' diameters differ by micrometres.

Physics
-------
Rollers of one bearing are sorted into diameter lots of about a micrometre
(ISO 3096 grades); wear and a damaged roller add to it. Against roller
deflections of a micrometre, a roller 1 um larger carries visibly more load
in the load zone: the roller passages over the sensor differ roller by
roller, a pattern repeating once per cage turn (FTF and its harmonics
around every BPFO line).

Model
-----
Each roller's gap grows by its diameter deficit (roller 0, the one at
``start_phase_rad``, is the reference: a common offset is the clearance);
the configuration repeats once per cage turn, tabulated over it.

Parameters: ``roller_{k}_offset_m``, k = 1..Z-1, in [-10, 10] um (positive:
smaller than roller 0); the last, k = Z-1, is held at 0 (a second reference).

What the sensor cannot see: a pattern b sin(2 pi k / Z) over the roller
index k is the inner ring displaced by b perpendicular to roller 0, turning
with the cage: every roller's gap, hence every roller load and the sensor
force, is the same (exactly, for rigid rings). Fitting all Z-1 offsets
left that direction free (at 30 dB the offsets were correlated at
|r| = 0.9999998 pairwise and each 95% interval was +-13 to +-45 um, wider
than the bounds; the fitted pattern minus the hidden one was
-1.35 um x sin(2 pi k / 11) within 0.2 um, measured). Holding roller Z-1
at 0 fixes it (sin(2 pi (Z-1) / Z) is not 0): the fitted pattern is the
one of the indistinguishable family in which rollers 0 and Z-1 have the
same diameter. With ``clearance`` also in the model, a (cos(2 pi k / Z) - 1)
becomes invisible too (a common offset is the clearance): read such a fit's
correlations.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect


class RollerScatter(Effect):
    name = "roller_scatter"
    title = "roller diameter scatter"
    example = {"roller_4_offset_m": 2e-6}
    example_reason = (
        "roller 4 2 um smaller than the rest: the diameter scatter within a roller set is of the order of "
        "micrometres (sorting lots, wear)"
    )
    physics = (
        "Rollers differ by micrometres (sorting lots, wear): a larger roller carries more load, so the roller "
        "passages differ roller by roller, repeating once per cage turn (FTF sidebands of BPFO)."
    )

    def params(self, record) -> list[Param]:
        z = record.rig.geometry.n_rollers
        return [
            Param(f"roller_{k}_offset_m", 0.0, -10e-6, 10e-6, scale=1e-7, vary=k < z - 1,
                  description=f"diameter deficit of roller {k} against roller 0 [m]"
                  + ("" if k < z - 1 else " (held: the sensor cannot see a sin(2 pi k / Z) pattern)"))
            for k in range(1, z)
        ]

    def summary(self, values):
        off = np.array([values[k] for k in sorted(values) if k.startswith("roller_")])
        return f"diameter deficits {np.round(off * 1e6, 2).tolist()} um (rms {np.sqrt(np.mean(off**2)) * 1e6:.2f} um)"


EFFECT = RollerScatter()
