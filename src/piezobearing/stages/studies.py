"""Stage functions of the parameter studies (rules study_case, study_summary).

Each study kind runs, per case, only the rules its varied keys affect, in process and in memory, and reduces
them to one summary row (the case's summary.json, its only file). A kind runs the workflow's own code path:
the functions the rules' stages call (:mod:`piezobearing.chain.bearing`, :mod:`piezobearing.chain.signals`;
:func:`workflow_chain` from the bearing to the fault indicator), each output handed on as the next rule reads
it back from its file, so a case's results equal the workflow's for the same config to the bit and a change
to a rule changes every study.
"""

from __future__ import annotations

import copy
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from ..bearing.geometry import BearingGeometry
from ..chain import bearing as bearing_outputs
from ..chain import calibration as sensor_outputs
from ..chain import signals as signals_outputs
from ..comparison import calibrated
from ..config.cases import case_config
from ..diagnosis.calibration.record import check_record
from ..housing import transient as bearing_transient
from ..housing.transient import CASES
from ..io import (
    FORCE_CSV_FORMAT,
    as_read,
    json_as_read,
    kinematics_of,
    measurement_as_read,
    read_harmonic,
    read_json,
    read_kinematics,
    read_series,
    table_series,
    write_json,
)
from ..plotting import save, use_style
from ..plotting import sensor_comparison as comparison_figures
from ..plotting.studies import SUMMARY_FIGURES
from ..sensor import design as sensor_design
from ..sensor import fem as sensor_fem
from ..sensor.analysis import SensorFemParams
from ..sensor.calibration import SensorCircuit, design_resistance_ohm
from ..sensor.mesh import stack_mesh
from ..signals import daq, detection
from ..signals.detectors import is_alarm
from ..signals.envelope import EnvelopeSettings
from .sensor_comparison import study_case as sensor_comparison_case


def calibration_circuit_case(config: dict, outdir: Path) -> dict:
    """Synthesis, sensitivity, resistance fit and low-frequency limit for one case: the calibration rules'
    functions (:mod:`piezobearing.chain.calibration`) in memory, the synthetic record as extract_sensitivity and
    fit_resistance read it back from measurement.csv (with the reader's checks)."""
    m = measurement_as_read(sensor_outputs.synthesize_calibration(config), "measurement.csv")
    imps = check_record(m, config, m.source)
    s = json_as_read(sensor_outputs.extract_sensitivity(m, imps, config))
    r = json_as_read(sensor_outputs.fit_resistance(m, config)[0])
    lf = json_as_read(sensor_outputs.lowfreq(r["resistance_ohm"], config)[0])
    return {
        "impulse_sensitivity_V_per_N": s["sensitivity_V_per_N"],
        "resistance_fitted_ohm": r["resistance_ohm"],
        "resistance_ci95_ohm": r["resistance_ci95_ohm"],
        "tau_s": r["tau_s"],
        "nrmse": r["nrmse"],
        "linear_from_Hz": lf["linear_from_Hz"],
        "reference_sensitivity_V_per_N": lf["reference_sensitivity_V_per_N"],
        "open_circuit_sensitivity_V_per_N": lf["open_circuit_sensitivity_V_per_N"],
    }


