"""Stage functions of the bearing and housing model (Sec. III-A, IV; Fig. 3).

bearing_lpm -> housing_mesh_{case} -> housing_transient_{case} -> sensor_force_{case}.csv,
plus the mesh convergence study, the sampling-phase study and the scorecard.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from ..bearing import housing_fem as fem
from ..bearing import lpm as brg
from ..bearing.housing_mesh import HousingGeometry, HousingMesh, build_housing_mesh, mesh_quality
from ..io import read_json, write_json
from ..scorecard import Row, write_part
from ..sensor.materials import CAST_IRON, STEEL, adhesive_from_config, alumina_from_config, pzt_from_config
from . import log_progress

CASES = ("healthy", "faulty")
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


def _case(case: str) -> bool:
    if case not in CASES:
        raise ValueError(f"case must be one of {CASES}, got {case!r}")
    return case == "faulty"


def time_grid(bearing: dict) -> np.ndarray:
    """Output instants 0, dt, ... of the record [s] (duration_s / time_step_s samples)."""
    dt = bearing["time_step_s"]
    return dt * np.arange(int(round(bearing["duration_s"] / dt)))


# ---------------------------------------------------------------------------
# bearing_lpm
# ---------------------------------------------------------------------------


def run_lpm(bearing: dict, faulty: bool, method: str = "compiled", seed: int = 0) -> dict:
    """The LPM on its fine grid and resampled at the FEM step (dict of arrays).

    ``method`` as in simulate_lpm; ``seed``: the config's seed (roller diameters, slip jitter). With
    ``bearing.tachometer_pulses_per_rev`` > 0 the dict has the tachometer's pulse times over the record.
    """
    p = brg.LPMParameters.from_config(bearing, faulty, seed)
    dt = bearing["time_step_s"]
    h = dt / bearing["substeps"]
    t_out = time_grid(bearing)
    t_start = -bearing["settle_s"] - dt
    n_steps = int(np.ceil((t_out[-1] + dt - t_start) / h))
    res = brg.simulate_lpm(p, t_start, n_steps, h, method=method)
    keep = res.time_s >= -dt / 2 - 1e-12
    q_out = brg.resample_loads(res.time_s, res.load_N, t_out, dt, bearing["resample"])
    extra = {}
    if bearing.get("tachometer_pulses_per_rev", 0) > 0:
        extra["tachometer_time_s"] = p.tachometer_times(
            -dt / 2, t_out[-1] + dt / 2, bearing["tachometer_pulses_per_rev"]
        )
    return {
        **extra,
        "fine_time_s": res.time_s[keep],
        "fine_load_N": res.load_N[keep],
        "fine_shaft_m": res.shaft_m[keep],
        "fine_pedestal_m": res.pedestal_m[keep],
        "time_s": t_out,
        "load_N": q_out,
        "angle_rad": p.roller_angles(t_out),
        "newton_iterations": res.newton_iterations,
        "params": p,
    }


def _impact_intervals(t: np.ndarray, qmax: np.ndarray, bpfo: float) -> np.ndarray:
    """Times between the defect's load peaks (largest roller load within each roller period)."""
    from scipy.signal import find_peaks

    dt = t[1] - t[0]
    peaks, _ = find_peaks(
        qmax, distance=max(1, int(0.6 / bpfo / dt)), prominence=0.05 * (qmax.max() - qmax.min())
    )
    # a peak within half a period of either end may be the record's edge, not an impact
    inner = (t[peaks] > t[0] + 0.5 / bpfo) & (t[peaks] < t[-1] - 0.5 / bpfo)
    return np.diff(t[peaks[inner]])


