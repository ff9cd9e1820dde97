"""Stage functions of the parameter studies (rules study_case, study_summary).

Each study kind runs, per case, only the stages its varied keys affect, in
process, into the case's own folder, and reduces them to one summary row.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd

from ..bearing.lpm import BearingGeometry
from ..io import read_json, write_json
from ..studies import case_config
from .calibration import extract_sensitivity, fit_resistance, lowfreq, synthesize_calibration


def calibration_circuit_case(config: dict, outdir: Path) -> dict:
    """Synthesis, sensitivity, resistance fit and low-frequency limit for one case."""
    meas = outdir / "measurement.csv"
    synthesize_calibration(config, str(meas))
    extract_sensitivity(str(meas), str(outdir / "sensitivity.json"), config)
    fit_resistance(str(meas), str(outdir / "resistance.json"), str(outdir / "fit.csv"), config)
    lowfreq(
        str(outdir / "resistance.json"), str(outdir / "lowfreq.json"), str(outdir / "lowfreq.csv"), config
    )
    s, r, lf = (read_json(outdir / n) for n in ("sensitivity.json", "resistance.json", "lowfreq.json"))
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


def fault_detection_case(config: dict, outdir: Path, resistance: str, harmonic: str | None = None) -> dict:
    """Bearing LPM, housing (reduced), voltage, noise over seeds, envelope and indicator for one case.

    The stage functions of the bearing and signals areas run in turn into
    ``outdir``, healthy and faulty: bearing_lpm, housing_mesh and
    housing_transient (the reduced modal solve only: ``housing.method`` =
    reduced, no direct check), sensor_voltage (the workflow's fitted
    ``resistance`` JSON and, if ``signals.sensor_fem_correction``, the sensor
    FEM's ``harmonic`` CSV: neither depends on the bearing), noisy, envelope
    and indicator (noise replicate 0: ``fault_indicator.json``), then the
    indicator at ``signals.snr_dB`` over ``signals.study_n_seeds`` noise
    replicates (``seeds.csv``; replicate 0 is the noisy stage's record).
    The large binary intermediates (contact-force NPZ, mesh NPZ and VTK) are
    deleted once used.
    """
    from ..signals import detection as sig
    from . import bearing as brs
    from . import signals as sgs

    cfg = copy.deepcopy(config)
    cfg["housing"].update(method="reduced", direct_check_s=0.0)
    s = cfg["signals"]
    if s["sensor_fem_correction"] and not harmonic:
        raise ValueError(
            "signals.sensor_fem_correction is on but no sensor FEM response was given; "
            "pass results/sensor/harmonic.csv as input 'harmonic'"
        )
    d = Path(outdir)
    cases = brs.CASES
    kin_json = d / "kinematics.json"
    contact = {c: d / f"contact_forces_{c}.npz" for c in cases}
    brs.bearing_lpm(kin_json, contact, {c: d / f"contact_forces_{c}.csv" for c in cases}, d / "lpm.json", cfg)
    for c in cases:
        mesh = d / f"housing_mesh_{c}.npz"
        brs.housing_mesh(c, mesh, d / f"housing_mesh_{c}.vtk", d / f"housing_mesh_{c}.json", cfg)
        brs.housing_transient(
            c,
            mesh,
            contact[c],
            d / f"sensor_force_{c}.csv",
            d / f"housing_modes_{c}.json",
            d / f"housing_transient_{c}.json",
            d / f"influence_line_{c}.csv",
            cfg,
        )
        for p in (mesh, d / f"housing_mesh_{c}.vtk", contact[c]):
            p.unlink()
        sgs.sensor_voltage(
            d / f"sensor_force_{c}.csv",
            resistance,
            harmonic if s["sensor_fem_correction"] else None,
            d / f"voltage_{c}.csv",
            d / f"voltage_{c}.json",
            cfg,
        )
        sgs.noisy(d / f"voltage_{c}.csv", c, d / f"noisy_{c}.csv", d / f"noisy_{c}.json", cfg)
        sgs.envelope(
            d / f"noisy_{c}.csv",
            d / f"voltage_{c}.csv",
            kin_json,
            d / f"envelope_{c}.csv",
            d / f"envelope_{c}.json",
            cfg,
        )
    ind_json = d / "fault_indicator.json"
    sgs.indicator(
        {c: (d / f"envelope_{c}.csv", d / f"envelope_{c}.json") for c in cases},
        kin_json,
        {c: d / f"noisy_{c}.json" for c in cases},
        ind_json,
        cfg,
    )
    kin = sgs.kinematics(kin_json)
    f0 = kin["bpfo_Hz"]
    b = cfg["bearing"]
    # time a roller centre takes to cross the (first) groove (it sinks over this arc; lpm.chord_drop_m)
    crossing_s = b["defects"][0]["width_m"] / (
        BearingGeometry.from_config(b).outer_raceway_radius_m * 2 * np.pi * kin["ftf_Hz"]
    )
    es, ins = sig.EnvelopeSettings.from_config(s), sig.IndicatorSettings.from_config(s)
    rows = []
    for c in cases:
        _, v, dt = sgs.read_series(d / f"voltage_{c}.csv", "voltage_V")
        rows += sig.snr_sweep(v, dt, f0, c, [s["snr_dB"]], s["study_n_seeds"], cfg["seed"], es, ins)
    seeds = pd.DataFrame(rows)
    sgs.write_csv(seeds, d / "seeds.csv")
    ind, lpm = read_json(ind_json), read_json(d / "lpm.json")
    tr = {c: read_json(d / f"housing_transient_{c}.json") for c in cases}
    by = {c: seeds[seeds["case"] == c] for c in cases}
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


def detector_case(config: dict, outdir: Path, resistance: str, harmonic: str | None = None) -> dict:
    """The fault_detection case, then the search detector over noise seeds at the configured DAQ.

    Runs :func:`fault_detection_case` (bearing to fault_indicator.json; its
    SNR sweep at the model clock), then the classification stage (sampling
    at signals.sample_rate_Hz, the configured noise model, every seed; no
    ROC) into ``outdir``. The row adds: the faulty and healthy
    classifications, the rate at which the faulty case is classified as its
    true type and the healthy one as none, each type's detection rate on
    the faulty case, and the largest clipped fraction.
    """
    from . import signals as sgs

    cfg = copy.deepcopy(config)
    cfg["signals"]["detector"]["roc_snr_dB"] = []
    row = fault_detection_case(cfg, outdir, resistance, harmonic)
    d = Path(outdir)
    sgs.classification({c: str(d / f"voltage_{c}.csv") for c in ("healthy", "faulty")}, str(d / "kinematics.json"),
                       str(d / "classification.json"), str(d / "classification.csv"), str(d / "roc.csv"), cfg)
    cm = read_json(d / "classification.json")
    seeds = pd.read_csv(d / "classification.csv")
    ind = read_json(d / "fault_indicator.json")
    faulty = seeds[seeds["case"] == "faulty"]
    true = cm["true_types"]["faulty"]
    row.update({
        "true_type": true,
        "noise_model": cm["noise_model"],
        "sample_rate_Hz": cm["sample_rate_Hz"],
        "fault_type_faulty": ind["faulty"]["fault_type"],
        "fault_type_healthy": ind["healthy"]["fault_type"],
        "correct_rate_faulty": float((faulty["fault_type"] == true).mean()),
        "false_alarm_rate_healthy": float((seeds[seeds["case"] == "healthy"]["fault_type"] != "none").mean()),
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
    from ..plotting import save, use_style
    from ..plotting.studies import SUMMARY_FIGURES

    rows = []
    for p in case_jsons:
        d = read_json(p)
        rows.append({**d["overrides"], **{k: v for k, v in d["summary"].items() if not isinstance(v, list)}})
    df = pd.DataFrame(rows)
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)
    use_style()
    save(SUMMARY_FIGURES[study](df), out_png)
