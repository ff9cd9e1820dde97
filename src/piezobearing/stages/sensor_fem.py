"""Stage functions of the sensor finite-element model (Sec. III-C; Fig. 7, 8b).

sensor_mesh -> sensor_modal -> sensor_convergence, sensor_harmonic -> scorecard_sensor_fem. sensor_modal also
writes the harmonic analysis's Ritz model and the convergence table's row of its mesh (one assembly and one
factorisation of the SS system on the modal mesh serve the three rules). The result tables are computed in :mod:`piezobearing.sensor.analysis`; the mesh files are read and written by :mod:`piezobearing.io`.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import numpy as np

from .. import io
from ..io import read_npz, write_csv, write_json, write_npz
from ..sensor.analysis import (
    SensorFemError,
    SensorFemParams,
    convergence_row,
    convergence_table,
    first_axial_mode_fields,
    harmonic_from_ritz,
    mesh_inputs,
    modal_results,
    placement_check,
    ritz_arrays,
)
from ..sensor.analysis import (
    harmonic_results as harmonic_results,  # re-exported: the study and tests call it
)
from ..sensor.calibration import SensorCircuit, design_resistance_ohm
from ..sensor.mesh import StackMesh, stack_mesh
from . import log_progress
from .meshes import read_stack_mesh, write_stack_mesh


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
    geo, dens, multipliers = mesh_inputs(config)
    if len(out_meshes) != len(multipliers):
        raise SensorFemError("one mesh output per sensor_fem.refinement_multipliers entry is expected")
    levels = []
    for k, (mult, path) in enumerate(zip(multipliers, out_meshes, strict=True), start=1):
        mesh = stack_mesh(geo, dens, mult)
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
            "geometry": asdict(geo),
            "z_interfaces_m": geo.z_interfaces_m.tolist(),
            "sector": "quarter (x >= 0, y >= 0), mirror planes x = 0 and y = 0",
            "levels": levels,
            "config": _config_record(config),
        },
        out_json,
    )


def sensor_convergence(mesh_paths: list[str], modal_row_json: str, out_csv: str, config: dict) -> None:
    """Mesh convergence of the first axial frequency over all refinement levels (SS quarter).

    The row of the modal stage's level comes from sensor_modal (``modal_row_json``), which solved that mesh's
    system already; the other levels are solved here.
    """
    log_progress()
    p = SensorFemParams.from_config(config)
    row = read_json(modal_row_json, ["row"])["row"]
    if row.get("level") != p.mesh_level or row.get("multiplier") != p.multiplier:
        raise SensorFemError(
            f"{modal_row_json}: the row of level {row.get('level')} is not this config's sensor_fem.mesh_level "
            f"{p.mesh_level}; rerun the rule sensor_modal"
        )
    meshes = [
        None if k == p.mesh_level else read_mesh(path, p, m)
        for k, (path, m) in enumerate(zip(mesh_paths, p.multipliers, strict=True), start=1)
    ]
    df = convergence_table(meshes, p, known={p.mesh_level: row})
    write_csv(df, out_csv, None)


def sensor_modal(
    mesh_vtk: str, out_json: str, out_mode_npz: str, out_ritz_npz: str, out_row_json: str, config: dict
) -> None:
    """Modes below the configured limit, short and open circuit, labelled; the first axial mode shape; and,
    from the same factorisation of the SS system, the harmonic analysis's Ritz model (``out_ritz_npz``, for
    sensor_harmonic) and this mesh's row of the convergence table (``out_row_json``, for sensor_convergence)."""
    log_progress()
    p = SensorFemParams.from_config(config)
    mesh = read_mesh(mesh_vtk, p, p.multiplier)
    out, survey = modal_results(mesh, p)
    out["placement_check"] = placement_check(p)
    out["config"] = _config_record(config)
    write_json(out, out_json)
    write_npz(out_mode_npz, **first_axial_mode_fields(survey, mesh))
    write_npz(out_ritz_npz, **ritz_arrays(survey.ss_system, p))
    write_json({"row": convergence_row(survey.ss_system, p.mesh_level, mesh)}, out_row_json)


#: The arrays of the Ritz model file sensor_modal writes for sensor_harmonic.
RITZ_KEYS = ("omega2", "b_k", "f_k", "c0_F", "first_axial_short_Hz", "first_axial_open_Hz", "n_dof_displacement")


def read_ritz(path: str | Path) -> dict:
    """The Ritz model file of sensor_modal (missing file or array: :class:`SensorFemError`)."""
    if not Path(path).is_file():
        raise SensorFemError(f"{path}: file not found; run the rule sensor_modal")
    ritz = read_npz(path)
    missing = [k for k in RITZ_KEYS if k not in ritz]
    if missing:
        raise SensorFemError(f"{path}: array(s) {', '.join(missing)} missing; rerun the rule sensor_modal")
    return ritz


def sensor_harmonic(
    ritz_npz: str,
    modal_json: str,
    resistance_json: str,
    lowfreq_json: str,
    out_csv: str,
    out_json: str,
    config: dict,
) -> None:
    """1 N harmonic force on the bottom, top clamped, the fitted R and the cable across the electrodes.

    The FEM part (the SS family's Ritz model) comes from sensor_modal's ``ritz_npz``: the sweep, the band edges
    and the circuit are evaluated on it.
    """
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
    ritz = read_ritz(ritz_npz)
    rc = SensorCircuit.from_config(config["sensor"], design_resistance_ohm(config["sensor"], r))
    df, band = harmonic_from_ritz(ritz, p, rc, float(low["linear_from_Hz"]))
    if not np.isclose(band["first_axial_short_Hz"], modal["first_resonance_short_Hz"], rtol=1e-6):
        raise SensorFemError(
            f"{modal_json}: first resonance differs from {ritz_npz}'s; rerun rule sensor_modal"
        )
    band["band_low_source"] = f"{lowfreq_json}: linear_from_Hz"
    band["config"] = _config_record(config)
    write_csv(df, out_csv, None)
    write_json(band, out_json)
