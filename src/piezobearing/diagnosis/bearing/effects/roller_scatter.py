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
smaller than roller 0).
"""

from __future__ import annotations

import numpy as np

from ...params import Param
from .base import Effect


class RollerScatter(Effect):
    name = "roller_scatter"
    title = "roller diameter scatter"
    physics = (
        "Rollers differ by micrometres (sorting lots, wear): a larger roller carries more load, so the roller "
        "passages differ roller by roller, repeating once per cage turn (FTF sidebands of BPFO)."
    )

    def params(self, record) -> list[Param]:
        z = record.rig.geometry.n_rollers
        return [
            Param(f"roller_{k}_offset_m", 0.0, -10e-6, 10e-6, scale=1e-7,
                  description=f"diameter deficit of roller {k} against roller 0 [m]")
            for k in range(1, z)
        ]

    def summary(self, values):
        off = np.array([values[k] for k in sorted(values) if k.startswith("roller_")])
        return f"diameter deficits {np.round(off * 1e6, 2).tolist()} um (rms {np.sqrt(np.mean(off**2)) * 1e6:.2f} um)"


EFFECT = RollerScatter()