def lpm_checks(run: dict, kin: brg.KinematicFrequencies) -> dict:
    """Verification numbers of one LPM run: static Harris check, load balance, impact period."""
    p: brg.LPMParameters = run["params"]
    g = p.geometry
    out = {}
    # quasi-static check in the two symmetric roller positions (healthy bearing)
    for name, psi0 in (("roller_at_bottom", 0.0), ("rollers_straddling", 0.5 * g.roller_pitch_rad)):
        psi = psi0 + g.roller_pitch_rad * np.arange(g.n_rollers)
        e = brg.static_offset(
            np.array([0.0, -p.radial_load_N]), psi, p.gap_m, np.zeros_like(psi), p.k_contact
        )
        _, _, q = brg.bearing_force(e, psi, p.gap_m, np.zeros_like(psi), p.k_contact)
        qh, dr = brg.harris_discrete_loads(p.radial_load_N, psi, p.gap_m, p.k_contact)
        out[f"harris_{name}"] = {
            "lpm_N": q.tolist(),
            "harris_N": qh.tolist(),
            "max_rel_diff": float(np.abs(q - qh).max() / qh.max()),
            "shift_m": float(dr),
        }
    q, psi = run["fine_load_N"], p.roller_angles(run["fine_time_s"])
    fz = np.sum(q * -np.cos(psi), axis=1)
    fy = np.sum(q * np.sin(psi), axis=1)
    out["mean_vertical_load_N"] = float(-fz.mean())
    out["mean_horizontal_load_N"] = float(fy.mean())
    out["max_roller_load_N"] = float(q.max())
    out["loaded_rollers_min_max"] = [int((q > 0).sum(1).min()), int((q > 0).sum(1).max())]
    if p.defects:
        rate = {"outer_race": kin.bpfo_Hz, "inner_race": kin.bpfi_Hz, "rolling_element": 2 * kin.bsf_Hz}
        drops = p.defect_max_drops_m()
        out["defects"] = [
            {
                "type": d.kind,
                "width_m": d.width_m,
                "max_drop_m": drop,
                "max_drop_flat_raceway_m": d.max_drop_m(0.5 * g.roller_diameter_m),
                "impact_rate_Hz": rate[d.kind],
            }
            for d, drop in zip(p.defects, drops, strict=True)
        ]
        out["defect_max_drop_m"] = drops[0]
    if p.defects and p.defects[0].kind == "outer_race":
        # the paper's case: a fixed groove, every roller strikes it at BPFO
        iv = _impact_intervals(run["fine_time_s"], q.max(axis=1), kin.bpfo_Hz)
        out["impact_interval_mean_s"] = float(iv.mean()) if len(iv) else float("nan")
        out["impact_interval_std_s"] = float(iv.std()) if len(iv) else float("nan")
        out["impact_frequency_Hz"] = float(1 / iv.mean()) if len(iv) else float("nan")
        out["n_impacts"] = int(len(iv) + 1)
    return out


def bearing_lpm(
    out_kinematics: str, out_npz: dict, out_csv: dict, out_json: str, config: dict, method: str = "compiled"
) -> None:
    """Stage bearing_lpm: kinematic frequencies and both cases' roller contact loads.

    Writes ``kinematics.json`` (shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz without slip; cage_slip,
    slip_jitter, the same frequencies at the mean slip under ``with_slip``, speed_ramp_Hz_per_s, defect_types),
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
    write_json({**kin0.to_dict(), **operating, "config": {"bearing": b}}, out_kinematics)
    summary = {
        "kinematics": kin0.to_dict(),
        "kinematics_with_slip": kin.to_dict(),
        "contact_stiffness_N_per_m10_9": brg.line_contact_stiffness(geo.roller_length_m),
        "config": {"bearing": b},
    }
    for case in CASES:
        t0 = time.perf_counter()
        run = run_lpm(b, _case(case), method, config["seed"])
        secs = time.perf_counter() - t0
        log.info("LPM %s: %d steps in %.1f s", case, len(run["fine_time_s"]), secs)
        Path(out_npz[case]).parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(out_npz[case], **{k: v for k, v in run.items() if k != "params"})
        z = geo.n_rollers
        df = pd.DataFrame({"time_s": run["time_s"]})
        for j in range(z):
            df[f"load_N_{j:02d}"] = run["load_N"][:, j]
        for j in range(z):
            df[f"angle_rad_{j:02d}"] = run["angle_rad"][:, j]
        df.to_csv(out_csv[case], index=False, float_format="%.9g")
        summary[case] = {
            **lpm_checks(run, kin),
            "fine_step_s": float(run["fine_time_s"][1] - run["fine_time_s"][0]),
            "newton_iterations_per_step": run["newton_iterations"] / len(run["fine_time_s"]),
        }
    write_json(summary, out_json)


# ---------------------------------------------------------------------------
# housing_mesh
# ---------------------------------------------------------------------------


def housing_geometry(config: dict) -> HousingGeometry:
    """The housing model's geometry; the sensor's contact disk is the sensor FEM's (``sensor_fem.bottom_disk_*``)."""
    return HousingGeometry.from_config(
        config["bearing"], config["housing"], config["sensor_fem"]["bottom_disk_diameter_m"]
    )


