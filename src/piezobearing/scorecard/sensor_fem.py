"""Scorecard rows of the sensor FEM (Sec. III-C): the paper's numbers (:mod:`piezobearing.config.paper`) beside the
modal survey's, the harmonic response's and the mesh convergence's, with the reasons where they differ."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..config.paper import CIRCUIT, PZT, TABLE
from . import Row


def rows(modal: dict, band: dict, convergence: pd.DataFrame) -> list[Row]:
    """The paper's numbers of Sec. III-C beside ours, with the reasons where they differ."""
    # longer than 80 lines: a table, one Row literal a paper number, read top to bottom like the scorecard
    sec = "III-C sensor FEM"
    pc = modal["placement_check"]
    lower = [m for m in modal["modes"] if m["frequency_short_Hz"] < modal["first_resonance_short_Hz"]]
    lower_txt = ", ".join(f"{m['label']} {m['frequency_short_Hz'] / 1e3:.1f} kHz" for m in lower)
    fr = TABLE["first_resonance_Hz"].value
    x3 = 10 ** (band["band_ratio_dB"] / 20)
    sdof_3db = fr * np.sqrt(1 - 1 / x3)
    sdof_27 = fr * np.sqrt(1 - 1 / (1 + band["band_ratio_percent"] / 100))
    rise_45 = 1 / (1 - (TABLE["band_high_Hz"].value / fr) ** 2)
    last = convergence.iloc[-1]
    x_low = band["band_low_Hz"] / band["rc_model_corner_Hz"]
    hp_low = x_low / np.sqrt(1 + x_low**2)
    return [
        Row(
            sec,
            "first resonance (first axial mode, electrodes shorted)",
            fr,
            modal["first_resonance_short_Hz"],
            "Hz",
            f"the mode a centred axial force excites; open circuit {modal['first_resonance_open_Hz'] / 1e3:.1f} kHz, "
            f"with R and the cable {band['loaded_resonance_Hz'] / 1e3:.1f} kHz; below it only modes an axial force "
            f"cannot excite ({lower_txt}). Depends on which disk is clamped: with the 5 mm disk on the housing "
            f"{pc['first_axial_short_Hz'] / 1e3:.0f} kHz",
            PZT,
        ),
        Row(
            sec,
            "first resonance, open circuit (floating electrode)",
            None,
            modal["first_resonance_open_Hz"],
            "Hz",
            f"coupling factor k_eff = {modal['first_resonance_coupling_factor']:.3f}",
        ),
        Row(
            sec,
            "band low edge",
            TABLE["linear_from_Hz"].value,
            band["band_low_Hz"],
            "Hz",
            "from the low-frequency analysis (lowfreq.json, linear_from_Hz)",
            (*CIRCUIT, "lowfreq.deviation_threshold"),
        ),
        Row(
            sec,
            f"band high edge (+{band['band_ratio_dB']:g} dB over mid-band)",
            TABLE["band_high_Hz"].value,
            band["band_high_Hz"],
            "Hz",
            f"reference |V/F| at {band['reference_frequency_Hz']:g} Hz. A single-mode response "
            f"1/(1-(f/fr)^2) with the paper's own fr = 121 kHz is +{band['band_ratio_dB']:g} dB (x{x3:.3f}) at "
            f"fr sqrt(1-1/{x3:.3f}) = {sdof_3db / 1e3:.1f} kHz and only x{rise_45:.3f} "
            f"({20 * np.log10(rise_45):.1f} dB) at 45 kHz, so 45 kHz cannot be a +3 dB edge of a 121 kHz resonance; "
            f"relative to the sensitivity at the band's low edge, {band['band_low_Hz']:g} Hz (the paper's "
            f"reference), ours is {band['band_high_rel_band_low_Hz'] / 1e3:.1f} kHz",
            CIRCUIT,
        ),
        Row(
            sec,
            f"band high edge (+{band['band_ratio_percent']:g}%)",
            TABLE["band_high_Hz"].value,
            band["band_high_27_percent_Hz"],
            "Hz",
            f"the paper equates +3 dB with 'about 27%' (+3 dB is +41% in amplitude, +27% is "
            f"{20 * np.log10(1.27):.2f} dB); single-mode estimate with fr = 121 kHz: {sdof_27 / 1e3:.1f} kHz; "
            f"relative to the sensitivity at {band['band_low_Hz']:g} Hz ours is "
            f"{band['band_high_27_percent_rel_band_low_Hz'] / 1e3:.1f} kHz",
            CIRCUIT,
        ),
        Row(
            sec,
            "mid-band sensitivity",
            None,
            band["reference_sensitivity_V_per_N"],
            "V/N",
            f"at {band['reference_frequency_Hz']:g} Hz: effective d33 {band['effective_d33_C_per_N'] * 1e12:.0f} pC/N "
            f"over (C_FEM {band['fem_capacitance_F'] * 1e12:.1f} pF + cable "
            f"{band['cable_capacitance_F'] * 1e12:.0f} pF); the RC model with the paper's d33 and Cp gives "
            f"{band['rc_model_mid_band_V_per_N']:.3f} V/N",
        ),
        Row(
            sec,
            "sensitivity at the band low edge (reference of the paper)",
            TABLE["reference_sensitivity_V_per_N"].value,
            band["sensitivity_at_band_low_V_per_N"],
            "V/N",
            f"the paper's 0.36 V/N cannot hold with its own constants: d33/(Cp + Ccable) = "
            f"{band['rc_model_mid_band_V_per_N']:.3f} V/N times the RC high-pass at {band['band_low_Hz']:g} Hz "
            f"({hp_low:.3f}) = {band['rc_model_mid_band_V_per_N'] * hp_low:.3f} V/N (see the calibration rows); "
            "the FEM differs from that RC model only by its effective d33 and capacitance",
            (*CIRCUIT, "lowfreq.deviation_threshold"),
        ),
        Row(
            sec,
            "mesh convergence: change of the first axial frequency between the two finest meshes",
            None,
            float(last["change_short_percent"]),
            "%",
            f"levels {', '.join(f'{m:g}' for m in convergence['multiplier'])}; "
            f"{int(last['n_dof'])} DOF on the finest",
        ),
    ]