def workflow_chain(config: dict, resistance: dict, harmonic=None, resistance_source: str = "resistance.json") -> dict:
    """The workflow's rules from the bearing to the fault indicator for one config, in memory.

    bearing_lpm, housing_mesh and housing_transient, sensor_voltage, noisy, envelope (healthy and faulty) and
    fault_indicator: each rule's own function (:mod:`piezobearing.chain.bearing`,
    :mod:`piezobearing.chain.signals`), called as its stage calls it, each output handed to the next rule as
    that rule reads it back from the file (:func:`piezobearing.io.as_read`, :func:`piezobearing.io.json_as_read`:
    the CSVs' digits), so the results are the workflow's to the bit and no file is written. ``resistance``: the
    fit_resistance record; ``harmonic``: the sensor FEM's (frequency, |V/F|) where
    ``signals.sensor_fem_correction``, else None.

    Returns the records by rule (``kinematics``, ``lpm``, per case ``transient``, ``voltage`` (t, v, dt),
    ``noisy`` (y, v, dt, record), ``envelope`` (table, record)) and ``indicator`` (fault_indicator.json).
    """
    lpm = bearing_outputs.bearing_lpm(config)
    kin = kinematics_of(json_as_read(lpm["kinematics"]), "kinematics.json")
    circuit = signals_outputs.sensor_circuit(config, resistance, resistance_source)
    out = {"kinematics": kin, "lpm": json_as_read(lpm["summary"]), "transient": {}, "voltage": {}, "noisy": {},
           "envelope": {}}
    for c in CASES:
        mesh, _ = bearing_outputs.housing_mesh(c, config)
        tr = bearing_outputs.housing_transient(c, mesh, lpm["contact"][c], config)
        del mesh
        out["transient"][c] = json_as_read(tr["summary"])
        force = table_series(as_read(tr["force"], FORCE_CSV_FORMAT), "force_N", f"sensor_force_{c}.csv")
        volt, _ = signals_outputs.sensor_voltage(*force, circuit, harmonic, config, f"sensor_force_{c}.csv")
        out["voltage"][c] = table_series(as_read(volt), "voltage_V", f"voltage_{c}.csv")
        table, record = signals_outputs.noisy(*out["voltage"][c], c, config)
        table = as_read(table)
        _, y, dt = table_series(table, "voltage_V", f"noisy_{c}.csv")
        _, v, _ = table_series(table, "noiseless_V", f"noisy_{c}.csv")
        out["noisy"][c] = (y, v, dt, json_as_read(record))
        env, env_record = signals_outputs.envelope(y, v, dt, kin, config)
        out["envelope"][c] = (as_read(env), json_as_read(env_record))
    envelopes = {c: rec for c, (_, rec) in out["envelope"].items()}
    out["indicator"] = json_as_read(signals_outputs.fault_indicator(envelopes, kin, out["noisy"], config))
    return out


def _chain_of_case(config: dict, resistance: str, harmonic: str | None) -> tuple[dict, dict]:
    """The case's config (the housing's reduced solve only: ``housing.method`` = reduced, no direct check) and
    :func:`workflow_chain` on it, with the workflow's fitted ``resistance`` JSON and, if
    ``signals.sensor_fem_correction``, the sensor FEM's ``harmonic`` CSV."""
    cfg = copy.deepcopy(config)
    cfg["housing"].update(method="reduced", direct_check_s=0.0)
    if cfg["signals"]["sensor_fem_correction"] and not harmonic:
        raise ValueError(
            "signals.sensor_fem_correction is on but no sensor FEM response was given; "
            "pass results/sensor/harmonic.csv as input 'harmonic'"
        )
    fem = read_harmonic(harmonic) if cfg["signals"]["sensor_fem_correction"] else None
    return cfg, workflow_chain(cfg, read_json(resistance), fem, resistance)


def fault_detection_case(config: dict, outdir: Path, resistance: str, harmonic: str | None = None) -> dict:
    """Bearing LPM, housing (reduced), voltage, noise over seeds, envelope and indicator for one case.

    The workflow's chain (:func:`workflow_chain`, in memory: the case writes its summary only), then the
    indicator at ``signals.snr_dB`` over ``signals.study_n_seeds`` noise replicates (replicate 0 is the
    noisy rule's record).
    """
    cfg, run = _chain_of_case(config, resistance, harmonic)
    return _fault_detection_row(cfg, run)


