"""Sparse solvers and the batched SNR sweep against the methods they replace, in one run each, as ratios.

* housing: factorisation of K (wall and CPU seconds) and the influence line (one solve) at each mesh level
  of the convergence study, and the shift-invert modes, with SuperLU in the model's nested-dissection
  numbering (the previous method) and with PARDISO (MKL); the relative difference of the influence
  line and of the natural frequencies between the two; the process's peak memory after each level (the
  finest level, 151 k DOF on the paper config, holds the peak: SuperLU's factors);
* sensor: the SS family's saddle factorisation and its short-circuit modes on the default mesh;
* snr_study: the sweep of one record (the paper's healthy stand-in) over the study's SNR grid and
  seeds, record by record (method='loop', the previous method) against batched over SNRs.

Writes results/benchmarks/solvers.json (a run of some parts keeps the others of an earlier run on the same
config). Usage: python benchmarks/bench_solvers.py [--ci] [--only housing,sensor,snr] [--max-level 1.0]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from pathlib import Path

import numpy as np

import piezobearing.config
from piezobearing.numerics import sparse_solve

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)


def factor_entries(lu) -> int:
    """Entries of a factorisation: ``factor_nnz`` of :func:`piezobearing.numerics.sparse_solve.factorize`'s
    factors; SciPy's ``SuperLU`` (the housing's :func:`~piezobearing.housing.fem.splu_symmetric`) has none, and
    its entries are those of L and U."""
    if hasattr(lu, "factor_nnz"):
        return int(lu.factor_nnz)
    return int(lu.L.nnz + lu.U.nnz)


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _timed_cpu(fn):
    """``fn()``, its wall seconds and the CPU seconds of this process's threads meanwhile (PARDISO's threads
    counted together; unlike the wall seconds, unmoved by other processes on a shared machine)."""
    c0, t0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def peak_rss_MB() -> float:
    """This process's peak resident memory so far [MB]."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_housing(config: dict, max_level: float) -> dict:
    from piezobearing.housing import fem as housing_fem
    from piezobearing.housing import transient
    from piezobearing.housing.mesh import build_housing_mesh

    h = config["housing"]
    out = {}
    for level in [lv for lv in h["convergence_levels"] if lv <= max_level]:
        mesh = build_housing_mesh(transient.housing_geometry(config), False, level)
        model = transient.make_model(mesh, config)
        row = {"n_dofs": model.n_dofs}
        lines = {}
        for solver in ("superlu", "pardiso"):
            model.solver, model._lu = solver, None
            lu, secs, cpu = _timed_cpu(model.factor)
            (gy, gz, radial), solve_s = _timed(model.influence_line)
            row[solver] = {"factor_s": secs, "factor_cpu_s": cpu, "influence_line_s": solve_s,
                           "factor_nnz": factor_entries(lu)}
            if level == h["mesh_level"]:
                modes, row[solver]["modes_s"] = _timed(
                    lambda mdl=model: housing_fem.compute_modes(mdl, h["n_modes"], config["seed"])
                )
                lines[solver + "_freq"] = modes.frequencies_Hz
            lines[solver] = radial
            model._lu = lu = None
        row["speedup_factor_and_line"] = (row["superlu"]["factor_s"] + row["superlu"]["influence_line_s"]) / (
            row["pardiso"]["factor_s"] + row["pardiso"]["influence_line_s"]
        )
        row["influence_line_max_rel_diff"] = float(
            np.abs(lines["pardiso"] - lines["superlu"]).max() / np.abs(lines["superlu"]).max()
        )
        if "pardiso_freq" in lines:
            row["speedup_modes"] = row["superlu"]["modes_s"] / row["pardiso"]["modes_s"]
            row["natural_frequency_max_rel_diff"] = float(
                np.max(np.abs(lines["pardiso_freq"] / lines["superlu_freq"] - 1))
            )
        row["peak_rss_MB"] = peak_rss_MB()  # the process's peak so far: this level's where it is the largest
        out[f"level_{level}"] = row
        print(json.dumps({f"level_{level}": row}), flush=True)
        del model
    return out


