"""Stage of rule fault_type_voltage: the sensor voltage of one more fault type for the classification, from the
bearing chain (LPM, housing mesh and solve) through the sensor_voltage rule's function.

Apart from :mod:`piezobearing.stages.signals` because it runs the bearing's and the housing's models (numba,
sfepy): the signal rules load neither.
"""

from __future__ import annotations

from ..chain import signals as outputs
from ..chain.bearing import fault_type_force
from ..io import write_csv
from .signals import sensor_voltage


def fault_type_voltage(fault_type: str, resistance_json: str, harmonic_csv: str | None, out_force_csv: str,
                       out_csv: str, out_json: str, config: dict) -> None:
    """The sensor force and voltage of one more fault type for the classification →
    fault_types/{sensor_force,voltage}_{type}.csv, voltage_{type}.json.

    The faulty case's first defect as a ``fault_type`` defect (:func:`~piezobearing.chain.signals.fault_type_config`)
    through the bearing chain's functions (:func:`piezobearing.chain.bearing.fault_type_force`: LPM, housing
    mesh, reduced housing solve) and the sensor_voltage rule's function.
    """
    cfg = outputs.fault_type_config(config, fault_type)
    force = fault_type_force(cfg)
    write_csv(force, out_force_csv, "%.9g")
    sensor_voltage(out_force_csv, resistance_json, harmonic_csv, out_csv, out_json, cfg)