def _fault_detection_row(cfg: dict, run: dict) -> dict:
    """The fault_detection summary row of a case's chain (:func:`workflow_chain`)."""
    s, b, kin = cfg["signals"], cfg["bearing"], run["kinematics"]
    f0 = kin["bpfo_Hz"]
    # time a roller centre takes to cross the (first) groove (it sinks over this arc; lpm.chord_drop_m)
    crossing_s = b["defects"][0]["width_m"] / (
        BearingGeometry.from_config(b).outer_raceway_radius_m * 2 * np.pi * kin["ftf_Hz"]
    )
    es, ins = EnvelopeSettings.from_config(s), detection.IndicatorSettings.from_config(s)
    rows = []
    for c in CASES:
        _, v, dt = run["voltage"][c]
        rows += detection.snr_sweep(v, dt, f0, c, [s["snr_dB"]], s["study_n_seeds"], cfg["seed"], es, ins)
    seeds = pd.DataFrame(rows)
    ind, lpm, tr = run["indicator"], run["lpm"], run["transient"]
    by = {c: seeds[seeds["case"] == c] for c in CASES}
    return {
        "bpfo_Hz": f0,
        "snr_dB": s["snr_dB"],
        "n_seeds": s["study_n_seeds"],
        "band_rule": s["band_rule"],
        "indicator_healthy": float(np.median(by["healthy"]["indicator"])),
        "indicator_faulty": float(np.median(by["faulty"]["indicator"])),
        "threshold": float(seeds["threshold"].max()),
        "detection_rate_healthy": float(by["healthy"]["detected"].mean()),
        "detection_rate_faulty": float(by["faulty"]["detected"].mean()),
        "noiseless_indicator_healthy": ind["healthy"]["noiseless"]["indicator"],
        "noiseless_indicator_faulty": ind["faulty"]["noiseless"]["indicator"],
        "in_band_snr_healthy_dB": ind["healthy"]["in_band_snr_dB"],
        "in_band_snr_faulty_dB": ind["faulty"]["in_band_snr_dB"],
        "defect_max_drop_m": lpm["faulty"]["defect_max_drop_m"],
        "defect_crossing_s": crossing_s,
        "defect_crossing_steps": crossing_s / b["time_step_s"],
        "sensor_force_peak_to_peak_healthy_N": tr["healthy"]["sensor_force_max_N"]
        - tr["healthy"]["sensor_force_min_N"],
        "sensor_force_peak_to_peak_faulty_N": tr["faulty"]["sensor_force_max_N"]
        - tr["faulty"]["sensor_force_min_N"],
    }


def sensor_design_housing(out_json: str, config: dict) -> None:
    """Rule sensor_design_housing: :func:`piezobearing.chain.bearing.sensor_port`, written."""
    write_json(bearing_outputs.sensor_port(config), out_json)