def bench_sensor(config: dict) -> dict:
    from piezobearing.sensor import analysis as sensor_analysis
    from piezobearing.sensor import fem
    from piezobearing.sensor.mesh import stack_mesh

    p = sensor_analysis.SensorFemParams.from_config(config)
    asm = sensor_analysis._assemble(stack_mesh(p.geometry, p.density, p.multiplier), p)
    out = {"n_dof_displacement": int(asm.n_u)}
    freqs = {}
    for solver in ("superlu", "pardiso"):
        rs = fem.reduce(asm, fem.stack_conditions(p.geometry.z_interfaces_m, "SS"), solver=solver)
        lu, fs = _timed(lambda rs=rs: rs._saddle_lu)
        m, ms = _timed(lambda rs=rs: fem.modes(rs, p.n_ritz_modes, "short"))
        out[solver] = {"factor_s": fs, "modes_s": ms, "factor_nnz": factor_entries(lu)}
        freqs[solver] = m.frequency_Hz
        del rs, lu
    out["speedup"] = (out["superlu"]["factor_s"] + out["superlu"]["modes_s"]) / (
        out["pardiso"]["factor_s"] + out["pardiso"]["modes_s"]
    )
    out["frequency_max_rel_diff"] = float(np.max(np.abs(freqs["pardiso"] / freqs["superlu"] - 1)))
    print(json.dumps({"sensor": out}), flush=True)
    return out


def bench_snr(config: dict) -> dict:
    from piezobearing.signals import detection
    from piezobearing.signals.analysis import snr_grid
    from piezobearing.signals.envelope import EnvelopeSettings

    s = config["signals"]
    fs = 2550.0
    dt, f0 = 1 / fs, fs / 36
    n = int(round(config["bearing"]["duration_s"] * fs))
    t = dt * np.arange(n)
    # a roller-passage stand-in: a smooth bump per passage plus a two-sample impulse (the faulty case)
    ph = (t * f0) % 1.0
    v = 0.2 * np.exp(-0.5 * ((ph - 0.4) / 0.1) ** 2)
    v[np.flatnonzero(np.diff(np.floor(t * f0 - 0.3)) > 0) + 1] -= 0.05
    grid = snr_grid(s)
    out = {"n_samples": n, "n_snr": len(grid), "n_seeds": s["study_n_seeds"]}
    ins = detection.IndicatorSettings.from_config(s)
    for rule in ("fixed", "kurtogram"):
        es = EnvelopeSettings.from_config(dict(s, band_rule=rule))
        res = {}
        for method in ("loop", "batch"):
            rows, res[method] = _timed(
                lambda m=method, e=es: detection.snr_sweep(v, dt, f0, "faulty", grid, s["study_n_seeds"], 7, e, ins, method=m)
            )
            res[method + "_rows"] = rows
        out[rule] = {
            "loop_s": res["loop"],
            "batch_s": res["batch"],
            "speedup": res["loop"] / res["batch"],
            "rows_identical": res["loop_rows"] == res["batch_rows"],
        }
        print(json.dumps({rule: out[rule]}), flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="use config/ci.yaml")
    ap.add_argument("--only", default="housing,sensor,snr")
    ap.add_argument("--out", default="results/benchmarks/solvers.json")
    ap.add_argument(
        "--max-level", type=float, default=10.0, help="skip housing levels above this (SuperLU needs 7.4 GB at 2.0)"
    )
    args = ap.parse_args()
    config = piezobearing.config.load(CONFIG / "ci.yaml") if args.ci else piezobearing.config.load()
    path = Path(args.out)
    # a run of some parts (--only) keeps the other parts of an earlier run of the same config
    kept = json.loads(path.read_text()) if path.exists() else {}
    kept = {k: kept[k] for k in ("snr_study", "sensor", "housing") if k in kept} if kept.get("config") == (
        "ci" if args.ci else "paper") else {}
    out = {
        "cpu_count": os.cpu_count(),
        "load_average_at_start": os.getloadavg()[0],
        "config": "ci" if args.ci else "paper",
        "pardiso_available": sparse_solve.pardiso_available(),
    }
    parts = args.only.split(",")
    if "snr" in parts:
        out["snr_study"] = bench_snr(config)
    if "sensor" in parts:
        out["sensor"] = bench_sensor(config)
    if "housing" in parts:
        out["housing"] = bench_housing(config, args.max_level)
    out["load_average_at_end"] = os.getloadavg()[0]
    out.update({k: v for k, v in kept.items() if k not in out})
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
