"""The bearing in its housing over time (Sec. III-A, IV): the LPM on the record's grid, the housing model
built from the config, the sensor force by modal reduction with its check against the direct solve.

Pure functions of arrays, frozen dataclasses and the validated config sections; the stages in
:mod:`piezobearing.stages.bearing` read and write the files.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ..bearing import lpm
from ..sensor.materials import CAST_IRON, STEEL, adhesive_from_config, alumina_from_config, pzt_from_config
from . import fem as housing_fem
from .mesh import HousingGeometry, HousingMesh

log = logging.getLogger("piezobearing.bearing.lpm")

CASES = ("healthy", "faulty")


def is_faulty(case: str) -> bool:
    """True for the ``faulty`` case, False for ``healthy``; anything else is a ValueError."""
    if case not in CASES:
        raise ValueError(f"case must be one of {CASES}, got {case!r}")
    return case == "faulty"


def time_grid(bearing: dict) -> np.ndarray:
    """Output instants 0, dt, ... of the record [s] (duration_s / time_step_s samples)."""
    dt = bearing["time_step_s"]
    return dt * np.arange(int(round(bearing["duration_s"] / dt)))


def run_lpm(bearing: dict, faulty: bool, method: str = "compiled", seed: int = 0, base_motion=None,
            realisation: int = 0) -> dict:
    """The LPM on its fine grid and resampled at the FEM step (dict of arrays; ``params``: the LPMParameters).

    ``method`` as in :func:`~piezobearing.bearing.lpm.simulate_lpm`; ``seed``: the config's seed (roller
    diameters, slip jitter). With ``bearing.tachometer_pulses_per_rev`` > 0 the dict has the tachometer's
    pulse times over the record. ``base_motion``: None (the ground at rest) or a function of the LPM's fine
    time grid [s] giving the ground's acceleration (n, 2) [m/s^2] (y, z;
    :func:`piezobearing.housing.base_motion.realisation`); the dict then holds it on the fine grid
    (``fine_base_acceleration_m_per_s2``) and at the FEM step (``base_acceleration_m_per_s2``, treated as the
    roller loads are, ``bearing.resample``), and the displacements are relative to the ground.
    ``realisation``: which draw of the bearing's surfaces and unbalance phase (``bearing.roughness_rms_m``,
    ``waviness_*``, ``unbalance_kg_m``; :mod:`piezobearing.bearing.surface`); nothing is drawn where they are off.
    """
    p = lpm.LPMParameters.from_config(bearing, faulty, seed, realisation)
    dt = bearing["time_step_s"]
    h = dt / bearing["substeps"]
    t_out = time_grid(bearing)
    t_start = -bearing["settle_s"] - dt
    n_steps = int(np.ceil((t_out[-1] + dt - t_start) / h))
    extra = {}
    ab = None
    if base_motion is not None:
        ab = np.asarray(base_motion(t_start + h * np.arange(n_steps + 1)), dtype=float)
    res = lpm.simulate_lpm(p, t_start, n_steps, h, method=method, base_acceleration_m_per_s2=ab)
    keep = res.time_s >= -dt / 2 - 1e-12
    q_out = lpm.resample_loads(res.time_s, res.load_N, t_out, dt, bearing["resample"])
    if ab is not None:
        extra["fine_base_acceleration_m_per_s2"] = ab[keep]
        extra["base_acceleration_m_per_s2"] = lpm.resample_loads(res.time_s, ab, t_out, dt, bearing["resample"])
    if bearing["tachometer_pulses_per_rev"] > 0:
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


def housing_geometry(config: dict) -> HousingGeometry:
    """The housing model's geometry; the sensor's contact disk is the sensor FEM's (``sensor_fem.bottom_disk_*``)."""
    return HousingGeometry.from_config(
        config["bearing"], config["housing"], config["sensor_fem"]["bottom_disk_diameter_m"]
    )