def sensor_design_case(
    config: dict,
    outdir: Path,
    resistance: str,
    force_healthy: str,
    force_faulty: str,
    kinematics: str,
    housing: str,
) -> dict:
    """One sensor design: its FEM figures of merit, its load share in the housing, detection at the DAQ's noise.

    1. The stack (``sensor``, ``sensor_fem``) on the study's mesh (``sensor_fem.design_mesh_multiplier``)
       with its measuring circuit (``sensor.daq_resistance_ohm``, or the workflow's fitted ``resistance``
       where null; cable plus DAQ capacitance): :func:`piezobearing.sensor.design.design_figures`.
    2. The load share: the sensor force per newton of radial roller load with a roller over the sensor.
       The sensor is a rank-one spring on the housing, so its stiffness scales the whole influence line by
       one factor (:func:`piezobearing.housing.fem.spring_share_factor`, from the ``housing``
       file of :func:`sensor_design_housing`); a design with another contact disk gets its own housing model
       (:func:`piezobearing.chain.bearing.design_load_share`).
    3. The workflow's sensor force records (``force_healthy``/``force_faulty``, made with the configured
       design) scaled by the ratio of this design's load share to the configured one: exact for the
       quasi-static force (the dynamic part is below 1e-4 of it, docs/theory/bearing_housing.md), approximate for another contact disk.
    4. Voltage through this design's RC circuit with its own FEM's gain and time constant (d33_eff /
       (C_FEM + C_circuit), tau = R (C_FEM + C_circuit): the static limit of the design's harmonic response;
       the row's ``sensor_model`` says so and ``fem_factor`` gives that gain over the design's RC gain
       d33 / C, the number the workflow's one sensor model, :mod:`piezobearing.sensor.response`, multiplies
       the RC gain by; for the configured design the two gains agree within 0.2 %,
       tests/test_sensor_design.py), exact for piecewise-linear
       force, started in its periodic steady state for the force's period), the first ``signals.skip_s``
       dropped, sampled by the DAQ at ``signals.sample_rate_Hz`` as the noisy rule does (:func:`piezobearing.signals.daq.sample`); the DAQ's absolute noise and ADC
       (:func:`noise_settings`); the envelope indicator over ``signals.study_n_seeds`` replicates.
    """
    s, f = config["sensor"], config["sensor_fem"]
    p = SensorFemParams.from_config(config)
    r_ohm = design_resistance_ohm(s, read_json(resistance)["resistance_ohm"])
    circuit = sensor_fem.MeasuringCircuit(r_ohm, p.cable_capacitance_F)
    mesh = stack_mesh(p.geometry, p.density, f["design_mesh_multiplier"])
    settings = sensor_design.DesignSettings(
        order=p.order,
        damping_ratio=p.damping_ratio,
        n_ritz_modes=p.n_ritz_modes,
        reference_frequency_Hz=p.reference_frequency_Hz,
        band_ratio_dB=p.band_ratio_dB,
        linear_tolerance=config["lowfreq"]["deviation_threshold"],
    )
    figs = sensor_design.design_figures(mesh, p.materials, circuit, settings)

    rc_gain = SensorCircuit.from_config(s, r_ohm).open_circuit_gain_V_per_N
    port = read_json(housing)
    spring = bearing_transient.sensor_spring(config)
    share = bearing_outputs.design_load_share(config, port, spring)
    kin = read_kinematics(kinematics)
    sg = config["signals"]
    voltages, p2p = {}, {}
    for case, path in (("healthy", force_healthy), ("faulty", force_faulty)):
        t, force, dt = read_series(path, "force_N")
        # the sensor_voltage rule's RC step, with this design's gain and time constant
        v = signals_outputs.rc_record(t, force * (share / port["load_share"]), dt, figs["open_circuit_gain_V_per_N"],
                                      figs["tau_s"], sg["skip_s"],
                                      signals_outputs.sensor_force_period_s(config["bearing"]), path)[2]
        p2p[case] = float(np.ptp(v))
        # the noisy rule's DAQ: anti-alias filter and sampling at signals.sample_rate_Hz (as is on its clock)
        smp = daq.sample(v, dt, sg["sample_rate_Hz"])
        voltages[case], dt_daq = smp.voltage_V, smp.dt_s
    det = sensor_design.detection_at_noise(
        voltages, dt_daq, kin["bpfo_Hz"], noise_settings(config), sg["study_n_seeds"], config["seed"],
        EnvelopeSettings.from_config(sg), detection.IndicatorSettings.from_config(sg),
        sg["study_required_detection_rate"],
    )
    return {
        "material": s["material"],
        "pzt_diameter_m": s["pzt_diameter_m"],
        "pzt_thickness_m": s["pzt_height_m"],
        "bottom_disk_diameter_m": f["bottom_disk_diameter_m"],
        "bottom_disk_thickness_m": f["bottom_disk_height_m"],
        "top_disk_diameter_m": f["top_disk_diameter_m"],
        "top_disk_thickness_m": f["top_disk_height_m"],
        "adhesive_thickness_m": f["adhesive_height_m"],
        "cable_length_m": s["cable_length_m"],
        "daq_capacitance_F": s["daq_capacitance_F"],
        **figs,
        "sensor_model": "this design's stack FEM: gain d33_eff / (C_FEM + C_circuit), tau = R (C_FEM + C_circuit)",
        "fem_factor": figs["open_circuit_gain_V_per_N"] / rc_gain,
        "sensor_spring_N_per_m": spring,
        "load_share": share,
        "load_share_configured": port["load_share"],
        "voltage_peak_to_peak_healthy_V": p2p["healthy"],
        "voltage_peak_to_peak_faulty_V": p2p["faulty"],
        **det,
        "bpfo_Hz": kin["bpfo_Hz"],
        "mesh_multiplier": f["design_mesh_multiplier"],
    }


def noise_settings(config: dict):
    """The DAQ's absolute noise: ``signals.noise`` where the config has it (model forced to absolute), else
    :class:`piezobearing.signals.daq.NoiseSettings`' absolute defaults (1 uV/sqrt(Hz), 24 bits, +-60 V)."""
    if "noise" in config["signals"]:
        return replace(daq.NoiseSettings.from_config(config["signals"]), model="absolute")
    return daq.NoiseSettings(model="absolute")


