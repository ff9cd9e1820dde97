"""The quasi-static surrogate (load distribution x influence line) against the full chain (LPM + housing FEM).

For the healthy and the faulty bearing of the config: the full chain is the
workflow's (the LPM integrated on dt/36 with the shaft's and pedestal's
inertia, its loads averaged over each step, the housing's reduced modal
model with static correction on the case's own mesh); the surrogate is
:mod:`piezobearing.bearing.surrogate` with the same mesh's influence line.
Reports the difference as a share of the full chain's standard deviation
and its largest value, and the time of each. Also times one surrogate
record of 2 s at 2550 Hz and at 25.6 kHz (table built, then looked up).

Writes results/benchmarks/surrogate.json. Usage: python benchmarks/bench_surrogate.py [--ci]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from piezobearing import config as cfg
from piezobearing.bearing import surrogate as sg
from piezobearing.bearing.geometry import BearingGeometry
from piezobearing.housing import fem
from piezobearing.housing import transient as st
from piezobearing.housing.mesh import build_housing_mesh

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="use config/ci.yaml (coarse mesh, short record)")
    ap.add_argument("--out", default="results/benchmarks/surrogate.json")
    args = ap.parse_args()
    config = cfg.load(CONFIG / "ci.yaml") if args.ci else cfg.load()
    b, h = config["bearing"], config["housing"]
    dt = b["time_step_s"]
    geo = BearingGeometry.from_config(b)
    op = sg.Operating(b["radial_load_N"], b["radial_clearance_m"])
    out: dict = {"cpu_count": os.cpu_count(), "config": "ci" if args.ci else "paper", "cases": {}}
    for case in ("healthy", "faulty"):
        faulty = case == "faulty"
        t0 = time.perf_counter()
        run = st.run_lpm(b, faulty)
        t_lpm = time.perf_counter() - t0
        mesh = build_housing_mesh(st.housing_geometry(config), faulty, h["mesh_level"])
        model = st.make_model(mesh, config)
        t0 = time.perf_counter()
        modes = fem.compute_modes(model, h["n_modes"], seed=config["seed"])
        alpha, beta = fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])
        ops = fem.reduced_operators(model, modes, alpha, beta)
        wy, wz = model.column_loads(run["load_N"], run["angle_rad"])
        full = fem.sensor_force_reduced(ops, wy, wz, dt)["force_N"]
        t_housing = time.perf_counter() - t0
        _, _, radial = model.influence_line()
        infl = sg.InfluenceLine(mesh.raceway_psi, radial)
        p = run["params"]
        drop, key = None, None
        if faulty:
            (d,) = p.defects  # the LPM's groove on the concave outer raceway
            drop, key = (lambda psi, d=d: sg.outer_race_drop(psi, d.angle_rad, d.width_m, geo)), d
        t0 = time.perf_counter()
        s = sg.Surrogate(geo, infl)
        ph = sg.cage_phase(run["time_s"], p.shaft_speed_Hz, geo, p.start_angle_rad)
        sur = s.box_average(sg.phase_edges(ph), op, drop, key)
        t_sur = time.perf_counter() - t0
        diff = sur - full
        out["cases"][case] = {
            "n_samples": int(full.size),
            "full_std_N": float(np.std(full)),
            "full_mean_N": float(np.mean(full)),
            "surrogate_mean_N": float(np.mean(sur)),
            "rms_diff_N": float(np.sqrt(np.mean(diff**2))),
            "rms_diff_of_std": float(np.sqrt(np.mean(diff**2)) / np.std(full)),
            "ac_diff_of_std": float(np.std(diff) / np.std(full)),
            "max_abs_diff_N": float(np.abs(diff).max()),
            "first_mode_Hz": float(modes.frequencies_Hz[0]),
            "full_lpm_s": t_lpm,
            "full_housing_s": t_housing,
            "surrogate_s": t_sur,
        }
        print(case, json.dumps(out["cases"][case]))
    s = sg.Surrogate(geo, infl)
    for fs in (2550.0, 25600.0):
        t = np.arange(int(2 * fs)) / fs
        t0 = time.perf_counter()
        s._cache.clear()
        s.box_average(sg.phase_edges(sg.cage_phase(t, 1000 / 60, geo, 0.1)), op, drop, key)
        out[f"record_2s_{int(fs)}Hz_s"] = time.perf_counter() - t0
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps({k: v for k, v in out.items() if k != "cases"}))


if __name__ == "__main__":
    main()
