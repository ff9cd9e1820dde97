"""What the rules of the bearing chain write, in memory: one function per rule (bearing_lpm, housing_mesh,
housing_transient), the rule's inputs in, its outputs' contents out (records as dicts, tables as DataFrames).

The stages in :mod:`piezobearing.stages.bearing` read the inputs, call one of these and write what it returns;
the parameter studies (:mod:`piezobearing.stages.studies`) call the same functions and hand the contents on in
memory (:func:`piezobearing.io.as_read`), so a study case runs the workflow's code path, not a copy of it.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict

import pandas as pd

from ..bearing import lpm
from ..bearing.geometry import BearingGeometry, kinematic_frequencies
from ..housing.checks import lpm_checks
from ..housing.fem import spring_share_factor
from ..housing.mesh import HousingMesh, build_housing_mesh, mesh_quality
from ..housing.transient import (
    CASES,
    housing_geometry,
    is_faulty,
    make_model,
    run_lpm,
    transient,
    transient_summary,
)

log = logging.getLogger("piezobearing.bearing.lpm")


def bearing_lpm(config: dict, method: str = "compiled") -> dict:
    """Rule bearing_lpm: kinematic frequencies and both cases' roller contact loads.

    Returns ``kinematics`` (kinematics.json: shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz without slip;
    cage_slip, slip_jitter, the same frequencies at the mean slip under ``with_slip``, speed_ramp_Hz_per_s,
    defect_types; with a tachometer its pulses_per_rev and pulse times ``tachometer_time_s`` on the record's time
    axis), ``contact`` (per case the arrays of contact_forces_{case}.npz: the fine integration grid
    and the FEM-step series), ``tables`` (per case contact_forces_{case}.csv at the FEM step: time_s,
    load_N_jj, angle_rad_jj) and ``summary`` (lpm.json, the checks). ``method``: the LPM's step loop
    (simulate_lpm), for the benchmark.
    """
    b = config["bearing"]
    geo = BearingGeometry.from_config(b)
    # top level: the kinematic (no-slip) lines, which signals.fault_bands slips itself; "with_slip": at the
    # configured mean cage slip, what the LPM's cage does on average
    kin0 = kinematic_frequencies(geo, b["shaft_speed_rpm"] / 60.0)
    kin = kinematic_frequencies(geo, b["shaft_speed_rpm"] / 60.0, b["cage_slip"])
    operating = {
        "cage_slip": b["cage_slip"],
        "slip_jitter": b["slip_jitter"],
        "with_slip": kin.to_dict(),
        "speed_ramp_Hz_per_s": b["speed_ramp_rpm_per_s"] / 60.0,
        "defect_types": [d["type"] for d in b["defects"]],
    }
    out = {"contact": {}, "tables": {}}
    summary = {
        "kinematics": kin0.to_dict(),
        "kinematics_with_slip": kin.to_dict(),
        "contact_stiffness_N_per_m10_9": lpm.line_contact_stiffness(geo.roller_length_m),
        "config": {"bearing": b},
    }
    for case in CASES:
        t0 = time.perf_counter()
        run = run_lpm(b, is_faulty(case), method, config["seed"])
        log.info("LPM %s: %d steps in %.1f s", case, len(run["fine_time_s"]), time.perf_counter() - t0)
        out["contact"][case] = {k: v for k, v in run.items() if k != "params"}
        df = pd.DataFrame({"time_s": run["time_s"]})
        for j in range(geo.n_rollers):
            df[f"load_N_{j:02d}"] = run["load_N"][:, j]
        for j in range(geo.n_rollers):
            df[f"angle_rad_{j:02d}"] = run["angle_rad"][:, j]
        out["tables"][case] = df
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
    out["kinematics"] = {**kin0.to_dict(), **operating, "config": {"bearing": b}}
    out["summary"] = summary
    return out


def housing_mesh(case: str, config: dict) -> tuple[HousingMesh, dict]:
    """Rule housing_mesh_{case}: the hexahedral mesh and its statistics (housing_mesh_{case}.json)."""
    geo = housing_geometry(config)
    m = build_housing_mesh(geo, is_faulty(case), config["housing"]["mesh_level"])
    record = {
        **mesh_quality(m),
        "case": case,
        "level": m.level,
        "geometry": asdict(geo),
        "config": {k: config[k] for k in ("bearing", "housing", "sensor_fem")},
    }
    return m, record


def housing_transient(case: str, m: HousingMesh, contact: dict, config: dict) -> dict:
    """Rule housing_transient_{case}: the sensor force over time, the modes, the method check.

    ``contact``: the case's arrays of :func:`bearing_lpm` (contact_forces_{case}.npz). Returns ``force``
    (sensor_force_{case}.csv: time_s, force_N), ``influence`` (influence_line_{case}.csv), ``modes``
    (housing_modes_{case}.json), ``summary`` (housing_transient_{case}.json) and ``quasi_static``
    (quasi_static_{case}.npz: the mesh's level, its DOFs and the quasi-static sensor force g(t) [N], which
    the convergence study takes as its row of ``housing.mesh_level`` instead of factorising that mesh again).
    """
    run = transient(case, m, contact, config)
    influence, modes, summary = transient_summary(case, m, run, config)
    return {
        "quasi_static": {
            "level": float(m.level),
            "n_dofs": run["model"].n_dofs,
            "quasi_static_N": run["reduced"]["quasi_static_N"],
        },
        "force": pd.DataFrame({"time_s": run["time_s"], "force_N": run["force_N"]}),
        "influence": pd.DataFrame(influence),
        "modes": {**modes, "config": {"housing": config["housing"]}},
        "summary": {**summary, "config": {k: config[k] for k in ("housing", "bearing", "sensor", "sensor_fem")}},
    }


def fault_type_force(config: dict) -> pd.DataFrame:
    """Rule fault_type_voltage's bearing part: the faulty case's sensor force (time_s, force_N) of ``config``
    in one pass: the LPM (faulty case only), the housing mesh with its grooves, the housing solve."""
    b = config["bearing"]
    run = run_lpm(b, True, "compiled", config["seed"])
    m = build_housing_mesh(housing_geometry(config), True, config["housing"]["mesh_level"])
    tr = transient("faulty", m, {k: run[k] for k in ("time_s", "load_N", "angle_rad")}, config)
    return pd.DataFrame({"time_s": tr["time_s"], "force_N": tr["force_N"]})


def sensor_port(config: dict) -> dict:
    """Rule sensor_design_housing: the housing seen by the sensor, once for the sensor_design study.

    The workflow's path (the housing_mesh rule's healthy mesh at ``housing.mesh_level``, the model with the
    configured sensor spring): its influence line's peak (the configured design's load share) and the
    housing's flexibility at the sensor (the port compliance, which :func:`design_load_share` uses).
    """
    model = make_model(housing_mesh("healthy", config)[0], config)
    return {
        "load_share": float(model.influence_line()[2].max()),
        "sensor_spring_N_per_m": model.sensor_stiffness_N_per_m,
        "port_compliance_m_per_N": model.sensor_port_compliance_m_per_N(),
        "bottom_disk_diameter_m": config["sensor_fem"]["bottom_disk_diameter_m"],
        "n_dofs": model.n_dofs,
        "config": {k: config[k] for k in ("sensor", "sensor_fem", "bearing", "housing")},
    }


def design_load_share(config: dict, port: dict, spring_N_per_m: float) -> float:
    """A sensor design's load share [N/N]: from the housing's port compliance (:func:`sensor_port`; exact for
    the same contact disk: the sensor is a rank-one spring on the housing), else its own housing model."""
    if config["sensor_fem"]["bottom_disk_diameter_m"] == port["bottom_disk_diameter_m"]:
        k_ref, a0 = port["sensor_spring_N_per_m"], port["port_compliance_m_per_N"]
        return port["load_share"] * spring_share_factor(spring_N_per_m, k_ref, a0)
    return float(make_model(housing_mesh("healthy", config)[0], config).influence_line()[2].max())
