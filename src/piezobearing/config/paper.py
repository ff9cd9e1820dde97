"""The paper's numbers, in one table: every value the scorecard (and the sensor FEM's records) hold ours against.

Each entry is the value as the paper states it, in SI units (or the unit its key names), with the section it comes
from and how it is stated there. Nothing here is an input of the model: the config holds those (several config
defaults equal a paper value; the scorecard then shows the input beside the paper's number).

:data:`CASE` holds the config values of the paper's case (speed, load, bearing, defect, sensor, noise): a scorecard
row is compared with the paper only where the run's config holds every condition the row names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class PaperValue:
    """One number of the paper: ``value`` in ``unit``, from ``section``, as ``stated``."""

    value: float
    unit: str
    section: str
    stated: str


#: The paper's numbers by name.
TABLE: dict[str, PaperValue] = {
    # Sec. II-III-B/C: the sensor and its calibration (Fig. 5, 6, 8a)
    "impulse_sensitivity_V_per_N": PaperValue(74.4e-3, "V/N", "III-B", "74.4 mV/N from the calibration impulses"),
    "resistance_ohm": PaperValue(50e6, "Ohm", "III-B", "R = 50 MOhm, the circuit resistance of Eq. 6"),
    "cable_capacitance_F_per_m": PaperValue(90e-12, "F/m", "III-B", "90 pF/m (PCB-003 cable)"),
    "linear_from_Hz": PaperValue(
        30.0, "Hz", "III-C", "linear from 30 Hz (deviation below 5%); the low edge of the usable band 30 Hz-45 kHz"
    ),
    "deviation_threshold": PaperValue(0.05, "-", "III-C", "5% deviation"),
    "reference_sensitivity_V_per_N": PaperValue(0.36, "V/N", "III-C", "0.36 V/N at the onset of linearity"),
    # Sec. III-C: the sensor FEM (Fig. 7, 8b)
    "first_resonance_Hz": PaperValue(1.21e5, "Hz", "III-C", "first resonance at 121 kHz"),
    "band_high_Hz": PaperValue(45e3, "Hz", "III-C", "usable band 30 Hz to 45 kHz (+3 dB, 'about 27%')"),
    # Sec. III-A, IV: the bearing and its housing (Fig. 3, 9, 10)
    "bpfo_Hz": PaperValue(70.8, "Hz", "IV", "BPFO = 70.8 Hz at 1000 rpm"),
    "n_rollers": PaperValue(11, "-", "IV", "11 rollers"),
    "radial_load_N": PaperValue(500.0, "N", "IV", "500 N radial load"),
    "shaft_speed_rpm": PaperValue(1000.0, "rpm", "IV", "1000 rpm"),
    "time_step_s": PaperValue(0.392156e-3, "s", "III-A", "time step 0.392156 ms"),
    "defect_width_m": PaperValue(0.9e-3, "m", "III-A", "outer-race defect 0.9 mm wide"),
    "defect_depth_m": PaperValue(1.0e-3, "m", "III-A", "and 1 mm deep"),
    "snr": PaperValue(10.0, "dB", "IV", "'an SNR of 10' (read as a power ratio, 10 dB)"),
}


def value(name: str) -> float:
    """The paper's value of ``name`` (a key of :data:`TABLE`)."""
    return TABLE[name].value


# --------------------------------------------------------------------------- the paper's case


@dataclass(frozen=True)
class Condition:
    """A config value of the paper's case: ``value`` (in the unit the key names; None: the config's null),
    described as ``label``."""

    value: object
    label: str


#: The outer-race groove of the paper (Sec. III-A) as (type, width [m], depth [m], angle [deg]), the form
#: :func:`case_value` gives ``bearing.defects`` in.
_PAPER_DEFECTS = (("outer_race", 0.9e-3, 1.0e-3, 0.0),)

#: The config values under which the paper's numbers hold, by dotted config key: its operating point, bearing,
#: defect, sensor and noise (the stated values, or for the bearing's diameters the ones its BPFO fixes; see the
#: config's comments). A scorecard row is compared with the paper only where every key it names holds.
CASE: dict[str, Condition] = {
    "bearing.shaft_speed_rpm": Condition(1000.0, "shaft speed [rpm]"),
    "bearing.radial_load_N": Condition(500.0, "radial load [N]"),
    "bearing.n_rollers": Condition(11, "rollers [-]"),
    "bearing.roller_diameter_m": Condition(10.0e-3, "roller diameter [m]"),
    "bearing.pitch_diameter_m": Condition(44.0e-3, "pitch diameter [m]"),
    "bearing.defects": Condition(_PAPER_DEFECTS, "defects (type, width [m], depth [m], angle [deg])"),
    "bearing.time_step_s": Condition(0.392156e-3, "FEM time step [s]"),
    "sensor.material": Condition("apc850_paper", "piezoceramic"),
    "sensor.pzt_diameter_m": Condition(4.7e-3, "PZT diameter [m]"),
    "sensor.pzt_height_m": Condition(3.4e-3, "PZT height [m]"),
    "sensor.d33_C_per_N": Condition(None, "d33 [C/N] (null: the material's)"),
    "sensor.eps33_T_rel": Condition(None, "eps33^T/eps0 [-] (null: the material's)"),
    "sensor.cable_length_m": Condition(2.0, "cable length [m]"),
    "sensor.cable_capacitance_F_per_m": Condition(90e-12, "cable capacitance [F/m]"),
    "synthesis.resistance_ohm": Condition(50e6, "circuit resistance of the calibration record [Ohm]"),
    "lowfreq.deviation_threshold": Condition(0.05, "deviation threshold of linearity [-]"),
    "signals.snr_dB": Condition(10.0, "SNR of the added noise [dB]"),
}

#: Condition groups the scorecard's rows name.
KINEMATICS = ("bearing.n_rollers", "bearing.roller_diameter_m", "bearing.pitch_diameter_m", "bearing.shaft_speed_rpm")
RUNNING = (*KINEMATICS, "bearing.radial_load_N", "bearing.defects", "bearing.time_step_s")
PZT = ("sensor.material", "sensor.pzt_diameter_m", "sensor.pzt_height_m", "sensor.d33_C_per_N", "sensor.eps33_T_rel")
CIRCUIT = (*PZT, "sensor.cable_length_m", "sensor.cable_capacitance_F_per_m", "synthesis.resistance_ohm")
DETECTION = (*RUNNING, *CIRCUIT, "signals.snr_dB")


def case_value(config: dict, key: str):
    """The value of dotted ``key`` in ``config``, in the form :data:`CASE` holds it."""
    node = config
    for k in key.split("."):
        node = node[k]
    if key == "bearing.defects":
        return tuple(
            (d["type"], float(d["width_m"]), float(d["depth_m"]), float(d.get("angle_deg", 0.0))) for d in node
        )
    return node


def _same(a, b) -> bool:
    if isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0)
    return a == b


def differs(config: dict, key: str) -> bool:
    """Whether ``config`` leaves the paper's case at ``key`` (a key of :data:`CASE`)."""
    return not _same(case_value(config, key), CASE[key].value)
