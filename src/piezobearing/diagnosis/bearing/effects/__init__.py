"""The running bearing's catalogue: effects the healthy, nominal chain leaves out.

======================  ==========================================================
identifier              what it models
======================  ==========================================================
``outer_race_defect``   a groove on the outer raceway (width, angle from the sensor)
``inner_race_defect``   a groove on the inner raceway, turning with the shaft
``rolling_element_defect``  a pit on one roller, meeting both raceways
``cage_slip``           the cage lags the kinematic speed
``shaft_speed``         the shaft's speed outside the baseline's tolerance
``radial_load``         another radial load than believed
``clearance``           another radial internal clearance than believed
``load_share``          the share of the force the mounting passes to the PZT
``roller_scatter``      the rollers' diameters differ by micrometres
``mains_pickup``        50/60 Hz interference and its odd harmonics
``shaft_dynamics``      the shaft's mass on its rollers (the dynamic rung)
``housing_mode``        a housing mode between rollers and sensor (the rung above)
======================  ==========================================================

``shaft_dynamics`` is a rung of the model, not a candidate of the quasi-static search
(:data:`RUNGS`): an evaluation with it costs 12-50 times one without (0.08-0.24 s against 3-9 ms for a 2 s record
at 2550 Hz, benchmarks/bench_shaft_dynamics.py), and alone on a healthy bearing it changes
the record by less than the noise. The subject adds it where the quasi-static model leaves a fault's lines or
rings (:mod:`..rung`), or from the rig file (``bearing_diagnosis.effects``). ``housing_mode`` rides on it (a mode on
the dynamic rung's fine grid): the subject tries it where the dynamic rung is accepted and still leaves the record
``unexplained``, and with the shaft's dynamics where the rig file gives the mode (``bearing_diagnosis.housing_mode_Hz``).
"""

from __future__ import annotations

from ...effect import Catalogue
from . import (
    cage_slip,
    clearance,
    housing_mode,
    inner_race_defect,
    load_share,
    mains_pickup,
    outer_race_defect,
    radial_load,
    roller_scatter,
    rolling_element_defect,
    shaft_dynamics,
    shaft_speed,
)
from .base import Effect

CATALOGUE = Catalogue("bearing")
for _m in (
    outer_race_defect,
    inner_race_defect,
    rolling_element_defect,
    cage_slip,
    shaft_speed,
    radial_load,
    clearance,
    load_share,
    roller_scatter,
    mains_pickup,
    shaft_dynamics,
    housing_mode,
):
    CATALOGUE.register(_m.EFFECT)

#: The effects that are a fault, and the fault type each names in ``fault.type``.
FAULT_TYPES = {
    "outer_race_defect": ("outer_race", "outer_defect_width_m", "outer_defect_angle_rad"),
    "inner_race_defect": ("inner_race", "inner_defect_width_m", "inner_defect_angle_rad"),
    "rolling_element_defect": ("rolling_element", "roller_defect_width_m", "roller_defect_spin_rad"),
}

#: Rungs of the model: effects the quasi-static search does not rank; the subject adds them (:data:`CATALOGUE`
#: holds them, so a rig file may switch them on).
RUNGS = ("shaft_dynamics", "housing_mode")

__all__ = ["CATALOGUE", "FAULT_TYPES", "RUNGS", "Effect"]
