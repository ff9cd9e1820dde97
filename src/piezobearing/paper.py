"""The paper's numbers, in one table: every value the scorecard (and the sensor FEM's records) hold ours against.

Each entry is the value as the paper states it, in SI units (or the unit its key names), with the section it comes
from and how it is stated there. Nothing here is an input of the model: the config holds those (several config
defaults equal a paper value; the scorecard then shows the input beside the paper's number).
"""

from __future__ import annotations

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