def sensor_spring(config: dict) -> float:
    """Axial stiffness of the sensor stack from the config [N/m] (tip disk, its bond layer, PZT)."""
    s, h, sf = config["sensor"], config["housing"], config["sensor_fem"]
    return housing_fem.sensor_stiffness(
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


def make_model(m: HousingMesh, config: dict) -> housing_fem.HousingModel:
    """The housing model of a mesh: steel ring, cast-iron housing, the configured sensor spring and patch."""
    return housing_fem.build_model(m, STEEL, CAST_IRON, sensor_spring(config), config["housing"]["patch_width_m"])


def bearing_seat_stiffness(model: housing_fem.HousingModel, load_N: np.ndarray, angle_rad: np.ndarray) -> float:
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


def mode_direction_shares(model: housing_fem.HousingModel, modes: housing_fem.Modes) -> np.ndarray:
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


def direct_check(direct_N: np.ndarray, reduced_N: np.ndarray, t: np.ndarray) -> dict:
    """The reduced solve against the direct one over the first ``len(direct_N)`` steps (relative RMS differences)."""
    n_check = len(direct_N)
    diff = direct_N - reduced_N[:n_check]
    rms = float(np.sqrt(np.mean(reduced_N[:n_check] ** 2)))
    ac = float(np.std(reduced_N[:n_check]))
    return {
        "n_steps": n_check,
        "duration_s": float(t[n_check - 1]),
        "rms_rel_diff": float(np.sqrt(np.mean(diff**2)) / rms),
        "rms_rel_diff_of_variation": float(np.sqrt(np.mean(diff**2)) / ac),
        "max_abs_diff_N": float(np.abs(diff).max()),
    }


def transient(case: str, m: HousingMesh, contact: dict, config: dict) -> dict:
    """The sensor force over the record of one case, the housing's modes and the method check.

    ``contact``: the LPM's arrays at the FEM step (``time_s``, ``load_N``,
    ``angle_rad``). The reduced modal solve gives the force; the direct
    (generalized-alpha) solve runs over ``housing.direct_check_s`` as its check,
    or over the whole record when ``housing.method`` is ``direct`` (then its
    force is the result). Returns a dict with the model, the modes, the
    Rayleigh coefficients, the reduced operators and response, the force [N]
    and the check (None without a direct solve). Wall-clock times go to the log only.
    """
    h, dt = config["housing"], config["bearing"]["time_step_s"]
    timings = {}
    t0 = time.perf_counter()
    model = make_model(m, config)
    timings["assemble_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model.factor()
    timings["factor_s"] = time.perf_counter() - t0
    log.info("%s: %d DOFs, assembled in %.1f s, factorised in %.1f s", case, model.n_dofs,
             timings["assemble_s"], timings["factor_s"])
    t0 = time.perf_counter()
    modes = housing_fem.compute_modes(model, h["n_modes"], seed=config["seed"])
    timings["modes_s"] = time.perf_counter() - t0
    top, nyq = float(modes.frequencies_Hz.max()), 0.5 / dt
    if h["method"] == "reduced" and top < nyq:
        # the static correction holds for modes well above the band only (docs/theory/bearing_housing.md)
        raise ValueError(
            f"housing.n_modes = {h['n_modes']}: the highest mode, {top:.0f} Hz, lies below the Nyquist frequency "
            f"{nyq:.0f} Hz of bearing.time_step_s; raise housing.n_modes until it passes {nyq:.0f} Hz"
        )
    alpha, beta = housing_fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])
    t, q, psi = contact["time_s"], contact["load_N"], contact["angle_rad"]
    wy, wz = model.column_loads(q, psi)
    t0 = time.perf_counter()
    ops = housing_fem.reduced_operators(model, modes, alpha, beta)
    red = housing_fem.sensor_force_reduced(ops, wy, wz, dt)
    timings["reduced_response_s"] = time.perf_counter() - t0
    check = None
    force = red["force_N"]
    n_check = len(t) if h["method"] == "direct" else min(len(t), int(round(h["direct_check_s"] / dt)) + 1)
    if n_check > 1:
        log.info("%s: direct reference over %d steps", case, n_check)
        d = housing_fem.sensor_force_direct(
            model, wy[:n_check], wz[:n_check], dt, alpha, beta, h["rho_inf"],
            progress=lambda k, n: log.info("  direct step %d / %d", k, n),
        )
        timings["direct_s"] = d["seconds"]
        check = direct_check(d["force_N"], red["force_N"], t)
        if h["method"] == "direct":
            force = d["force_N"]
    # wall-clock times go to the log (and the rule's benchmark file), never into results: two runs of the
    # same config must give byte-identical result files
    log.info("%s: timings [s] %s", case, ", ".join(f"{k} {v:.2f}" for k, v in timings.items()))
    return {"model": model, "modes": modes, "alpha": alpha, "beta": beta, "ops": ops, "reduced": red,
            "force_N": force, "check": check, "time_s": t, "seat_load": (q[0], psi[0])}


def transient_summary(case: str, m: HousingMesh, run: dict, config: dict) -> tuple[dict, dict, dict]:
    """The result tables of :func:`transient`: (influence line columns, modes record, transient record)."""
    h, dt = config["housing"], config["bearing"]["time_step_s"]
    model, modes, force = run["model"], run["modes"], run["force_N"]
    gy, gz, radial = model.influence_line()
    influence = {
        "angle_rad": m.raceway_psi,
        "sensor_per_y_load": gy,
        "sensor_per_z_load": gz,
        "sensor_per_radial_load": radial,
    }
    freqs = modes.frequencies_Hz
    modes_rec = {
        "case": case,
        "natural_frequencies_Hz": freqs.tolist(),
        "direction_share_xyz": mode_direction_shares(model, modes).tolist(),
        "nyquist_Hz": 0.5 / dt,
        "modal_damping_ratio": run["ops"].zeta.tolist(),
        "n_dofs": model.n_dofs,
    }
    summary = {
        "case": case,
        "method": h["method"],
        "n_dofs": model.n_dofs,
        "n_nodes": m.n_nodes,
        "n_cells": m.n_cells,
        "model_mass_kg": model.mass_kg,
        "sensor_stiffness_N_per_m": model.sensor_stiffness_N_per_m,
        "bearing_seat_stiffness_N_per_m": bearing_seat_stiffness(model, *run["seat_load"]),
        "first_natural_frequency_Hz": float(freqs[0]),
        "rayleigh_alpha_per_s": run["alpha"],
        "rayleigh_beta_s": run["beta"],
        "influence_at_sensor_N_per_N": float(np.interp(0.0, m.raceway_psi, radial)),
        "sensor_force_mean_N": float(force.mean()),
        "sensor_force_min_N": float(force.min()),
        "sensor_force_max_N": float(force.max()),
        "sensor_force_std_N": float(force.std()),
        "dynamic_part_rms_N": float(np.sqrt(np.mean(run["reduced"]["dynamic_N"] ** 2))),
        "direct_check": run["check"],
        "time_step_s": dt,
        "n_samples": len(run["time_s"]),
    }
    return influence, modes_rec, summary
