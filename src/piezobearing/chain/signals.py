"""What the rules from the sensor force to the fault indicator write, in memory: one function per rule
(sensor_voltage, noisy, envelope, fault_indicator, fault_classification), the inputs' contents in (time series
as arrays, records as dicts, tables as DataFrames), the outputs' contents out.

The stages in :mod:`piezobearing.stages.signals` read the files, call one of these and write what it returns;
the parameter studies (:mod:`piezobearing.stages.studies`) call the same functions and hand the contents on in
memory (:func:`piezobearing.io.as_read`), so a study case runs the workflow's code path, not a copy of it.
Warnings go to stderr (the rule's log).
"""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd

from ..bearing.geometry import BearingGeometry, kinematic_frequencies
from ..io import SignalFileError
from ..sensor.calibration import SensorCircuit, design_resistance_ohm, rc_voltage
from ..sensor.response import sensor_model
from ..signals import classification, daq, detection, detectors
from ..signals.analysis import INDICATOR_DEFINITION, envelope_analysis


def sensor_circuit(config: dict, resistance: dict, source: str = "resistance.json") -> SensorCircuit:
    """The sensor circuit of ``config["sensor"]`` with R = ``sensor.daq_resistance_ohm``, or where that is null the
    calibration's fitted R (``resistance``: the fit_resistance record, read from ``source``)."""
    if "resistance_ohm" not in resistance:
        raise SignalFileError(f"{source}: key 'resistance_ohm' missing; rerun rule fit_resistance")
    return SensorCircuit.from_config(config["sensor"], design_resistance_ohm(config["sensor"], resistance["resistance_ohm"]))


def sensor_force_period_s(bearing: dict) -> float:
    """The period of the sensor force of a running bearing (``bearing``: the config section) [s].

    The rollers pass the sensor at BPFO (at the mean cage slip, the record's starting speed): with equal rollers
    the force repeats every passage, 1/BPFO (an outer-race defect's impacts too); with a scatter of the roller
    diameters (``bearing.roller_diameter_scatter_m`` > 0) each roller loads the sensor differently and the force
    repeats once the cage has turned once, Z passages (1/FTF). Slip jitter, a speed ramp, an inner-race or a
    rolling-element defect make the force not quite periodic; the period is then the roller passage's.
    """
    geo = BearingGeometry.from_config(bearing)
    bpfo = kinematic_frequencies(geo, bearing["shaft_speed_rpm"] / 60.0, bearing["cage_slip"]).bpfo_Hz
    return (geo.n_rollers if bearing["roller_diameter_scatter_m"] > 0 else 1) / bpfo


