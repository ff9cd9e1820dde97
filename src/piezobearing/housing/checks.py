"""Verification of the bearing and housing model (Sec. III-A): the LPM's static and impact checks, the housing
mesh convergence of the sensor force, and what the paper's step 1/(36 BPFO) does to the sampled force.

Pure functions of arrays and the validated config sections; the stages in
:mod:`piezobearing.stages.bearing` read and write the files.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pandas as pd

from ..bearing import lpm
from ..bearing.geometry import BearingGeometry, kinematic_frequencies
from ..bearing.kinematics import Kinematics
from . import fem as housing_fem
from .mesh import build_housing_mesh
from .transient import housing_geometry, make_model

log = logging.getLogger("piezobearing.bearing.lpm")


# --------------------------------------------------------------------------- LPM checks


def impact_intervals(t: np.ndarray, qmax: np.ndarray, bpfo: float) -> np.ndarray:
    """Times between the defect's load peaks (largest roller load within each roller period) [s]."""
    dt = t[1] - t[0]
    # Imported here: scipy.signal costs about a second of import, which every bearing job would pay for this
    # check's peaks alone.
    from scipy.signal import find_peaks

    peaks, _ = find_peaks(
        qmax, distance=max(1, int(0.6 / bpfo / dt)), prominence=0.05 * (qmax.max() - qmax.min())
    )
    # a peak within half a period of either end may be the record's edge, not an impact
    inner = (t[peaks] > t[0] + 0.5 / bpfo) & (t[peaks] < t[-1] - 0.5 / bpfo)
    return np.diff(t[peaks[inner]])


def lpm_checks(run: dict, kin: Kinematics) -> dict:
    """Verification numbers of one LPM run: static Harris check, load balance, impact period."""
    p: lpm.LPMParameters = run["params"]
    g = p.geometry
    out = {}
    # quasi-static check in the two symmetric roller positions (healthy bearing)
    for name, psi0 in (("roller_at_bottom", 0.0), ("rollers_straddling", 0.5 * g.roller_pitch_rad)):
        psi = psi0 + g.roller_pitch_rad * np.arange(g.n_rollers)
        e = lpm.static_offset(
            np.array([0.0, -p.radial_load_N]), psi, p.gap_m, np.zeros_like(psi), p.k_contact
        )
        _, _, q = lpm.bearing_force(e, psi, p.gap_m, np.zeros_like(psi), p.k_contact)
        qh, dr = lpm.harris_discrete_loads(p.radial_load_N, psi, p.gap_m, p.k_contact)
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
        iv = impact_intervals(run["fine_time_s"], q.max(axis=1), kin.bpfo_Hz)
        out["impact_interval_mean_s"] = float(iv.mean()) if len(iv) else float("nan")
        out["impact_interval_std_s"] = float(iv.std()) if len(iv) else float("nan")
        out["impact_frequency_Hz"] = float(1 / iv.mean()) if len(iv) else float("nan")
        out["n_impacts"] = int(len(iv) + 1)
    return out


# --------------------------------------------------------------------------- mesh convergence


def quasi_static_force(model: housing_fem.HousingModel, load_N: np.ndarray, angle_rad: np.ndarray) -> np.ndarray:
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


def convergence_row(level: float, n_dofs: int, quasi_static_N: np.ndarray, bpfo_Hz: float, dt_s: float) -> dict:
    """One level's row of the convergence table, from the quasi-static sensor force g(t) on its mesh [N]."""
    f = np.asarray(quasi_static_N, dtype=float)
    amp = harmonic_amplitudes(f, dt_s, bpfo_Hz, 3)
    return {
        "level": level,
        "n_dofs": n_dofs,
        "peak_to_peak_N": float(f.max() - f.min()),
        "mean_N": float(f.mean()),
        "bpfo_amplitude_N": float(amp[0]),
    }


def mesh_convergence(contact: dict, config: dict, known: dict | None = None) -> tuple[pd.DataFrame, dict]:
    """Sensor force amplitude (healthy, quasi-static) on the levels ``housing.convergence_levels``.

    The dynamic part of the sensor force is below 1e-3 of it (see
    transient_healthy.json), so the convergence of the quasi-static force
    measures the mesh's. One factorisation a level. ``known`` maps a level to
    (DOFs, quasi-static force [N]) computed already on the healthy mesh of that
    level (the rule housing_transient_healthy's, on ``housing.mesh_level``):
    that level is not built and factorised again. Returns the table (one
    row a level) and the record (levels, observed order, Richardson
    extrapolation of the peak-to-peak force [N], NaN where the changes are
    not monotone or the levels not in geometric progression).
    """
    h, b = config["housing"], config["bearing"]
    kin = kinematic_frequencies(BearingGeometry.from_config(b), b["shaft_speed_rpm"] / 60.0)
    geo = housing_geometry(config)
    rows = []
    for level in h["convergence_levels"]:
        t0 = time.perf_counter()
        if known and level in known:
            n_dofs, f = known[level]
        else:
            model = make_model(build_housing_mesh(geo, False, level), config)
            n_dofs, f = model.n_dofs, quasi_static_force(model, contact["load_N"], contact["angle_rad"])
            del model
        rows.append(convergence_row(level, n_dofs, f, kin.bpfo_Hz, b["time_step_s"]))
        log.info(
            "level %.2f: %d DOFs, peak-to-peak %.4f N, %.1f s (wall clock, not written to the results)%s",
            level, n_dofs, rows[-1]["peak_to_peak_N"], time.perf_counter() - t0,
            " (the housing_transient's)" if known and level in known else "",
        )
    df = pd.DataFrame(rows)
    ref = df["peak_to_peak_N"].iloc[-1]
    df["rel_change_to_finest"] = df["peak_to_peak_N"] / ref - 1
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
    record = {
        "levels": rows,
        "observed_order": order,
        "extrapolated_peak_to_peak_N": extrapolated,
        "default_level": h["mesh_level"],
    }
    return df, record


# --------------------------------------------------------------------------- the sampling phase: dt = 1/(36 BPFO)


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


def sampling_phase(
    contact: dict, angle_rad: np.ndarray, sensor_per_radial_load: np.ndarray, bearing: dict, seed: int = 0
) -> dict:
    """What the step 1/(36 BPFO) does to the sensor force of the faulty bearing.

    The quasi-static sensor force (the LPM's fine-grid loads ``contact`` times
    the influence line ``sensor_per_radial_load`` [N/N] at ``angle_rad``) is
    sampled at the paper's step with the sampling instants shifted by a
    fraction phi of a step (equivalently, a different starting roller angle),
    by point sampling and by step averaging; for each, the BPFO amplitude, the
    peak-to-peak and the share of variance off the BPFO harmonics; and the same
    at a step of 1/2500 s, not commensurate with the roller passage.
    """
    b = bearing
    p = lpm.LPMParameters.from_config(b, True, seed)
    kin = kinematic_frequencies(p.geometry, p.shaft_speed_Hz, p.cage_slip)
    tf = contact["fine_time_s"]
    psi = p.roller_angles(tf)
    order = np.argsort(angle_rad)
    gfun = np.interp(psi, angle_rad[order], sensor_per_radial_load[order], period=2 * np.pi)
    f_fine = np.sum(contact["fine_load_N"] * gfun, axis=1)
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
    return out
