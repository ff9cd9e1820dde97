"""Stage functions of the scorecard rules: read a stage area's results, build its rows
(:mod:`piezobearing.scorecard`), write its fragment; and gather the fragments (rule scorecard)."""

from __future__ import annotations

import pandas as pd

from ..io import read_json, read_kinematics
from ..scorecard import assemble, write_part
from ..scorecard import bearing as bearing_rows
from ..scorecard import calibration as calibration_rows
from ..scorecard import sensor_fem as sensor_fem_rows
from ..scorecard import signals as signals_rows
from ..sensor.errors import SensorFemError
from .calibration import nominal_circuit

__all__ = ["assemble", "scorecard_bearing", "scorecard_calibration", "scorecard_sensor_fem", "scorecard_signals"]


def scorecard_bearing(
    kinematics_json: str,
    lpm_json: str,
    transient_jsons: dict,
    convergence_json: str,
    sampling_json: str,
    out_csv: str,
    config: dict,
) -> None:
    """Rows of results/scorecard/bearing.csv (:mod:`piezobearing.scorecard.bearing`)."""
    kin, lpm, conv, samp = (
        read_json(p) for p in (kinematics_json, lpm_json, convergence_json, sampling_json)
    )
    tr = {k: read_json(v) for k, v in transient_jsons.items()}
    write_part(bearing_rows.rows(kin, lpm, tr, conv, samp, config["bearing"]), out_csv)


def scorecard_calibration(
    sensitivity_json: str, resistance_json: str, lowfreq_json: str, out_csv: str, config: dict
) -> None:
    """The calibration rows of the scorecard (:mod:`piezobearing.scorecard.calibration`)."""
    sens, res, lf = read_json(sensitivity_json), read_json(resistance_json), read_json(lowfreq_json)
    c = nominal_circuit(config, res["resistance_ohm"])
    write_part(calibration_rows.rows(sens, res, lf, c, config), out_csv)


def scorecard_sensor_fem(modal_json: str, band_json: str, convergence_csv: str, out_csv: str) -> None:
    """Write results/scorecard/sensor_fem.csv (:mod:`piezobearing.scorecard.sensor_fem`)."""
    modal = read_json(modal_json, ["first_resonance_short_Hz", "modes", "placement_check"], error=SensorFemError)
    band = read_json(band_json, ["band_high_Hz", "band_low_Hz"], error=SensorFemError)
    write_part(sensor_fem_rows.rows(modal, band, pd.read_csv(convergence_csv)), out_csv)


def scorecard_signals(indicator_json: str, study_json: str, kinematics_json: str, out_csv: str) -> None:
    """The Sec. IV rows of the scorecard → results/scorecard/signals.csv (:mod:`piezobearing.scorecard.signals`)."""
    rows = signals_rows.rows(read_json(indicator_json), read_json(study_json), read_kinematics(kinematics_json))
    write_part(rows, out_csv)