def rc_record(t: np.ndarray, force: np.ndarray, dt: float, gain_V_per_N: float, tau_s: float, skip_s: float,
              period_s: float, source: str = "the force record") -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The force [N] through the RC high-pass of gain ``gain_V_per_N`` and time constant ``tau_s`` (exact for a
    piecewise-linear force), the first ``skip_s`` dropped. Returns time [s], force [N], voltage [V] after the
    skip and the samples dropped.

    The circuit starts in its periodic steady state for the force's first ``period_s`` (the roller passage or
    the cage revolution, :func:`sensor_force_period_s`): the sensor of a running bearing has run for a long time, it
    does not start at rest (:func:`~piezobearing.sensor.calibration.rc_voltage`). What the skip then drops
    is the start of the force model and the start's error where the force is not exactly periodic (slip
    jitter, a defect of another period, a speed ramp), which decays as exp(-t / tau).
    """
    skip = int(round(skip_s / dt))
    if skip >= t.size - 8:
        raise SignalFileError(f"{source}: signals.skip_s = {skip_s} s leaves no record; lower it")
    if period_s > (t.size - 1) * dt:
        raise SignalFileError(f"{source}: the record ({t.size * dt:.4g} s) is shorter than one period of the "
                              f"sensor force ({period_s:.4g} s); lengthen bearing.duration_s")
    print(f"sensor_voltage: {t.size} samples, dt = {dt:.6g} s, {skip} dropped; the circuit starts in its "
          f"periodic steady state for the first {period_s:.6g} s", file=sys.stderr)
    v = rc_voltage(force, dt, gain_V_per_N, tau_s, period_s)
    return t[skip:], force[skip:], v[skip:], skip


def sensor_voltage(t: np.ndarray, force: np.ndarray, dt: float, circuit: SensorCircuit, harmonic, config: dict,
                   source: str = "the force record") -> tuple[pd.DataFrame, dict]:
    """Rule sensor_voltage_{case}: the sensor force through the calibrated sensor model.

    The one model of the sensor (:func:`piezobearing.sensor.response.sensor_model`, the diagnosis's too): the
    RC model of Eq. 6 (``circuit``: the fitted or the DAQ's R, the cable) times the sensor FEM's correction,
    the median |H_FEM| / |H_RC| below the Nyquist frequency (the FEM is flat there: its first resonance is near
    100 kHz); ``harmonic``: the sensor FEM's (frequency [Hz], |V/F| [V/N]) where ``signals.sensor_fem_correction``,
    else None. By :func:`rc_record`, started in its periodic steady state for the sensor force's period
    (:func:`sensor_force_period_s`), the first ``signals.skip_s`` dropped. Returns the table (time_s, force_N,
    voltage_V) and the record (voltage_{case}.json without ``source``).
    """
    s = config["signals"]
    model = sensor_model(config, circuit, 0.5 / dt, harmonic)
    t, force, v, skip = rc_record(t, force, dt, model.gain_V_per_N, model.tau_s, s["skip_s"],
                                  sensor_force_period_s(config["bearing"]), source)
    record = {
        "dt_s": dt,
        "sample_rate_Hz": 1.0 / dt,
        "n_samples": int(t.size),
        "duration_s": float(t.size * dt),
        "skipped_s": skip * dt,
        "resistance_ohm": circuit.resistance_ohm,
        "capacitance_F": circuit.capacitance_F,
        "tau_s": circuit.tau_s,
        "open_circuit_gain_V_per_N": circuit.open_circuit_gain_V_per_N,
        "fem_correction": model.correction,
        "sensor_model": model.describe(),
        "voltage_rms_V": float(np.sqrt(np.mean(v**2))),
        "voltage_peak_to_peak_V": float(np.ptp(v)),
        "force_mean_N": float(force.mean()),
        "force_peak_to_peak_N": float(np.ptp(force)),
    }
    return pd.DataFrame({"time_s": t, "force_N": force, "voltage_V": v}), record


def noisy(t: np.ndarray, v: np.ndarray, dt: float, case: str, config: dict) -> tuple[pd.DataFrame, dict]:
    """Rule noisy_{case}: the DAQ: anti-alias filter and sampling at signals.sample_rate_Hz, noise.

    ``signals.noise.model`` relative: white noise at signals.snr_dB,
    SNR = 10 log10(P_s / sigma^2), P_s the mean square of the whole sampled
    noiseless record (the paper). absolute: the DAQ's input noise density,
    mains and drive lines and its ADC; clipped samples are counted in the record
    and named in the log. The table keeps the sampled noiseless record beside
    the noisy one (column noiseless_V).
    """
    s = config["signals"]
    ns = daq.NoiseSettings.from_config(s)
    smp = daq.sample(v, dt, s["sample_rate_Hz"])
    vs, dts = smp.voltage_V, smp.dt_s
    acq = daq.add_noise(vs, dts, ns, detection.noise_rng(config["seed"], case, 0))
    y = acq.voltage_V
    if acq.n_clipped:
        print(f"noisy: warning: {case}: {acq.n_clipped} of {y.size} samples ({100 * acq.clipped_fraction:.2g}%) "
              f"clipped at +-{ns.range_V} V; raise signals.noise.range_V", file=sys.stderr)
    n = y - vs
    table = pd.DataFrame({"time_s": t[0] + np.arange(y.size) * dts, "voltage_V": y, "noiseless_V": vs})
    record = {
        "case": case,
        "snr_dB": s["snr_dB"],
        "snr_definition": "10 log10(mean(v^2) / sigma^2) over the whole noiseless record",
        "noise_model": ns.model,
        "sample_rate_Hz": 1.0 / dts,
        "model_sample_rate_Hz": 1.0 / dt,
        "anti_alias": smp.anti_alias,
        "daq": acq.report(),
        "signal_power_V2": detection.signal_power_V2(vs),
        "noise_std_V": acq.noise_std_V,
        "realised_snr_dB": float(10 * np.log10(detection.signal_power_V2(vs) / np.mean(n**2))),
        "seed": [config["seed"], 6, detection.CASE_CODES[case], 0],
        "config": {"seed": config["seed"], "signals": s},
    }
    return table, record


def envelope(y: np.ndarray, v: np.ndarray, dt: float, kinematics: dict, config: dict) -> tuple[pd.DataFrame, dict]:
    """Rule envelope_{case}: band (kurtogram or fixed) and envelope spectrum of the noisy record ``y`` and, for
    reference, of the sampled noiseless ``v`` in the same band (:func:`..analysis.envelope_analysis`)."""
    s = config["signals"]
    table, record = envelope_analysis(y, v, dt, kinematics["bpfo_Hz"], s)
    return table, {**record, "config": {"signals": s}}


#: What fault_indicator.json's ``detection`` entries hold, by method (signals.detector.statistic).
DETECTION_DEFINITIONS = {
    "envelope": (
        "detection (statistic envelope, piezobearing.signals.detectors.envelope): the Hann squared envelope "
        "spectrum of the configured band; per family the sum over its lines (k x carrier + m x sideband, searched "
        "over the slip range) of the largest power ratio over the local-median floor; threshold: the sum's "
        "(1 - pfa / n_families) quantile under noise alone; margin_dB = 10 log10(statistic / threshold); "
        "fault_type: none if no family is detected, else the detected family of largest margin"
    ),
    "baseline": detectors.baseline.DEFINITION + "; " + detectors.baseline.CLIPPED_DEFINITION,
}


def fault_indicator(envelopes: dict, kinematics: dict, noisy_records: dict, config: dict) -> dict:
    """Rule fault_indicator: the paper's indicator and the configured detector on each case's noisy record.

    ``envelopes`` maps each case to its envelope record (envelope_{case}.json: the band, in-band SNR and the raw
    spectrum's test); ``noisy_records`` each case to its noisy record (y [V], the sampled noiseless v [V],
    dt [s], noisy_{case}.json). Per case: the ``paper`` detector's indicator record (k BPFO over the local floor,
    indicator, threshold, detected; :mod:`.detectors.paper`) on y, and on v in y's band (``noiseless``,
    reference only); ``fault_type`` and ``detection`` (:class:`.detectors.Detection`) of the method of
    ``signals.detector.statistic`` on y, as it judges any record (``baseline``: against the healthy case's
    noiseless record).
    """
    s = config["signals"]
    paper = detectors.paper.Settings.from_config(s)
    healthy = noisy_records.get("healthy")
    chosen = classification.configured_detector(s, kinematics, None if healthy is None else healthy[1:3])
    out = {}
    for case, meta in envelopes.items():
        y, v, dt, nrec = noisy_records[case]
        band = tuple(meta["band_Hz"])
        r = dict(detectors.detect(y, 1.0 / dt, kinematics, "paper", paper).details)
        r["noiseless"] = detectors.detect(v, 1.0 / dt, kinematics, "paper", paper.in_band(band)).details
        r["snr_dB"] = nrec["snr_dB"]
        r["in_band_snr_dB"] = meta["in_band_snr_dB"]
        r["raw_spectrum_test"] = meta["raw_spectrum_test"]
        r["daq"] = nrec.get("daq")
        found = chosen.many([y], dt, kinematics)[0]
        r["fault_type"] = found.fault_type
        r["detection"] = found.to_dict()
        out[case] = r
    out["definition"] = INDICATOR_DEFINITION + "; " + DETECTION_DEFINITIONS[chosen.method]
    out["kinematics"] = kinematics
    out["config"] = {"seed": config["seed"], "signals": s}
    return out


def true_fault_type(bearing: dict) -> str:
    """The faulty case's fault type from the bearing config: ``bearing.defects`` (its single type) or,
    in the configs before the defect list, the outer-race defect."""
    defects = bearing.get("defects")
    if defects is None:
        return "outer_race"
    types = sorted({d["type"] for d in defects})
    if len(types) != 1:
        raise ValueError(f"bearing.defects: {len(types)} fault types ({', '.join(types) or 'none'}); the "
                         "classification needs exactly one true type in the faulty case")
    return types[0]


def fault_type_config(config: dict, fault_type: str) -> dict:
    """The config of rule fault_type_voltage_{type}: the faulty case with one defect, the first of
    ``bearing.defects`` (its width, depth, angle) as a ``fault_type`` defect; the housing by the reduced
    modal solve without the direct check (the main chain checks the method)."""
    d = dict(config["bearing"]["defects"][0], type=fault_type)
    return {**config, "bearing": {**config["bearing"], "defects": [d]},
            "housing": {**config["housing"], "method": "reduced", "direct_check_s": 0.0}}


def fault_classification(voltages: dict, kinematics: dict, config: dict,
                         type_voltages: dict | None = None) -> tuple[dict, pd.DataFrame, pd.DataFrame]:
    """Rule fault_classification: fault type over noise seeds and ROC across SNR.

    ``voltages`` maps healthy and faulty to their voltage (v [V], dt [s]) on the model clock;
    ``type_voltages`` (optional) maps further fault types to theirs (rule fault_type_voltage_{type}), so
    that the confusion matrix has a row per fault type. Each record is sampled at signals.sample_rate_Hz,
    then replicate j adds the configured DAQ noise from noise_rng(seed, case, j) (replicate 0 of healthy
    and faulty is the noisy rule's record). Rows of the confusion matrix: true type (healthy: none),
    columns: classified type. The ROC is the faulty case's. Returns the record (classification.json), the
    per-seed table (classification.csv) and the ROC table (roc.csv).
    """
    s = config["signals"]
    truth = {"healthy": "none", "faulty": true_fault_type(config["bearing"])}
    truth.update({t: t for t in (type_voltages or {})})
    records = {}
    for case, (v, dt) in {**voltages, **(type_voltages or {})}.items():
        smp = daq.sample(v, dt, s["sample_rate_Hz"])
        records[case] = (truth[case], smp.voltage_V, smp.dt_s)
    ns = daq.NoiseSettings.from_config(s)
    chosen = classification.configured_detector(s, kinematics, records["healthy"][1:])
    n = s["study_n_seeds"]
    rng = lambda case, j: detection.noise_rng(config["seed"], case, j)  # noqa: E731
    print(f"classification: {len(records)} cases x {n} seeds", file=sys.stderr, flush=True)
    cm, rows = classification.classify_seeds(records, kinematics, chosen, ns, rng, n)
    roc = []
    if truth["faulty"] != "none":
        print(f"classification: ROC at {len(s['detector']['roc_snr_dB'])} SNRs", file=sys.stderr, flush=True)
        roc = classification.roc_over_snr((truth["faulty"], records["faulty"][1]), records["healthy"][1],
                                          records["faulty"][2], kinematics, chosen, s["detector"]["roc_snr_dB"], rng,
                                          n)
    roc_table = pd.DataFrame([{"snr_dB": r["snr_dB"], "pfa": p, "pd": d} for r in roc
                              for p, d in zip(r["pfa"], r["pd"], strict=True)])
    record = {
        **cm,
        "n_seeds": n,
        "noise_model": ns.model,
        "snr_dB": s["snr_dB"] if ns.model == "relative" else None,
        "sample_rate_Hz": 1.0 / records["faulty"][2],
        "false_alarm_probability": s["false_alarm_probability"],
        "statistic": chosen.method,
        "true_types": truth,
        "roc": [{k: r[k] for k in ("snr_dB", "fault_type", "auc", "detection_rate", "false_alarm_rate")}
                for r in roc],
        "roc_definition": "per SNR (relative noise), the true type's score I/threshold, faulty against "
                          "healthy, over the same seeds; detection_rate/false_alarm_rate at score > 1",
        "config": {"seed": config["seed"], "signals": s},
    }
    return record, pd.DataFrame(rows), roc_table
