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
    read_json,
    read_npz,
    write_csv,
    write_housing_mesh,
    write_housing_vtk,
    write_json,
    write_npz,
)
from ..scorecard import Row, write_part
from . import log_progress

PAPER = {
    "bpfo_Hz": 70.8,
    "n_rollers": 11,
    "radial_load_N": 500.0,
    "shaft_speed_rpm": 1000.0,
    "time_step_s": 0.392156e-3,
    "defect_width_m": 0.9e-3,
    "defect_depth_m": 1.0e-3,
}

log = logging.getLogger("piezobearing.bearing.lpm")


def bearing_lpm(
    out_kinematics: str, out_npz: dict, out_csv: dict, out_json: str, config: dict, method: str = "compiled"
) -> None:
    """Stage bearing_lpm: kinematic frequencies and both cases' roller contact loads.

    Writes ``kinematics.json`` (shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz),
    per case an NPZ with the fine integration grid and the FEM-step series
    and a CSV at the FEM step (time_s, load_N_jj, angle_rad_jj), and a JSON
    of the checks. ``method``: the LPM's step loop (simulate_lpm), for the benchmark.
    """
    log_progress()
    b = config["bearing"]
    geo = brg.BearingGeometry.from_config(b)
    kin = brg.kinematic_frequencies(geo, b["shaft_speed_rpm"] / 60.0)
    write_json({**kin.to_dict(), "config": {"bearing": b}}, out_kinematics)
    summary = {
        "kinematics": kin.to_dict(),
        "contact_stiffness_N_per_m10_9": brg.line_contact_stiffness(geo.roller_length_m),
        "config": {"bearing": b},
    }
    for case in CASES:
        t0 = time.perf_counter()
        run = run_lpm(b, is_faulty(case), method)
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
    )
    write_json(out, out_json)


# ---------------------------------------------------------------------------
# Scorecard
# ---------------------------------------------------------------------------


def scorecard(
    kinematics_json: str,
    lpm_json: str,
    transient_jsons: dict,
    convergence_json: str,
    sampling_json: str,
    out_csv: str,
    config: dict,
) -> None:
    """Rows of results/scorecard/bearing.csv."""
    b = config["bearing"]
    kin, lpm, conv, samp = (
        read_json(p) for p in (kinematics_json, lpm_json, convergence_json, sampling_json)
    )
    tr = {k: read_json(v) for k, v in transient_jsons.items()}
    chk = tr["healthy"]["direct_check"] or {}
    rows = [
        Row(
            "IV",
            "BPFO at 1000 rpm",
            PAPER["bpfo_Hz"],
            kin["bpfo_Hz"],
            "Hz",
            "D_r/D_p = 10/44 (derived from the paper's BPFO; README); FTF x Z",
        ),
        Row("IV", "rollers", PAPER["n_rollers"], float(b["n_rollers"]), "-", "config bearing.n_rollers"),
        Row(
            "IV",
            "radial load",
            PAPER["radial_load_N"],
            b["radial_load_N"],
            "N",
            f"mean vertical roller load over the healthy record {lpm['healthy']['mean_vertical_load_N']:.2f} N",
        ),
        Row("IV", "shaft speed", PAPER["shaft_speed_rpm"], b["shaft_speed_rpm"], "rpm", ""),
        Row(
            "III-A",
            "FEM time step",
            PAPER["time_step_s"],
            b["time_step_s"],
            "s",
            f"= 1/(36 BPFO) = {1 / (36 * kin['bpfo_Hz']):.7g} s: every sample at the same phase of the roller passage",
        ),
        Row(
            "III-A",
            "defect width",
            PAPER["defect_width_m"],
            b["defect_width_m"],
            "m",
            f"a roller sinks at most {lpm['faulty']['defect_max_drop_m'] * 1e6:.1f} um, not the 1 mm depth",
        ),
        Row(
            "III-A", "defect depth (removed material)", PAPER["defect_depth_m"], b["defect_depth_m"], "m", ""
        ),
        Row(
            "IV",
            "defect impact frequency (LPM)",
            PAPER["bpfo_Hz"],
            lpm["faulty"]["impact_frequency_Hz"],
            "Hz",
            f"{lpm['faulty']['n_impacts']} impacts; paper's BPFO for comparison",
        ),
        Row(
            "III-A",
            "Harris discrete load distribution vs LPM (max rel. diff.)",
            None,
            max(
                lpm["healthy"]["harris_roller_at_bottom"]["max_rel_diff"],
                lpm["healthy"]["harris_rollers_straddling"]["max_rel_diff"],
            ),
            "-",
            f"radial clearance {b['radial_clearance_m'] * 1e6:.0f} um",
        ),
        Row(
            "III-A",
            "housing model: first natural frequency",
            None,
            tr["healthy"]["first_natural_frequency_Hz"],
            "Hz",
            f"above the {0.5 / b['time_step_s']:.0f} Hz Nyquist frequency of the paper's step",
        ),
        Row(
            "IV",
            "sensor force, healthy: mean",
            None,
            tr["healthy"]["sensor_force_mean_N"],
            "N",
            "the paper shows voltage only (Fig. 9)",
        ),
        Row(
            "IV",
            "sensor force, healthy: peak-to-peak",
            None,
            tr["healthy"]["sensor_force_max_N"] - tr["healthy"]["sensor_force_min_N"],
            "N",
            "",
        ),
        Row(
            "IV",
            "sensor force, faulty: peak-to-peak",
            None,
            tr["faulty"]["sensor_force_max_N"] - tr["faulty"]["sensor_force_min_N"],
            "N",
            "",
        ),
        Row(
            "III-A",
            "reduced vs direct FEM, healthy (RMS rel. diff.)",
            None,
            chk.get("rms_rel_diff", float("nan")),
            "-",
            f"over {chk.get('duration_s', float('nan')):.3g} s; sfepy generalized-alpha reference",
        ),
        Row(
            "III-A",
            "mesh convergence: peak-to-peak change to finest level",
            None,
            float(conv["levels"][1]["peak_to_peak_N"] / conv["levels"][2]["peak_to_peak_N"] - 1),
            "-",
            f"levels {[r['level'] for r in conv['levels']]}, {[r['n_dofs'] for r in conv['levels']]} DOFs",
        ),
        Row(
            "III-A",
            "sampling phase: spread of the faulty BPFO amplitude, point sampling",
            None,
            samp["sample"]["bpfo_amplitude_spread"],
            "-",
            "max/min - 1 over the 36 phases of a step",
        ),
        Row(
            "III-A",
            "sampling phase: spread of the faulty BPFO amplitude, step averaging",
            None,
            samp["average"]["bpfo_amplitude_spread"],
            "-",
            "what the workflow uses (bearing.resample)",
        ),
    ]
    write_part(rows, out_csv)