def detector_case(config: dict, outdir: Path, resistance: str, harmonic: str | None = None) -> dict:
    """The fault_detection case, then the configured detector over noise seeds at the configured DAQ.

    The fault_detection row (:func:`workflow_chain`; its SNR sweep at the model clock), then the
    fault_classification rule's function (sampling at signals.sample_rate_Hz, the configured noise model,
    every seed; no ROC) on the chain's voltages. The row adds: the faulty and healthy classifications, the
    rate at which the faulty case is classified as its true type and the healthy one as none, each type's
    detection rate on the faulty case, and the largest clipped fraction.
    """
    cfg = copy.deepcopy(config)
    cfg["signals"]["detector"]["roc_snr_dB"] = []
    cfg, run = _chain_of_case(cfg, resistance, harmonic)
    row = _fault_detection_row(cfg, run)
    voltages = {c: run["voltage"][c][1:] for c in CASES}
    record, rows, _ = signals_outputs.fault_classification(voltages, run["kinematics"], cfg)
    cm, seeds, ind = json_as_read(record), as_read(rows), run["indicator"]
    faulty = seeds[seeds["case"] == "faulty"]
    true = cm["true_types"]["faulty"]
    row.update({
        "true_type": true,
        "noise_model": cm["noise_model"],
        "sample_rate_Hz": cm["sample_rate_Hz"],
        "fault_type_faulty": ind["faulty"]["fault_type"],
        "fault_type_healthy": ind["healthy"]["fault_type"],
        "correct_rate_faulty": float((faulty["fault_type"] == true).mean()),
        "false_alarm_rate_healthy": float(seeds[seeds["case"] == "healthy"]["fault_type"].map(is_alarm).mean()),
        "clipped_fraction_max": float(seeds["clipped_fraction"].max()),
        **{f"detection_rate_{t}": float(faulty[f"{t}_detected"].mean())
           for t in ("outer_race", "inner_race", "rolling_element")},
        # the faulty case's row of the confusion matrix: share of seeds classified as each type
        **{f"classified_{t}": float((faulty["fault_type"] == t).mean())
           for t in ("outer_race", "inner_race", "rolling_element", "none")},
    })
    return row


#: Study kinds by name: the function that runs one case and returns its summary row. A kind that reads
#: workflow results its varied keys do not affect takes them as keyword arguments (studies.smk: STUDY_INPUTS).
KINDS = {
    "calibration_circuit": calibration_circuit_case,
    "fault_detection": fault_detection_case,
    "daq_noise": detector_case,
    "defect_position": detector_case,
    "fault_type_speed": detector_case,
    "sensor_design": sensor_design_case,
    "sensor_comparison": sensor_comparison_case,
}


#: Columns a kind's summary table derives across its cases, by kind: name -> function of the table.
SUMMARY_COLUMNS = {
    "sensor_comparison": {"smallest_detected_width_m": calibrated.smallest_detected_width},
}


def run_case(
    study: str, case: str, overrides: dict, config: dict, out_json: str, inputs: dict | None = None
) -> None:
    """Run one case of ``study`` with the table row ``overrides``; write its summary.

    ``inputs``: workflow results the kind reads (keyword arguments of its function).
    """
    if study not in KINDS:
        raise KeyError(f"study '{study}' is unknown; known: {', '.join(sorted(KINDS))}")
    cfg = case_config(config, overrides, source=f"study {study}, case {case}")
    outdir = Path(out_json).parent
    outdir.mkdir(parents=True, exist_ok=True)
    row = KINDS[study](cfg, outdir, **(inputs or {}))
    write_json({"study": study, "case": case, "overrides": overrides, "summary": row}, out_json)


def summarize(study: str, case_jsons: list[str], out_csv: str, out_png: str) -> None:
    """Gather the cases into one table and draw the study's summary figure."""
    rows = []
    for p in case_jsons:
        d = read_json(p)
        case = {**d["overrides"], **{k: v for k, v in d["summary"].items() if not isinstance(v, list)}}
        # a kind with several rows per case (one per sensor) lists them under "rows"
        rows.extend([{**case, **r} for r in d["summary"]["rows"]] if "rows" in d["summary"] else [case])
    df = pd.DataFrame(rows)
    if study in SUMMARY_COLUMNS:
        df = df.assign(**{name: f(df) for name, f in SUMMARY_COLUMNS[study].items()})
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)
    use_style()
    save(SUMMARY_FIGURES[study](df), out_png)


def calibrated_figures(case_jsons: list[str], out_healthy: str, out_roc: str) -> None:
    """Rule sensor_comparison_calibrated_figures: the study's healthy statistic distributions and ROC curves from
    its cases' summary.json files."""
    cases = [read_json(p) for p in case_jsons]
    cases.sort(key=lambda c: (c["summary"]["shaft_speed_rpm"], c["summary"]["fault_type"],
                              c["summary"]["defect_width_m"], c["summary"]["roughness_rms_m"],
                              c["summary"]["disturbance_level"]))
    use_style()
    save(comparison_figures.healthy_distributions(cases), out_healthy)
    save(comparison_figures.roc_curves(cases), out_roc)
