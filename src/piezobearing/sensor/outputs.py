"""What the rules of the calibration chain write, in memory: one function per rule (synthesize_calibration,
extract_sensitivity, fit_resistance, lowfreq_sensitivity), the inputs' contents in (the record, the fitted R),
the outputs' contents out (records as dicts, tables as DataFrames).

The stages in :mod:`piezobearing.stages.calibration` read the files, call one of these and write what it
returns; the calibration_circuit study (:mod:`piezobearing.stages.studies`) calls the same functions and hands
the contents on in memory (:func:`piezobearing.io.measurement_as_read`), so a study case runs the workflow's
code path, not a copy of it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..diagnosis.least_squares import nrmse
from ..io import Measurement
from ..synthesis import PressProtocol, synthesize
from . import calibration as cal
from .lowfreq import asymptote_onset_Hz, lowfreq_sensitivity


def nominal_circuit(config: dict, resistance_ohm: float | None = None) -> cal.SensorCircuit:
    """The sensor circuit of the config, with R from the synthesis truth unless given."""
    r = config["synthesis"]["resistance_ohm"] if resistance_ohm is None else resistance_ohm
    return cal.SensorCircuit.from_config(config["sensor"], r)


def synthesize_calibration(config: dict) -> Measurement:
    """Rule synthesize_calibration: the synthetic calibration record (measurement.csv)."""
    syn = config["synthesis"]
    return synthesize(PressProtocol.from_config(syn), nominal_circuit(config), config["seed"], syn["hidden_effects"])


def extract_sensitivity(m: Measurement, imps: list[cal.Impulse], config: dict) -> dict:
    """Rule extract_sensitivity: peak voltage over peak force per impulse (sensitivity.json) of the record ``m``
    and its impulses ``imps`` (the calibration subject's reader)."""
    out = cal.sensitivity_summary(imps, m.time_s)
    for d, imp in zip(out["impulses"], imps, strict=True):
        d.update(
            time_voltage_peak_s=float(m.time_s[imp.voltage_peak_index]),
            window_s=[float(m.time_s[imp.start]), float(m.time_s[imp.stop - 1])],
        )
    out.update(
        source=m.source, sample_rate_Hz=m.sample_rate_Hz, config={"calibration": config["calibration"]}
    )
    return out


def fit_resistance(m: Measurement, config: dict) -> tuple[dict, pd.DataFrame]:
    """Rule fit_resistance: R of Eq. 6 fitted to the record ``m`` (resistance.json) and the simulated voltage
    beside the record (fit.csv)."""
    circuit = nominal_circuit(config)
    res = cal.fit_resistance(
        m.force_N, m.voltage_V, m.dt_s, circuit, config["calibration"]["initial_resistance_ohm"]
    )
    r = res.values["resistance_ohm"]
    fitted = circuit.with_resistance(r)
    sim = cal.circuit_voltage(m.force_N, m.dt_s, fitted)
    record = {
        "resistance_ohm": r,
        "resistance_ci95_ohm": res.ci95["resistance_ohm"],
        "resistance_stderr_ohm": res.stderr["resistance_ohm"],
        "nrmse": nrmse(res.residual, m.voltage_V),
        "residual_rms_V": float(np.sqrt(np.mean(res.residual**2))),
        "pzt_capacitance_F": fitted.pzt_capacitance_F,
        "cable_capacitance_F": fitted.cable_capacitance_F,
        "capacitance_F": fitted.capacitance_F,
        "tau_s": fitted.tau_s,
        "open_circuit_gain_V_per_N": fitted.open_circuit_gain_V_per_N,
        "fit": res.report(),
        "source": m.source,
        "config": {"sensor": config["sensor"], "calibration": config["calibration"]},
    }
    table = pd.DataFrame(
        {"time_s": m.time_s, "force_N": m.force_N, "voltage_V": m.voltage_V, "simulated_voltage_V": sim}
    )
    return record, table


def lowfreq(resistance_ohm: float, config: dict) -> tuple[dict, pd.DataFrame]:
    """Rule lowfreq_sensitivity: sensitivity against frequency of the model with the fitted R
    (lowfreq.json, lowfreq.csv)."""
    circuit = nominal_circuit(config, resistance_ohm)
    thr = config["lowfreq"]["deviation_threshold"]
    lf = lowfreq_sensitivity(config["lowfreq"]["frequencies_Hz"], circuit, thr)
    record = {
        "linear_from_Hz": lf.linear_from_Hz,
        "reference_sensitivity_V_per_N": lf.reference_sensitivity_V_per_N,
        "open_circuit_sensitivity_V_per_N": lf.asymptote_V_per_N,
        "asymptote_within_threshold_from_Hz": asymptote_onset_Hz(circuit, thr),
        "deviation_threshold": thr,
        "resistance_ohm": resistance_ohm,
        "tau_s": circuit.tau_s,
        "config": {"sensor": config["sensor"], "lowfreq": config["lowfreq"]},
    }
    table = pd.DataFrame(
        {
            "frequency_Hz": lf.frequency_Hz,
            "sensitivity_V_per_N": lf.sensitivity_V_per_N,
            "deviation_next": lf.deviation_next,
            "deviation_asymptote": lf.deviation_asymptote,
        }
    )
    return record, table
