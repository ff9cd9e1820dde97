"""Direct against reduced solution of the housing's transient FEM, healthy bearing, paper case.

Both methods solve the same sfepy-assembled half model under the same roller
loads (the LPM's, averaged over each FEM step) for the whole record:

* direct: sfepy's generalized-alpha stepper on the full system (one
  factorisation of the effective matrix, one back-substitution a step);
* reduced: factorisation of K, the lowest modes by shift-invert Lanczos, the
  influence line and the modal operators, and the exact modal recurrence.

Each time includes everything the method needs after assembly. Also times
the factorisation of K with the nested-dissection numbering used by the
model against SuperLU's own orderings on the same matrix.

Writes results/benchmarks/housing.json (direct_s, reduced_s, speedup,
rms_rel_diff, ...). Usage: python benchmarks/bench_housing.py [--ci] [--duration S]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

import piezobearing.config
from piezobearing.housing import fem as housing_fem
from piezobearing.housing import transient
from piezobearing.housing.mesh import build_housing_mesh

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="use config/ci.yaml (coarse mesh, short record)")
    ap.add_argument("--duration", type=float, default=None, help="record length [s] (default: the config's)")
    ap.add_argument("--out", default="results/benchmarks/housing.json")
    args = ap.parse_args()
    config = piezobearing.config.load(CONFIG / "ci.yaml") if args.ci else piezobearing.config.load()
    if args.duration is not None:
        config["bearing"]["duration_s"] = args.duration
    b, h = config["bearing"], config["housing"]
    dt = b["time_step_s"]
    out: dict = {
        "cpu_count": os.cpu_count(),
        "omp_num_threads": os.environ.get("OMP_NUM_THREADS"),
        "config": "ci" if args.ci else "paper",
        "mesh_level": h["mesh_level"],
        "n_modes": h["n_modes"],
    }

    t0 = time.perf_counter()
    run = transient.run_lpm(b, faulty=False)
    out["lpm_s"] = time.perf_counter() - t0
    mesh = build_housing_mesh(transient.housing_geometry(config), False, h["mesh_level"])
    t0 = time.perf_counter()
    model = transient.make_model(mesh, config)
    out["assemble_s"] = time.perf_counter() - t0
    out["n_dofs"] = model.n_dofs
    wy, wz = model.column_loads(run["load_N"], run["angle_rad"])
    out["n_steps"] = len(run["time_s"])
    alpha, beta = housing_fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])

    t0 = time.perf_counter()
    model.factor()
    modes = housing_fem.compute_modes(model, h["n_modes"], seed=config["seed"])
    red = housing_fem.sensor_force_reduced(housing_fem.reduced_operators(model, modes, alpha, beta), wy, wz, dt)
    out["reduced_s"] = time.perf_counter() - t0

    d = housing_fem.sensor_force_direct(model, wy, wz, dt, alpha, beta, h["rho_inf"])
    out["direct_s"] = d["seconds"]
    out["speedup"] = out["direct_s"] / out["reduced_s"]
    diff = d["force_N"] - red["force_N"]
    out["rms_rel_diff"] = float(np.sqrt(np.mean(diff**2)) / np.sqrt(np.mean(red["force_N"] ** 2)))
    out["rms_rel_diff_of_variation"] = float(np.sqrt(np.mean(diff**2)) / np.std(red["force_N"]))
    out["max_abs_diff_N"] = float(np.abs(diff).max())
    out["sensor_force_peak_to_peak_N"] = float(np.ptp(red["force_N"]))

    # the factorisation of K: nested-dissection numbering against SuperLU's orderings
    orderings = {}
    for name, spec in (
        ("nested_dissection", "NATURAL"),
        ("mmd_at_plus_a", "MMD_AT_PLUS_A"),
        ("colamd", "COLAMD"),
    ):
        kk = model.K
        t0 = time.perf_counter()
        lu = spla.splu(kk, permc_spec=spec, diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        orderings[name] = {"seconds": time.perf_counter() - t0, "factor_nnz": int(lu.L.nnz + lu.U.nnz)}
        del lu
    out["factorisation"] = orderings

    path = Path(args.out)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
