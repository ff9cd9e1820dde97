"""The housing's reduced model at a DAQ rate where it is not quasi-static: modes against the direct solve.

At the paper's 2550 Hz (Nyquist 1275 Hz) the housing's first mode (near
2.9 kHz) lies above the band and the sensor force is nearly quasi-static. A
DAQ at 51.2 kHz (Nyquist 25.6 kHz) sees the housing ring: the reduced
method (modes by shift-invert Lanczos plus static correction) must carry
every mode the loads excite below the Nyquist frequency. This runs the
faulty bearing (the defect's impacts are broadband) at a model step of
1/rate, and compares the reduced sensor force for several ``n_modes``
with sfepy's direct generalized-alpha solve of the full system over the
same record: the error of the force's variation and each run's time.

Writes results/benchmarks/housing_rate.json. Usage:
python benchmarks/bench_housing_rate.py [--ci] [--rate HZ] [--duration S] [--modes 12 24 40]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

import piezobearing.config
from piezobearing.housing import fem as housing_fem
from piezobearing.housing import transient
from piezobearing.housing.mesh import build_housing_mesh

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="use config/ci.yaml (coarse mesh)")
    ap.add_argument("--rate", type=float, default=51200.0, help="DAQ rate = 1 / model step [Hz]")
    ap.add_argument("--duration", type=float, default=0.02, help="record length [s]")
    ap.add_argument("--modes", type=int, nargs="+", default=[12, 24, 40, 60])
    ap.add_argument("--out", default="results/benchmarks/housing_rate.json")
    args = ap.parse_args()
    config = piezobearing.config.load(CONFIG / "ci.yaml") if args.ci else piezobearing.config.load()
    b, h = config["bearing"], config["housing"]
    dt = 1.0 / args.rate
    b.update(time_step_s=dt, duration_s=args.duration, substeps=max(1, int(round(dt / 10e-6))))
    out: dict = {"cpu_count": os.cpu_count(), "config": "ci" if args.ci else "paper", "rate_Hz": args.rate,
                 "nyquist_Hz": 0.5 * args.rate, "duration_s": args.duration, "mesh_level": h["mesh_level"]}
    t0 = time.perf_counter()
    run = transient.run_lpm(b, faulty=True)
    out["lpm_s"] = time.perf_counter() - t0
    mesh = build_housing_mesh(transient.housing_geometry(config), True, h["mesh_level"])
    model = transient.make_model(mesh, config)
    out["n_dofs"] = model.n_dofs
    wy, wz = model.column_loads(run["load_N"], run["angle_rad"])
    out["n_steps"] = len(run["time_s"])
    alpha, beta = housing_fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])
    t0 = time.perf_counter()
    d = housing_fem.sensor_force_direct(model, wy, wz, dt, alpha, beta, h["rho_inf"])
    out["direct_s"] = time.perf_counter() - t0
    ref = d["force_N"]
    out["sensor_force_peak_to_peak_N"] = float(np.ptp(ref))
    model.factor()
    runs = []
    for n in args.modes:
        t0 = time.perf_counter()
        modes = housing_fem.compute_modes(model, n, seed=config["seed"])
        red = housing_fem.sensor_force_reduced(housing_fem.reduced_operators(model, modes, alpha, beta), wy, wz, dt)
        sec = time.perf_counter() - t0
        diff = ref - red["force_N"]
        f = modes.frequencies_Hz
        runs.append({"n_modes": n, "highest_mode_Hz": float(f.max()), "modes_below_nyquist": int(np.sum(f < 0.5 / dt)),
                     "reduced_s": sec,
                     "rms_rel_diff_of_variation": float(np.sqrt(np.mean(diff**2)) / np.std(ref)),
                     "max_abs_diff_N": float(np.abs(diff).max())})
        print(runs[-1], flush=True)
    out["reduced"] = runs
    path = Path(args.out)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
