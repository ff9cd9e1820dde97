"""Stage functions of the sensor finite-element model (Sec. III-C; Fig. 7, 8b).

sensor_mesh -> sensor_convergence, sensor_modal -> sensor_harmonic -> scorecard_sensor_fem. The result tables
are computed in :mod:`piezobearing.sensor.analysis`; the mesh files are read and written by :mod:`piezobearing.io`.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from .. import io
from ..io import read_stack_mesh, write_csv, write_json, write_npz, write_stack_mesh
from ..scorecard import Row, write_part
from ..sensor.analysis import (
    PAPER_BAND_HIGH_HZ,
    PAPER_BAND_LOW_HZ,
    PAPER_FIRST_RESONANCE_HZ,
    PAPER_REFERENCE_SENSITIVITY_V_PER_N,
    SensorFemError,
    SensorFemParams,
    convergence_table,
    first_axial_mode_fields,
    harmonic_results,
    modal_results,
    placement_check,
)
from ..sensor.calibration import SensorCircuit
from ..sensor.mesh import StackMesh, stack_mesh
from . import log_progress


def read_json(path: str | Path, keys=()) -> dict:
    """A result of an earlier stage (missing file or key: :class:`SensorFemError`)."""
    return io.read_json(path, keys, error=SensorFemError)


def _config_record(config: dict) -> dict:
    return {"sensor": config["sensor"], "sensor_fem": config["sensor_fem"]}


def read_mesh(path: str | Path, params: SensorFemParams, level: float) -> StackMesh:
    """Read a sensor mesh and check it against the configured geometry (:class:`SensorFemError` if not)."""
    return read_stack_mesh(path, params.geometry, level, error=SensorFemError)


def sensor_mesh(out_meshes: list[str], out_json: str, config: dict) -> None:
    """Write the quarter mesh at every refinement multiplier, and a summary with their sizes."""
    p = SensorFemParams.from_config(config)
    if len(out_meshes) != len(p.multipliers):
        raise SensorFemError("one mesh output per sensor_fem.refinement_multipliers entry is expected")
    levels = []
    for k, (mult, path) in enumerate(zip(p.multipliers, out_meshes, strict=True), start=1):
        mesh = stack_mesh(p.geometry, p.density, mult)
        write_stack_mesh(mesh, path)
        levels.append(
            {
                "level": k,
                "multiplier": mult,
                "n_cells": mesh.n_cells,
                "n_vertices": len(mesh.coors),
                "path": str(path),
            }
        )
    write_json(
        {
            "geometry": asdict(p.geometry),
            "z_interfaces_m": p.geometry.z_interfaces_m.tolist(),
            "sector": "quarter (x >= 0, y >= 0), mirror planes x = 0 and y = 0",
            "levels": levels,
            "config": _config_record(config),
        },
        out_json,
    )


def sensor_convergence(mesh_paths: list[str], out_csv: str, config: dict) -> None:
    """Mesh convergence of the first axial frequency over all refinement levels (SS quarter)."""
    log_progress()
    p = SensorFemParams.from_config(config)
    meshes = [read_mesh(path, p, m) for path, m in zip(mesh_paths, p.multipliers, strict=True)]
    df = convergence_table(meshes, p)
    write_csv(df, out_csv, None)


def sensor_modal(mesh_vtk: str, out_json: str, out_mode_npz: str, config: dict) -> None:
    """Modes below the configured limit, short and open circuit, labelled; the first axial mode shape."""
    log_progress()
    p = SensorFemParams.from_config(config)
    mesh = read_mesh(mesh_vtk, p, p.multiplier)
    out, survey = modal_results(mesh, p)
    out["placement_check"] = placement_check(p)
    out["config"] = _config_record(config)
    write_json(out, out_json)
    write_npz(out_mode_npz, **first_axial_mode_fields(survey, mesh))


def sensor_harmonic(
    mesh_vtk: str,
    modal_json: str,
    resistance_json: str,
    lowfreq_json: str,
    out_csv: str,
    out_json: str,
    config: dict,
) -> None:
    """1 N harmonic force on the bottom, top clamped, the fitted R and the cable across the electrodes."""
    log_progress()
    p = SensorFemParams.from_config(config)
    modal = read_json(modal_json, ["first_resonance_short_Hz", "first_resonance_open_Hz"])
    res = read_json(resistance_json, ["resistance_ohm"])
    low = read_json(lowfreq_json, ["linear_from_Hz"])
    r = float(res["resistance_ohm"])
    if not np.isfinite(r) or r <= 0:
        raise SensorFemError(
            f"{resistance_json}: resistance_ohm = {r} is not a positive number; rerun fit_resistance"
        )
    mesh = read_mesh(mesh_vtk, p, p.multiplier)
    rc = SensorCircuit.from_config(config["sensor"], r)
    df, band = harmonic_results(mesh, p, rc, float(low["linear_from_Hz"]))
    if not np.isclose(band["first_axial_short_Hz"], modal["first_resonance_short_Hz"], rtol=1e-6):
        raise SensorFemError(
            f"{modal_json}: first resonance differs from this mesh's; rerun rule sensor_modal"
        )
    band["band_low_source"] = f"{lowfreq_json}: linear_from_Hz"
    band["config"] = _config_record(config)
    write_csv(df, out_csv, None)
    write_json(band, out_json)


# --------------------------------------------------------------------------- scorecard


def scorecard_rows(modal: dict, band: dict, convergence: pd.DataFrame) -> list[Row]:
    """The paper's numbers of Sec. III-C beside ours, with the reasons where they differ."""
    sec = "III-C sensor FEM"
    pc = modal["placement_check"]
    lower = [m for m in modal["modes"] if m["frequency_short_Hz"] < modal["first_resonance_short_Hz"]]
    lower_txt = ", ".join(f"{m['label']} {m['frequency_short_Hz'] / 1e3:.1f} kHz" for m in lower)
    fr = PAPER_FIRST_RESONANCE_HZ
    x3 = 10 ** (band["band_ratio_dB"] / 20)
    sdof_3db = fr * np.sqrt(1 - 1 / x3)
    sdof_27 = fr * np.sqrt(1 - 1 / (1 + band["band_ratio_percent"] / 100))
    rise_45 = 1 / (1 - (PAPER_BAND_HIGH_HZ / fr) ** 2)
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
            PAPER_BAND_LOW_HZ,
            band["band_low_Hz"],
            "Hz",
            "from the low-frequency analysis (lowfreq.json, linear_from_Hz)",
        ),
        Row(
            sec,
            f"band high edge (+{band['band_ratio_dB']:g} dB over mid-band)",
            PAPER_BAND_HIGH_HZ,
            band["band_high_Hz"],
            "Hz",
            f"reference |V/F| at {band['reference_frequency_Hz']:g} Hz. A single-mode response "
            f"1/(1-(f/fr)^2) with the paper's own fr = 121 kHz is +{band['band_ratio_dB']:g} dB (x{x3:.3f}) at "
            f"fr sqrt(1-1/{x3:.3f}) = {sdof_3db / 1e3:.1f} kHz and only x{rise_45:.3f} "
            f"({20 * np.log10(rise_45):.1f} dB) at 45 kHz, so 45 kHz cannot be a +3 dB edge of a 121 kHz resonance; "
            f"relative to the 30 Hz sensitivity (the paper's reference) ours is "
            f"{band['band_high_rel_band_low_Hz'] / 1e3:.1f} kHz",
        ),
        Row(
            sec,
            f"band high edge (+{band['band_ratio_percent']:g}%)",
            PAPER_BAND_HIGH_HZ,
            band["band_high_27_percent_Hz"],
            "Hz",
            f"the paper equates +3 dB with 'about 27%' (+3 dB is +41% in amplitude, +27% is "
            f"{20 * np.log10(1.27):.2f} dB); single-mode estimate with fr = 121 kHz: {sdof_27 / 1e3:.1f} kHz; "
            f"relative to the 30 Hz sensitivity ours is {band['band_high_27_percent_rel_band_low_Hz'] / 1e3:.1f} kHz",
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
            PAPER_REFERENCE_SENSITIVITY_V_PER_N,
            band["sensitivity_at_band_low_V_per_N"],
            "V/N",
            f"the paper's 0.36 V/N cannot hold with its own constants: d33/(Cp + Ccable) = "
            f"{band['rc_model_mid_band_V_per_N']:.3f} V/N times the RC high-pass at {band['band_low_Hz']:g} Hz "
            f"({hp_low:.3f}) = {band['rc_model_mid_band_V_per_N'] * hp_low:.3f} V/N (see the calibration rows); "
            "the FEM differs from that RC model only by its effective d33 and capacitance",
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


def scorecard_sensor_fem(modal_json: str, band_json: str, convergence_csv: str, out_csv: str) -> None:
    """Write results/scorecard/sensor_fem.csv."""
    modal = read_json(modal_json, ["first_resonance_short_Hz", "modes", "placement_check"])
    band = read_json(band_json, ["band_high_Hz", "band_low_Hz"])
    conv = pd.read_csv(convergence_csv)
    write_part(scorecard_rows(modal, band, conv), out_csv)
