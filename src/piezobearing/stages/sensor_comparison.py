"""Stage of the rule sensor_comparison and the study kind of the same name: the embedded sensor against the
housing accelerometer (:mod:`piezobearing.comparison.rig`) on the housing models of the rule
sensor_comparison_housing (:mod:`piezobearing.housing.reduced`), the results written.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd

from ..bearing.geometry import BearingGeometry, kinematic_frequencies
from ..chain import signals as signal_outputs
from ..comparison import calibrated
from ..comparison import rig as comparison
from ..io import read_harmonic, read_json, write_csv, write_json
from . import housing_model

#: The two conditions of the main workflow's comparison: the frame at rest, and the configured surroundings.
CONDITIONS = ("without_disturbance", "with_disturbance")


def _inputs(config: dict, resistance_json: str, harmonic_csv: str | None):
    circuit = signal_outputs.sensor_circuit(config, read_json(resistance_json), resistance_json)
    if config["signals"]["sensor_fem_correction"] and not harmonic_csv:
        raise ValueError("signals.sensor_fem_correction is on but no sensor FEM response was given; "
                         "pass results/sensor/harmonic.csv as input 'harmonic'")
    harmonic = read_harmonic(harmonic_csv) if config["signals"]["sensor_fem_correction"] else None
    return circuit, harmonic


def at_rest(config: dict) -> dict:
    """The config with the machine frame at rest (``base_motion.level`` = 0)."""
    cfg = copy.deepcopy(config)
    cfg["base_motion"]["level"] = 0.0
    return cfg


def envelope_spectra(result: dict, condition: str) -> pd.DataFrame:
    """The faulty bearing's first replicate's squared envelope spectrum of each sensor as the envelope detector
    tested it (its chosen band; power over the local median, a noise bin's ratio being Exp(1)): a long table
    of condition, sensor, frequency_Hz, ratio."""
    rows = []
    for s in comparison.SENSORS:
        spec = result["sensors"][s]["detection"]["details"]["spectrum"]
        rows.append(pd.DataFrame({"condition": condition, "sensor": s, "frequency_Hz": spec["frequency_Hz"],
                                  "ratio": spec["ratio"]}))
    return pd.concat(rows, ignore_index=True)


def _summary(result: dict) -> dict:
    """The comparison's JSON record without the records."""
    return {k: v for k, v in result.items() if k != "records"}


def read_housings(config: dict, healthy_npz: str | None, faulty_npz: str | None) -> dict | None:
    """The healthy and faulty housing models of rule sensor_comparison_housing, checked against ``config``; None
    without files (the comparison then builds them itself)."""
    if healthy_npz is None and faulty_npz is None:
        return None
    reads = housing_model.housing_reads(config)
    return {False: housing_model.load_housing(healthy_npz, False, reads), True: housing_model.load_housing(faulty_npz, True, reads)}


def sensor_comparison(resistance_json: str, harmonic_csv: str | None, housing_healthy: str, housing_faulty: str,
                      out_json: str, out_spectra: str, config: dict) -> None:
    """Rule sensor_comparison: the paper's case seen by both sensors, with the frame at rest and under the
    configured base motion; sensor_comparison.json and the envelope spectra for the figure. ``housing_*``: the
    housing's models (rule sensor_comparison_housing)."""
    circuit, harmonic = _inputs(config, resistance_json, harmonic_csv)
    settings = comparison.ComparisonSettings.from_config(config)
    housings = read_housings(config, housing_healthy, housing_faulty)
    results, spectra = {}, []
    for condition, c in zip(CONDITIONS, (at_rest(config), config), strict=True):
        res = comparison.compare(c, circuit, harmonic, housings, keep_records=True, floor_per_seed=False)
        spectra.append(envelope_spectra(res, condition))
        results[condition] = _summary(res)
    b = config["bearing"]
    kin = kinematic_frequencies(BearingGeometry.from_config(b), b["shaft_speed_rpm"] / 60.0)
    write_json({
        "definition": (
            "per condition and sensor: detection_rate = share of seeds on the faulty bearing the envelope "
            "detector calls the true fault type; false_alarm_rate = share of seeds on the healthy bearing it "
            "calls any fault; margin_dB = median over seeds of the true family's 10 log10(statistic / threshold); "
            "detection: the first seed's Detection. The bearing has its floor (sensor_comparison.bearing_floor: "
            "roughness, waviness, unbalance). Frame at rest: one realisation of the rig per case (the first "
            "seed's floor), the seeds draw both DAQs' noise; under base motion each seed is a new realisation of "
            "the floor, of the base motion (through the LPM and the housing) and of both DAQs' noise. The "
            "calibrated test with independent realisations is the study's (study_sensor_comparison)."
        ),
        "kinematics": kin.to_dict(),
        "shaft_speed_rpm": b["shaft_speed_rpm"],
        "defect_width_m": b["defects"][0]["width_m"] if b["defects"] else None,
        "model_time_step_s": settings.time_step_s,
        "accelerometer_model": config["accelerometer"]["model"],
        **results,
        "config": {k: config[k] for k in ("seed", "bearing", "housing", "signals", "base_motion", "accelerometer",
                                           "sensor_comparison")},
    }, out_json)
    write_csv(pd.concat(spectra, ignore_index=True), out_spectra)


def study_case(config: dict, outdir: Path, resistance: str, harmonic: str | None = None,
               housing_healthy: str | None = None, housing_faulty: str | None = None) -> dict:
    """Study kind sensor_comparison: one case (speed, fault, disturbance level, mounting place) compared by the
    calibrated test (:mod:`piezobearing.comparison.calibrated`): ``sensor_comparison.n_healthy_seeds`` and
    ``n_faulty_seeds`` independent realisations of the rig.

    ``housing_*``: the case's housing models (rule sensor_comparison_housing); without them the case builds
    its own. Returns the case's summary with ``rows``: one per sensor (the study's summary.csv rows), and
    ``per_seed``: per sensor the true family's margin on every healthy and faulty seed (the ROC's and the
    healthy distribution's figures).
    """
    circuit, harmonic_fem = _inputs(config, resistance, harmonic)
    c = config["sensor_comparison"]
    res = comparison.compare(config, circuit, harmonic_fem, read_housings(config, housing_healthy, housing_faulty),
                             n_seeds=(c["n_healthy_seeds"], c["n_faulty_seeds"]))
    tests = calibrated.evaluate(res, c)
    b = config["bearing"]
    floor = c["bearing_floor"]
    common = {
        "shaft_speed_rpm": b["shaft_speed_rpm"],
        "fault_type": res["fault_type"],
        "defect_width_m": b["defects"][0]["width_m"] if b["defects"] else 0.0,
        "accelerometer_position": res["accelerometer_position"],
        "disturbance_level": config["base_motion"]["level"],
        "disturbance_rms_m_per_s2": res["disturbance_rms_m_per_s2"],
        "n_seeds": res["n_seeds"],
        "false_alarm_probability": res["false_alarm_probability"],
        "roughness_rms_m": floor["roughness_rms_m"],
        "waviness_rms_m": float(np.sqrt(0.5 * np.sum(np.square(floor["waviness_amplitudes_m"])))),
        "unbalance_kg_m": floor["unbalance_kg_m"],
    }
    rows = []
    for s in comparison.SENSORS:
        r = res["sensors"][s]
        rows.append({"sensor": s, **common, "detection_rate": r["detection_rate"],
                     "false_alarm_rate": r["false_alarm_rate"], "margin_dB": r["margin_dB"],
                     "margin_over_healthy_dB": r["margin_over_healthy_dB"],
                     "detection_rate_over_healthy": r["detection_rate_over_healthy"],
                     "band_low_Hz": r["detection"]["band_Hz"][0], "band_high_Hz": r["detection"]["band_Hz"][1],
                     "clean_rms_V": r["levels"]["faulty"]["clean_rms_V"],
                     "noise_std_V": r["levels"]["faulty"]["noise_std_V"],
                     "clipped_samples": r["clipped_samples"], **tests[s]})
    per_seed = [{"sensor": s, "healthy_margin_dB": res["sensors"][s]["healthy_margin_dB_per_seed"],
                 "faulty_margin_dB": res["sensors"][s]["margin_dB_per_seed"],
                 "called_healthy": res["sensors"][s]["called_healthy"],
                 "called_faulty": res["sensors"][s]["called_faulty"]} for s in comparison.SENSORS]
    housing = res["housing"]["faulty"]
    return {**common, "rows": rows, "per_seed": per_seed, "housing_n_modes": housing["n_modes"],
            "housing_first_mode_Hz": housing["first_mode_Hz"],
            "housing_effective_mass_fraction_y": housing["effective_mass_fraction_y"],
            "housing_effective_mass_fraction_z": housing["effective_mass_fraction_z"]}