def save_mesh(m: HousingMesh, path: str | Path) -> None:
    """The mesh and its node sets as NPZ (the geometry is rebuilt from the config)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path,
        coors=m.coors,
        conn=m.conn,
        group=m.group,
        raceway_psi=m.raceway_psi,
        raceway_x=m.raceway_x,
        raceway_nodes=m.raceway_nodes,
        ring_outer_psi=m.ring_outer_psi,
        ring_outer_nodes=m.ring_outer_nodes,
        base_nodes=m.base_nodes,
        faulty=m.faulty,
        level=m.level,
        geometry=json.dumps(asdict(m.geometry)),
    )


def load_mesh(path: str | Path) -> HousingMesh:
    d = np.load(path)
    geo = HousingGeometry(**json.loads(str(d["geometry"])))
    keys = (
        "coors conn group raceway_psi raceway_x raceway_nodes ring_outer_psi ring_outer_nodes base_nodes"
    ).split()
    return HousingMesh(
        **{k: d[k] for k in keys}, geometry=geo, faulty=bool(d["faulty"]), level=float(d["level"])
    )


def write_vtk(m: HousingMesh, path: str | Path) -> None:
    import meshio

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, meshio.Mesh(m.coors, [("hexahedron", m.conn)], cell_data={"group": [m.group]}))


def housing_mesh(case: str, out_npz: str, out_vtk: str, out_json: str, config: dict) -> None:
    """Stage housing_mesh_{case}: the hexahedral mesh (NPZ for the solver, VTK to view) and its statistics."""
    geo = housing_geometry(config)
    m = build_housing_mesh(geo, _case(case), config["housing"]["mesh_level"])
    save_mesh(m, out_npz)
    write_vtk(m, out_vtk)
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


# ---------------------------------------------------------------------------
# housing_transient
# ---------------------------------------------------------------------------


def sensor_spring(config: dict) -> float:
    """Axial stiffness of the sensor stack from the config [N/m] (tip disk, its bond layer, PZT)."""
    s, h, sf = config["sensor"], config["housing"], config["sensor_fem"]
    return fem.sensor_stiffness(
        pzt_from_config(s),
        s["pzt_diameter_m"],
        s["pzt_height_m"],
        alumina_from_config(sf),
        sf["bottom_disk_diameter_m"],
        sf["bottom_disk_height_m"],
        h["sensor_electrical"],
        adhesive_from_config(sf),
        sf["adhesive_height_m"],
    )


def make_model(m: HousingMesh, config: dict) -> fem.HousingModel:
    return fem.build_model(m, STEEL, CAST_IRON, sensor_spring(config), config["housing"]["patch_width_m"])


def load_contact(path: str | Path) -> dict:
    d = np.load(path)
    return {k: d[k] for k in d.files}


def bearing_seat_stiffness(model: fem.HousingModel, load_N: np.ndarray, angle_rad: np.ndarray) -> float:
    """Stiffness of the housing seen by the bearing: F_r / (load-weighted mean radial displacement) [N/m].

    The loads of one time sample are applied; the displacement is the mean
    over the loaded raceway columns of their radial displacement, weighted by
    the load. A value for the LPM's pedestal stiffness.
    """
    wy, wz = model.column_loads(load_N[None], angle_rad[None])
    f = model.load_vectors(wy, wz)[0]
    u = np.zeros(3 * model.mesh.n_nodes)
    u[model.free] = model.factor().solve(f)
    psi = model.mesh.raceway_psi
    nodes = model.mesh.raceway_nodes
    ur = (u[3 * nodes + 1] * np.sin(psi)[:, None] - u[3 * nodes + 2] * np.cos(psi)[:, None]).mean(axis=1)
    w = np.hypot(wy[0], wz[0])
    resultant = float(np.hypot(wy[0].sum(), wz[0].sum()))
    return resultant / float(w @ ur / w.sum())


def mode_direction_shares(model: fem.HousingModel, modes: fem.Modes) -> np.ndarray:
    """Share of each mode's kinetic energy in x (axial), y (horizontal) and z (vertical) motion, (n, 3).

    A label of the mode's shape: e.g. (0, 0.9, 0.1) is a sideways rocking of the housing.
    """
    comp = model.free % 3
    out = np.zeros((modes.shapes.shape[1], 3))
    mphi = model.M @ modes.shapes
    for c in range(3):
        sel = comp == c
        out[:, c] = np.einsum("ij,ij->j", modes.shapes[sel], mphi[sel])
    return out / out.sum(axis=1, keepdims=True)


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
    h, b = config["housing"], config["bearing"]
    dt = b["time_step_s"]
    timings = {}
    t0 = time.perf_counter()
    m = load_mesh(mesh_npz)
    model = make_model(m, config)
    timings["assemble_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model.factor()
    timings["factor_s"] = time.perf_counter() - t0
    log.info(
        "%s: %d DOFs, assembled in %.1f s, factorised in %.1f s",
        case,
        model.n_dofs,
        timings["assemble_s"],
        timings["factor_s"],
    )
    t0 = time.perf_counter()
    modes = fem.compute_modes(model, h["n_modes"], seed=config["seed"])
    timings["modes_s"] = time.perf_counter() - t0
    top, nyq = float(modes.frequencies_Hz.max()), 0.5 / dt
    if h["method"] == "reduced" and top < nyq:
        # the static correction holds for modes well above the band only (README, housing at DAQ rates)
        raise ValueError(
            f"housing.n_modes = {h['n_modes']}: the highest mode, {top:.0f} Hz, lies below the Nyquist frequency "
            f"{nyq:.0f} Hz of bearing.time_step_s; raise housing.n_modes until it passes {nyq:.0f} Hz"
        )
    alpha, beta = fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])
    c = load_contact(contact_npz)
    t, q, psi = c["time_s"], c["load_N"], c["angle_rad"]
    wy, wz = model.column_loads(q, psi)
    t0 = time.perf_counter()
    ops = fem.reduced_operators(model, modes, alpha, beta)
    red = fem.sensor_force_reduced(ops, wy, wz, dt)
    timings["reduced_response_s"] = time.perf_counter() - t0
    check = None
    n_check = min(len(t), int(round(h["direct_check_s"] / dt)) + 1)
    if h["method"] == "direct":
        n_check = len(t)
    if n_check > 1:
        log.info("%s: direct reference over %d steps", case, n_check)
        d = fem.sensor_force_direct(
            model,
            wy[:n_check],
            wz[:n_check],
            dt,
            alpha,
            beta,
            h["rho_inf"],
            progress=lambda k, n: log.info("  direct step %d / %d", k, n),
        )
        timings["direct_s"] = d["seconds"]
        diff = d["force_N"] - red["force_N"][:n_check]
        rms = float(np.sqrt(np.mean(red["force_N"][:n_check] ** 2)))
        ac = float(np.std(red["force_N"][:n_check]))
        check = {
            "n_steps": n_check,
            "duration_s": float(t[n_check - 1]),
            "rms_rel_diff": float(np.sqrt(np.mean(diff**2)) / rms),
            "rms_rel_diff_of_variation": float(np.sqrt(np.mean(diff**2)) / ac),
            "max_abs_diff_N": float(np.abs(diff).max()),
        }
        force = d["force_N"] if h["method"] == "direct" else red["force_N"]
    else:
        force = red["force_N"]
    # wall-clock times go to the log (and the rule's benchmark file), never into results: two runs of the
    # same config must give byte-identical result files
    log.info("%s: timings [s] %s", case, ", ".join(f"{k} {v:.2f}" for k, v in timings.items()))
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame({"time_s": t, "force_N": force}).to_csv(out_csv, index=False, float_format="%.9g")
    gy, gz, radial = model.influence_line()
    pd.DataFrame(
        {
            "angle_rad": m.raceway_psi,
            "sensor_per_y_load": gy,
            "sensor_per_z_load": gz,
            "sensor_per_radial_load": radial,
        }
    ).to_csv(out_influence, index=False, float_format="%.9g")
    freqs = modes.frequencies_Hz
    write_json(
        {
            "case": case,
            "natural_frequencies_Hz": freqs.tolist(),
            "direction_share_xyz": mode_direction_shares(model, modes).tolist(),
            "nyquist_Hz": 0.5 / dt,
            "modal_damping_ratio": ops.zeta.tolist(),
            "n_dofs": model.n_dofs,
            "config": {"housing": h},
        },
        out_modes,
    )
    seat = bearing_seat_stiffness(model, q[0], psi[0])
    write_json(
        {
            "case": case,
            "method": h["method"],
            "n_dofs": model.n_dofs,
            "n_nodes": m.n_nodes,
            "n_cells": m.n_cells,
            "model_mass_kg": model.mass_kg,
            "sensor_stiffness_N_per_m": model.sensor_stiffness_N_per_m,
            "bearing_seat_stiffness_N_per_m": seat,
            "first_natural_frequency_Hz": float(freqs[0]),
            "rayleigh_alpha_per_s": alpha,
            "rayleigh_beta_s": beta,
            "influence_at_sensor_N_per_N": float(np.interp(0.0, m.raceway_psi, radial)),
            "sensor_force_mean_N": float(force.mean()),
            "sensor_force_min_N": float(force.min()),
            "sensor_force_max_N": float(force.max()),
            "sensor_force_std_N": float(force.std()),
            "dynamic_part_rms_N": float(np.sqrt(np.mean(red["dynamic_N"] ** 2))),
            "direct_check": check,
            "time_step_s": dt,
            "n_samples": len(t),
            "config": {k: config[k] for k in ("housing", "bearing", "sensor", "sensor_fem")},
        },
        out_json,
    )


# ---------------------------------------------------------------------------
# Mesh convergence
# ---------------------------------------------------------------------------


def quasi_static_force(model: fem.HousingModel, load_N: np.ndarray, angle_rad: np.ndarray) -> np.ndarray:
    """Quasi-static sensor force g(t) = sum_j Q_j (K^-1 c) . p(psi_j) [N]."""
    gy, gz, _ = model.influence_line()
    wy, wz = model.column_loads(load_N, angle_rad)
    return wy @ gy + wz @ gz


def harmonic_amplitudes(x: np.ndarray, dt: float, f0: float, n: int) -> np.ndarray:
    """Amplitudes of the harmonics k f0, k = 1..n, by least squares on the record (no leakage) [unit of x]."""
    t = dt * np.arange(len(x))
    k = np.arange(1, n + 1)
    a = np.column_stack(
        [np.ones_like(t)] + [f(2 * np.pi * kk * f0 * t) for kk in k for f in (np.cos, np.sin)]
    )
    coef = np.linalg.lstsq(a, x, rcond=None)[0]
    return np.hypot(coef[1::2], coef[2::2])


def mesh_convergence(contact_npz: str, out_json: str, out_csv: str, config: dict) -> None:
    """Sensor force amplitude (healthy, quasi-static) on three mesh levels.

    The dynamic part of the sensor force is below 1e-3 of it (see
    transient_healthy.json), so the convergence of the quasi-static force
    measures the mesh's. One factorisation a level.
    """
    log_progress()
    h, b = config["housing"], config["bearing"]
    c = load_contact(contact_npz)
    kin = brg.kinematic_frequencies(brg.BearingGeometry.from_config(b), b["shaft_speed_rpm"] / 60.0)
    geo = housing_geometry(config)
    rows = []
    for level in h["convergence_levels"]:
        t0 = time.perf_counter()
        m = build_housing_mesh(geo, False, level)
        model = make_model(m, config)
        f = quasi_static_force(model, c["load_N"], c["angle_rad"])
        amp = harmonic_amplitudes(f, b["time_step_s"], kin.bpfo_Hz, 3)
        rows.append(
            {
                "level": level,
                "n_dofs": model.n_dofs,
                "peak_to_peak_N": float(f.max() - f.min()),
                "mean_N": float(f.mean()),
                "bpfo_amplitude_N": float(amp[0]),
            }
        )
        log.info(
            "level %.2f: %d DOFs, peak-to-peak %.4f N, %.1f s (wall clock, not written to the results)",
            level,
            model.n_dofs,
            rows[-1]["peak_to_peak_N"],
            time.perf_counter() - t0,
        )
        del model
    df = pd.DataFrame(rows)
    ref = df["peak_to_peak_N"].iloc[-1]
    df["rel_change_to_finest"] = df["peak_to_peak_N"] / ref - 1
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)
    p2p = df["peak_to_peak_N"].to_numpy()
    lv = np.asarray(h["convergence_levels"], dtype=float)
    # observed order for sizes h ~ 1/level (levels in geometric progression or not: solve for p numerically)
    order = float("nan")
    extrapolated = float("nan")
    d1, d2 = p2p[1] - p2p[0], p2p[2] - p2p[1]
    if (
        d1 != 0
        and d2 != 0
        and np.sign(d1) == np.sign(d2)
        and np.isclose(lv[1] / lv[0], lv[2] / lv[1], rtol=0.05)
    ):
        r = lv[1] / lv[0]
        order = float(np.log(abs(d1 / d2)) / np.log(r))
        extrapolated = float(p2p[2] + d2 / (r**order - 1))
    write_json(
        {
            "levels": rows,
            "observed_order": order,
            "extrapolated_peak_to_peak_N": extrapolated,
            "default_level": h["mesh_level"],
            "config": {"housing": h},
        },
        out_json,
    )


# ---------------------------------------------------------------------------
# The sampling phase: dt = 1/(36 BPFO)
# ---------------------------------------------------------------------------


def _sampled(t_fine, f_fine, dt, t0, n, mode):
    t = t0 + dt * np.arange(n)
    if mode == "sample":
        return np.interp(t, t_fine, f_fine)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(t_fine) * (f_fine[1:] + f_fine[:-1]))])
    return (np.interp(t + dt / 2, t_fine, cum) - np.interp(t - dt / 2, t_fine, cum)) / dt


def off_harmonic_fraction(x: np.ndarray, dt: float, f0: float) -> float:
    """Share of the variance of x off the harmonics of f0 (least-squares fit of all harmonics below Nyquist)."""
    n = int(np.floor(0.5 / dt / f0 - 1e-9))
    t = dt * np.arange(len(x))
    a = np.column_stack(
        [np.ones_like(t)] + [f(2 * np.pi * k * f0 * t) for k in range(1, n + 1) for f in (np.cos, np.sin)]
    )
    resid = x - a @ np.linalg.lstsq(a, x, rcond=None)[0]
    return float(np.var(resid) / np.var(x))


def sampling_phase(contact_npz: str, influence_csv: str, out_json: str, config: dict) -> None:
    """What the step 1/(36 BPFO) does to the sensor force of the faulty bearing.

    The quasi-static sensor force is evaluated on the LPM's fine grid and
    sampled at the paper's step with the sampling instants shifted by a
    fraction phi of a step (equivalently, a different starting roller angle),
    by point sampling and by step averaging; for each, the BPFO amplitude, the
    peak-to-peak and the share of variance off the BPFO harmonics; and the same
    at a step of 1/2500 s, not commensurate with the roller passage.
    """
    b = config["bearing"]
    c = load_contact(contact_npz)
    inf = pd.read_csv(influence_csv)
    p = brg.LPMParameters.from_config(b, True, config["seed"])
    kin = brg.kinematic_frequencies(p.geometry, p.shaft_speed_Hz, p.cage_slip)
    tf = c["fine_time_s"]
    psi = p.roller_angles(tf)
    order = np.argsort(inf["angle_rad"].to_numpy())
    ang = inf["angle_rad"].to_numpy()[order]
    g = inf["sensor_per_radial_load"].to_numpy()[order]
    gfun = np.interp(psi, ang, g, period=2 * np.pi)
    f_fine = np.sum(c["fine_load_N"] * gfun, axis=1)
    dt = b["time_step_s"]
    n_out = int(np.floor((tf[-1] - tf[0] - 2 * dt) / dt))
    phases = np.arange(0, 36) / 36
    out = {
        "bpfo_Hz": kin.bpfo_Hz,
        "time_step_s": dt,
        "steps_per_roller_passage": 1 / (dt * kin.bpfo_Hz),
        "phases_of_step": phases.tolist(),
        "config": {"bearing": b},
    }
    for mode in ("sample", "average"):
        amp, p2p, off = [], [], []
        for ph in phases:
            x = _sampled(tf, f_fine, dt, tf[0] + dt + ph * dt, n_out, mode)
            amp.append(float(harmonic_amplitudes(x, dt, kin.bpfo_Hz, 1)[0]))
            p2p.append(float(x.max() - x.min()))
            off.append(off_harmonic_fraction(x, dt, kin.bpfo_Hz))
        out[mode] = {
            "bpfo_amplitude_N": amp,
            "peak_to_peak_N": p2p,
            "off_harmonic_variance_fraction": off,
            "bpfo_amplitude_spread": float(max(amp) / min(amp) - 1),
            "peak_to_peak_spread": float(max(p2p) / min(p2p) - 1),
        }
    dt2 = 1 / 2500.0
    n2 = int(np.floor((tf[-1] - tf[0] - 2 * dt2) / dt2))
    out["incommensurate_step_s"] = dt2
    for mode in ("sample", "average"):
        x = _sampled(tf, f_fine, dt2, tf[0] + dt2, n2, mode)
        out[f"incommensurate_{mode}"] = {
            "off_harmonic_variance_fraction": off_harmonic_fraction(x, dt2, kin.bpfo_Hz),
            "peak_to_peak_N": float(x.max() - x.min()),
        }
    fine_dt = tf[1] - tf[0]
    out["fine_grid"] = {"step_s": float(fine_dt), "peak_to_peak_N": float(f_fine.max() - f_fine.min())}
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
    groove = next((d for d in b["defects"] if d["type"] == "outer_race"), None)  # the paper's defect
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
            groove["width_m"] if groove else None,
            "m",
            (
                f"a roller sinks at most {lpm['faulty']['defect_max_drop_m'] * 1e6:.1f} um against the concave "
                f"raceway ({lpm['faulty']['defects'][0]['max_drop_flat_raceway_m'] * 1e6:.1f} um on a flat one, "
                "as before issue 11), not the 1 mm depth"
                if groove
                else "no outer-race defect configured"
            ),
        ),
        Row(
            "III-A",
            "defect depth (removed material)",
            PAPER["defect_depth_m"],
            groove["depth_m"] if groove else None,
            "m",
            "",
        ),
        Row(
            "IV",
            "defect impact frequency (LPM)",
            PAPER["bpfo_Hz"],
            lpm["faulty"].get("impact_frequency_Hz"),
            "Hz",
            f"{lpm['faulty']['n_impacts']} impacts; paper's BPFO for comparison"
            if "n_impacts" in lpm["faulty"]
            else "the first configured defect is not on the outer race",
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
