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

from ..diagnosis.calibration.presses import PressProtocol, synthesize
from ..diagnosis.calibration.record import left_out_samples
from ..fitting.least_squares import nrmse
from ..io import Measurement
from ..sensor import calibration
from ..sensor.lowfreq import asymptote_onset_Hz, lowfreq_sensitivity


def nominal_circuit(config: dict, resistance_ohm: float | None = None) -> calibration.SensorCircuit:
    """The sensor circuit of the config, with R from the synthesis truth unless given."""
    r = config["synthesis"]["resistance_ohm"] if resistance_ohm is None else resistance_ohm
    return calibration.SensorCircuit.from_config(config["sensor"], r)


def synthesize_calibration(config: dict) -> Measurement:
    """Rule synthesize_calibration: the synthetic calibration record (measurement.csv)."""
    syn = config["synthesis"]
    return synthesize(PressProtocol.from_config(syn), nominal_circuit(config), config["seed"], syn["hidden_effects"])


def extract_sensitivity(m: Measurement, imps: list[calibration.Impulse], config: dict) -> dict:
    """Rule extract_sensitivity: peak voltage over peak force per impulse (sensitivity.json) of the record ``m``
    and its impulses ``imps`` (the calibration subject's reader)."""
    # a press whose top was filled across a gap of the clock has the interpolation's peak, not the
    # sensor's: that impulse is left out of the sensitivity (and named), as the diagnosis leaves the samples out
    # (all kept, each flagged, should every peak be filled: a sensitivity needs one impulse)
    lost = [imp for imp in imps if _peak_filled(m, imp)]
    every = len(lost) == len(imps)
    imps = [imp for imp in imps if not _peak_filled(m, imp)] or imps
    out = calibration.sensitivity_summary(imps, m.time_s)
    if lost:
        out["impulses_left_out"] = [
            {
                "time_force_peak_s": float(m.time_s[imp.force_peak_index]),
                "reason": "filled samples in the top half of the press" + (" (kept: every peak is)" if every else ""),
            }
            for imp in lost
        ]
    for d, imp in zip(out["impulses"], imps, strict=True):
        d.update(
            time_voltage_peak_s=float(m.time_s[imp.voltage_peak_index]),
            window_s=[float(m.time_s[imp.start]), float(m.time_s[imp.stop - 1])],
        )
    out.update(
        source=m.source, sample_rate_Hz=m.sample_rate_Hz, config={"calibration": config["calibration"]}
    )
    return out


def _peak_filled(m: Measurement, imp: calibration.Impulse) -> bool:
    """Whether a sample filled across a gap of the clock (or a measured one at a gap's edge) lies in the top half
    of the impulse's force or voltage swing: the true peak may then lie in the gap, and the recorded maximum
    is the interpolation's (or a flank's)."""
    if m.filled is None:
        return False
    w = slice(imp.start, imp.stop)
    near = np.convolve(m.filled[w].astype(float), np.ones(3), mode="same") > 0  # a gap and its edges
    top = np.zeros_like(near)
    for x in (m.force_N[w], m.voltage_V[w]):
        top |= x >= x.min() + 0.5 * (x.max() - x.min())
    return bool(np.any(near & top))


def fit_resistance(m: Measurement, config: dict) -> tuple[dict, pd.DataFrame]:
    """Rule fit_resistance: R of Eq. 6 fitted to the record ``m`` (resistance.json) and the simulated voltage
    beside the record (fit.csv)."""
    circuit = nominal_circuit(config)
    r0 = config["calibration"]["initial_resistance_ohm"]
    # samples filled across gaps of the clock, and the circuit's memory of them: the diagnosis's mask
    left_out = left_out_samples(m, config["diagnostics"]["quiet_settle_s"], circuit.with_resistance(r0).tau_s)
    res = calibration.fit_resistance(m.force_N, m.voltage_V, m.dt_s, circuit, r0, left_out)
    r = res.values["resistance_ohm"]
    fitted = circuit.with_resistance(r)
    sim = calibration.circuit_voltage(m.force_N, m.dt_s, fitted)
    measured = m.voltage_V if left_out is None else m.voltage_V[~left_out]
    record = {
        "resistance_ohm": r,
        "resistance_ci95_ohm": res.ci95["resistance_ohm"],
        "resistance_stderr_ohm": res.stderr["resistance_ohm"],
        "nrmse": nrmse(res.residual, measured),
        "residual_rms_V": float(np.sqrt(np.mean(res.residual**2))),
        "samples_left_out": 0 if left_out is None else int(np.count_nonzero(left_out)),
        "pzt_capacitance_F": fitted.pzt_capacitance_F,
        "cable_capacitance_F": fitted.cable_capacitance_F,
        "capacitance_F": fitted.capacitance_F,
        "tau_s": fitted.tau_s,
        "open_circuit_gain_V_per_N": fitted.open_circuit_gain_V_per_N,
        "fit": res.report(),
        "source": m.source,
        "config": {
            "sensor": config["sensor"],
            "calibration": config["calibration"],
            "diagnostics": {"quiet_settle_s": config["diagnostics"]["quiet_settle_s"]},
        },
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
