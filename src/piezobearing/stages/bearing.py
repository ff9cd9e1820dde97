"""Stage functions of the bearing and housing model (Sec. III-A, IV; Fig. 3).

bearing_lpm -> housing_mesh_{case} -> housing_transient_{case} -> sensor_force_{case}.csv,
plus the mesh convergence study, the sampling-phase study and the scorecard. The physics is in
:mod:`piezobearing.bearing.transient` and :mod:`piezobearing.bearing.checks`; the file formats in
:mod:`piezobearing.io`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict

import pandas as pd

from ..bearing import lpm as brg
from ..bearing.checks import lpm_checks
from ..bearing.checks import mesh_convergence as _mesh_convergence
from ..bearing.checks import sampling_phase as _sampling_phase
from ..bearing.housing_mesh import build_housing_mesh, mesh_quality
from ..bearing.transient import CASES, housing_geometry, is_faulty, run_lpm, transient, transient_summary
from ..io import (
    read_housing_mesh,
    read_npz,
    write_csv,
    write_housing_mesh,
    write_housing_vtk,
    write_json,
    write_npz,
)
from . import log_progress

log = logging.getLogger("piezobearing.bearing.lpm")


def bearing_lpm(
    out_kinematics: str, out_npz: dict, out_csv: dict, out_json: str, config: dict, method: str = "compiled"
) -> None:
    """Stage bearing_lpm: kinematic frequencies and both cases' roller contact loads.

    Writes ``kinematics.json`` (shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz without slip; cage_slip,
    slip_jitter, the same frequencies at the mean slip under ``with_slip``, speed_ramp_Hz_per_s, defect_types;
    with a tachometer its pulses_per_rev and pulse times ``tachometer_time_s`` on the record's time axis),
    per case an NPZ with the fine integration grid and the FEM-step series
    and a CSV at the FEM step (time_s, load_N_jj, angle_rad_jj), and a JSON
    of the checks. ``method``: the LPM's step loop (simulate_lpm), for the benchmark.
    """
    log_progress()
    b = config["bearing"]
    geo = brg.BearingGeometry.from_config(b)
    # top level: the kinematic (no-slip) lines, which signals.fault_bands slips itself; "with_slip": at the
    # configured mean cage slip, what the LPM's cage does on average
    kin0 = brg.kinematic_frequencies(geo, b["shaft_speed_rpm"] / 60.0)
    kin = brg.kinematic_frequencies(geo, b["shaft_speed_rpm"] / 60.0, b["cage_slip"])
    operating = {
        "cage_slip": b["cage_slip"],
        "slip_jitter": b["slip_jitter"],
        "with_slip": kin.to_dict(),
        "speed_ramp_Hz_per_s": b["speed_ramp_rpm_per_s"] / 60.0,
        "defect_types": [d["type"] for d in b["defects"]],
    }
    summary = {
        "kinematics": kin0.to_dict(),
        "kinematics_with_slip": kin.to_dict(),
        "contact_stiffness_N_per_m10_9": brg.line_contact_stiffness(geo.roller_length_m),
        "config": {"bearing": b},
    }
    for case in CASES:
        t0 = time.perf_counter()
        run = run_lpm(b, is_faulty(case), method, config["seed"])
        log.info("LPM %s: %d steps in %.1f s", case, len(run["fine_time_s"]), time.perf_counter() - t0)
        write_npz(out_npz[case], **{k: v for k, v in run.items() if k != "params"})
        df = pd.DataFrame({"time_s": run["time_s"]})
        for j in range(geo.n_rollers):
            df[f"load_N_{j:02d}"] = run["load_N"][:, j]
        for j in range(geo.n_rollers):
            df[f"angle_rad_{j:02d}"] = run["angle_rad"][:, j]
        write_csv(df, out_csv[case], "%.9g")
        summary[case] = {
            **lpm_checks(run, kin),
            "fine_step_s": float(run["fine_time_s"][1] - run["fine_time_s"][0]),
            "newton_iterations_per_step": run["newton_iterations"] / len(run["fine_time_s"]),
        }
    if b["tachometer_pulses_per_rev"] > 0:
        # the shaft's pulses (the same in both cases: the defects do not move the shaft's angle), on the
        # record's time axis, where the signals stages and a user read the kinematics
        operating["tachometer_pulses_per_rev"] = b["tachometer_pulses_per_rev"]
        operating["tachometer_time_s"] = run["tachometer_time_s"].tolist()
    write_json({**kin0.to_dict(), **operating, "config": {"bearing": b}}, out_kinematics)
    write_json(summary, out_json)


def housing_mesh(case: str, out_npz: str, out_vtk: str, out_json: str, config: dict) -> None:
    """Stage housing_mesh_{case}: the hexahedral mesh (NPZ for the solver, VTK to view) and its statistics."""
    geo = housing_geometry(config)
    m = build_housing_mesh(geo, is_faulty(case), config["housing"]["mesh_level"])
    write_housing_mesh(m, out_npz)
    write_housing_vtk(m, out_vtk)
    write_json(
        {
            **mesh_quality(m),
            "case": case,
            "level": m.level,
            "geometry": asdict(geo),
            "config": {k: config[k] for k in ("bearing", "housing", "sensor_fem")},
        },
        out_json,
    )


def housing_transient(
    case: str,
    mesh_npz: str,
    contact_npz: str,
    out_csv: str,
    out_modes: str,
    out_json: str,
    out_influence: str,
    config: dict,
) -> None:
    """Stage housing_transient_{case}: the sensor force over time, the modes, the method check."""
    log_progress()
    m = read_housing_mesh(mesh_npz)
    run = transient(case, m, read_npz(contact_npz), config)
    write_csv(pd.DataFrame({"time_s": run["time_s"], "force_N": run["force_N"]}), out_csv, "%.9g")
    influence, modes, summary = transient_summary(case, m, run, config)
    write_csv(pd.DataFrame(influence), out_influence, "%.9g")
    write_json({**modes, "config": {"housing": config["housing"]}}, out_modes)
    write_json(
        {**summary, "config": {k: config[k] for k in ("housing", "bearing", "sensor", "sensor_fem")}}, out_json
    )


def mesh_convergence(contact_npz: str, out_json: str, out_csv: str, config: dict) -> None:
    """Stage housing_convergence: the sensor force amplitude on the convergence levels (bearing.checks)."""
    log_progress()
    df, record = _mesh_convergence(read_npz(contact_npz), config)
    write_csv(df, out_csv, None)
    write_json({**record, "config": {"housing": config["housing"]}}, out_json)


def sampling_phase(contact_npz: str, influence_csv: str, out_json: str, config: dict) -> None:
    """Stage bearing_sampling: what the step 1/(36 BPFO) does to the faulty sensor force (bearing.checks)."""
    inf = pd.read_csv(influence_csv)
    out = _sampling_phase(
        read_npz(contact_npz),
        inf["angle_rad"].to_numpy(),
        inf["sensor_per_radial_load"].to_numpy(),
        config["bearing"],
        config["seed"],
    )
    write_json(out, out_json)
