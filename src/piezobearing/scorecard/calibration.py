"""Scorecard rows of the calibration chain (Sec. II, III-B/C): the paper's numbers (:mod:`piezobearing.config.paper`)
beside ours, with the arithmetic where the paper's own constants cannot hold together."""

from __future__ import annotations

import numpy as np

from ..config.paper import CIRCUIT, TABLE
from ..sensor import calibration as sensor_calibration
from . import Row


def rows(sens: dict, res: dict, lf: dict, c: sensor_calibration.SensorCircuit, config: dict) -> list[Row]:
    """The rows from sensitivity.json, resistance.json, lowfreq.json, the fitted circuit ``c`` and the config
    (``calibration.measurement``: synthetic or measured; ``sensor.cable_capacitance_F_per_m``)."""
    synthetic = config["calibration"]["measurement"] is None
    f_ref = TABLE["linear_from_Hz"].value
    x = abs(sensor_calibration.frequency_response([f_ref], c)[0]) / c.open_circuit_gain_V_per_N
    c_needed = c.d33_C_per_N * x / TABLE["reference_sensitivity_V_per_N"].value
    y = TABLE["reference_sensitivity_V_per_N"].value / c.open_circuit_gain_V_per_N
    r_needed = y / np.sqrt(1 - y * y) / (2 * np.pi * f_ref) / c.capacitance_F
    lo, hi = res["resistance_ci95_ohm"]
    return [
        Row(
            "III-B",
            "impulse-peak sensitivity at ~0.5 Hz",
            TABLE["impulse_sensitivity_V_per_N"].value,
            sens["sensitivity_V_per_N"],
            "V/N",
            "synthetic presses with rise times chosen so that (d33/C) tau pi/(2 T_r) is near 74 mV/N: "
            "agreement by construction, not a prediction"
            if synthetic
            else f"measured: {sens['source']}",
            CIRCUIT,
        ),
        Row(
            "III-B",
            "circuit resistance R (fitted)",
            TABLE["resistance_ohm"].value,
            res["resistance_ohm"],
            "Ohm",
            f"least squares, 95% CI [{lo:.4g}, {hi:.4g}] Ohm, NRMSE {res['nrmse']:.3f}"
            + (
                f"; the synthetic truth is {config['synthesis']['resistance_ohm'] / 1e6:g} MOhm, so this checks "
                "recovery"
                if synthetic
                else ""
            ),
            ("synthesis.resistance_ohm",),
        ),
        Row(
            "III-B",
            "cable capacitance",
            TABLE["cable_capacitance_F_per_m"].value,
            config["sensor"]["cable_capacitance_F_per_m"],
            "F/m",
            "input (PCB-003 datasheet, as in the paper)",
            ("sensor.cable_capacitance_F_per_m",),
        ),
        Row(
            "II",
            "PZT capacitance Cp = eps33^T A / h",
            None,
            c.pzt_capacitance_F,
            "F",
            f"not stated in the paper; with the {config['sensor']['cable_length_m']:g} m cable C = {c.capacitance_F * 1e12:.1f} pF, "
            f"tau = RC = {c.tau_s * 1e3:.2f} ms, d33/C = {c.open_circuit_gain_V_per_N:.3f} V/N",
        ),
        Row(
            "III-C",
            "onset of linearity (deviation < 5%)",
            TABLE["linear_from_Hz"].value,
            lf["linear_from_Hz"],
            "Hz",
            "deviation = relative change to the next sweep frequency; within 5% of the asymptote d33/C only "
            f"from {lf['asymptote_within_threshold_from_Hz']:.1f} Hz",
            (*CIRCUIT, "lowfreq.deviation_threshold"),
        ),
        Row(
            "III-C",
            "deviation threshold",
            TABLE["deviation_threshold"].value,
            lf["deviation_threshold"],
            "-",
            "input",
            ("lowfreq.deviation_threshold",),
        ),
        Row(
            "III-C",
            "reference sensitivity at the onset",
            TABLE["reference_sensitivity_V_per_N"].value,
            lf["reference_sensitivity_V_per_N"],
            "V/N",
            f"S(30 Hz) = d33/C x omega tau/sqrt(1+(omega tau)^2) = {c.open_circuit_gain_V_per_N:.3f} x {x:.3f}; "
            f"0.36 V/N would need C = {c_needed * 1e12:.0f} pF at the same tau, or R = {r_needed / 1e6:.1f} MOhm "
            "(and then the response would not be linear at 30 Hz): the paper's 0.36 V/N, 50 MOhm and "
            "C = Cp + 180 pF cannot all hold",
            (*CIRCUIT, "lowfreq.deviation_threshold"),
        ),
    ]
