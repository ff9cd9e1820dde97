"""Stage functions of the bearing and housing model (Sec. III-A, IV; Fig. 3).

bearing_lpm -> housing_mesh_{case} -> housing_transient_{case} -> sensor_force_{case}.csv,
plus the mesh convergence study and the sampling-phase study. Each stage reads its inputs, calls one function
(:mod:`piezobearing.chain.bearing` for the chain, :mod:`piezobearing.housing.checks`) and writes what it
returns; the file formats are in :mod:`piezobearing.io`.
"""

from __future__ import annotations

import pandas as pd

from ..chain import bearing as outputs
from ..housing.checks import mesh_convergence as _mesh_convergence
from ..housing.checks import sampling_phase as _sampling_phase
from ..housing.transient import CASES
from ..io import FORCE_CSV_FORMAT, read_npz, write_csv, write_json, write_npz
from . import log_progress
from .meshes import read_housing_mesh, write_housing_mesh, write_housing_vtk


def bearing_lpm(
    out_kinematics: str, out_npz: dict, out_csv: dict, out_json: str, config: dict, method: str = "compiled"
) -> None:
    """Stage bearing_lpm: kinematics.json, per case the contact loads (NPZ: fine grid and FEM step; CSV at the
    FEM step) and lpm.json (:func:`piezobearing.chain.bearing.bearing_lpm`). ``method``: for the benchmark."""
    log_progress()
    r = outputs.bearing_lpm(config, method)
    write_json(r["kinematics"], out_kinematics)
    for case in CASES:
        write_npz(out_npz[case], **r["contact"][case])
        write_csv(r["tables"][case], out_csv[case], FORCE_CSV_FORMAT)
    write_json(r["summary"], out_json)


def housing_mesh(case: str, out_npz: str, out_vtk: str, out_json: str, config: dict) -> None:
    """Stage housing_mesh_{case}: the hexahedral mesh (NPZ for the solver, VTK to view) and its statistics."""
    m, record = outputs.housing_mesh(case, config)
    write_housing_mesh(m, out_npz)
    write_housing_vtk(m, out_vtk)
    write_json(record, out_json)


def housing_transient(
    case: str,
    mesh_npz: str,
    contact_npz: str,
    out_csv: str,
    out_modes: str,
    out_json: str,
    out_influence: str,
    config: dict,
    out_quasi_static: str | None = None,
) -> None:
    """Stage housing_transient_{case}: the sensor force over time, the modes, the method check; and
    (``out_quasi_static``) the quasi-static force on this mesh for the convergence study (NPZ)."""
    log_progress()
    r = outputs.housing_transient(case, read_housing_mesh(mesh_npz), read_npz(contact_npz), config)
    if out_quasi_static is not None:
        write_npz(out_quasi_static, **r["quasi_static"])
    write_csv(r["force"], out_csv, FORCE_CSV_FORMAT)
    write_csv(r["influence"], out_influence, FORCE_CSV_FORMAT)
    write_json(r["modes"], out_modes)
    write_json(r["summary"], out_json)


def mesh_convergence(
    contact_npz: str, out_json: str, out_csv: str, config: dict, quasi_static_npz: str | None = None
) -> None:
    """Stage housing_convergence: the sensor force amplitude on the convergence levels (housing.checks).

    ``quasi_static_npz``: housing_transient_healthy's quasi-static force on the mesh of ``housing.mesh_level``,
    that level's row (its mesh is not factorised a second time).
    """
    log_progress()
    known = None
    if quasi_static_npz is not None:
        qs = read_npz(quasi_static_npz)
        level = float(qs["level"])
        if level != float(config["housing"]["mesh_level"]):
            raise ValueError(
                f"{quasi_static_npz}: level {level} is not this config's housing.mesh_level "
                f"{config['housing']['mesh_level']}; rerun the rule housing_transient"
            )
        known = {level: (int(qs["n_dofs"]), qs["quasi_static_N"])}
    df, record = _mesh_convergence(read_npz(contact_npz), config, known)
    write_csv(df, out_csv, None)
    write_json({**record, "config": {"housing": config["housing"]}}, out_json)


def sampling_phase(contact_npz: str, influence_csv: str, out_json: str, config: dict) -> None:
    """Stage bearing_sampling: what the step 1/(36 BPFO) does to the faulty sensor force (housing.checks)."""
    inf = pd.read_csv(influence_csv)
    out = _sampling_phase(
        read_npz(contact_npz),
        inf["angle_rad"].to_numpy(),
        inf["sensor_per_radial_load"].to_numpy(),
        config["bearing"],
        config["seed"],
    )
    write_json(out, out_json)
