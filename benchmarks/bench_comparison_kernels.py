"""The sensor comparison's two inner kernels, the numpy form they had against the compiled one, on a realisation of
the comparison's rig (the config's ``sensor_comparison`` model step and bearing floor):

* heights: every raceway's and roller's roughness and waviness at each roller's contacts on the LPM's fine grid
  (:meth:`piezobearing.bearing.surface.Surfaces.heights_m`), against ``np.interp(period=)`` of the profile plus
  ``A cos(n theta + phi)`` array expressions (kept here as ``heights_numpy``);
* projection: the roller loads onto the housing's reduced operators
  (:func:`piezobearing.housing.fem.project_roller_loads`), against the chunked scatter into a dense (n_t,
  n_columns) column-load matrix and its products (kept here as ``project_numpy``).

Each is timed warm (the compiled kernels already compiled), best of ``--repeat`` runs of process CPU; the record
holds the ratio numpy / compiled and the largest difference relative to the largest value. The projection reads
the workflow's housing model of the config (rule sensor_comparison_housing): run the workflow first.

    python benchmarks/bench_comparison_kernels.py [--configfile config/config.yaml] [--repeat 3]

Writes results/benchmarks/comparison_kernels.json.
"""

from __future__ import annotations

import argparse
import glob
import json
import time
from pathlib import Path

import numpy as np

from piezobearing import config as config_loader
from piezobearing.bearing import lpm
from piezobearing.comparison import rig
from piezobearing.housing import fem, transient
from piezobearing.stages import housing_model

ROOT = Path(__file__).resolve().parents[1]


def heights_numpy(surfaces, psi: np.ndarray, shaft: np.ndarray, spin: np.ndarray) -> np.ndarray:
    """Surfaces.heights_m as array expressions: np.interp with the period, then each waviness order."""

    def track(tr, theta):
        h = np.zeros_like(theta)
        if tr.profile_m.size:
            n = tr.profile_m.size
            x = np.arange(n) * (tr.circumference_m / n)
            s = np.mod(theta, 2 * np.pi) * (tr.circumference_m / (2 * np.pi))
            h += np.interp(s, x, tr.profile_m, period=tr.circumference_m)
        for order, amp, phase in zip(tr.orders, tr.amplitudes_m, tr.phases_rad, strict=True):
            h += amp * np.cos(order * theta + phase)
        return h

    h = track(surfaces.outer, psi) + track(surfaces.inner, psi - shaft[:, None])
    for j, (ro, ri) in enumerate(zip(surfaces.roller_outer, surfaces.roller_inner, strict=True)):
        h[:, j] += track(ro, spin) + track(ri, spin + np.pi)
    return h


def project_numpy(columns, ops, load_N: np.ndarray, angle_rad: np.ndarray, chunk: int = 8192):
    """project_roller_loads as a scatter into dense column loads, chunk by chunk, and their matrix products."""
    nt, z = load_N.shape
    nc = columns.psi_rad.size
    half = columns.window()
    g, f = np.empty(nt), np.empty((nt, ops.omega.size))
    for k in range(0, nt, chunk):
        qk, pk = load_N[k:k + chunk], angle_rad[k:k + chunk]
        n = qk.shape[0]
        cols, w = columns.patch_window(pk, half)
        cols, w = cols.reshape(n, z, -1), w.reshape(n, z, -1)
        rows = np.arange(n)[:, None]
        fy, fz = qk * np.sin(pk), -qk * np.cos(pk)
        wy, wz = np.zeros((n, nc)), np.zeros((n, nc))
        for j in range(z):
            wy[rows, cols[:, j]] += fy[:, j, None] * w[:, j]
            wz[rows, cols[:, j]] += fz[:, j, None] * w[:, j]
        g[k:k + chunk] = wy @ ops.static_y + wz @ ops.static_z
        f[k:k + chunk] = wy @ ops.modal_y + wz @ ops.modal_z
    return g, f


def best_cpu(fn, repeat: int):
    """(best process CPU of ``repeat`` calls [s], the last result)."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return best, out


def relative_difference(a, b) -> float:
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--configfile", default=None, help="config merged over config/config.yaml")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "results/benchmarks/comparison_kernels.json"))
    args = ap.parse_args(argv)
    config = config_loader.load(*filter(None, [args.configfile]))
    cfg = rig.rig_config(config, rig.ComparisonSettings.from_config(config))
    b = cfg["bearing"]

    p = lpm.LPMParameters.from_config(b, False, cfg["seed"], 0)
    h = b["time_step_s"] / b["substeps"]
    t = -b["settle_s"] - b["time_step_s"] + h * np.arange(int(np.ceil((b["duration_s"] + b["settle_s"]) / h)) + 2)
    m = p.motion(t)
    p.surfaces.heights_m(m.psi_rad[:10], m.shaft_angle_rad[:10], m.spin_rad[:10])  # compile
    t_new, h_new = best_cpu(lambda: p.surfaces.heights_m(m.psi_rad, m.shaft_angle_rad, m.spin_rad), args.repeat)
    t_old, h_old = best_cpu(lambda: heights_numpy(p.surfaces, m.psi_rad, m.shaft_angle_rad, m.spin_rad), args.repeat)

    reads = housing_model.housing_reads(cfg)
    found = sorted(glob.glob(str(ROOT / "results/sensor_comparison/housing/healthy_*.npz")))
    housing = _first_housing(found, reads)
    if housing is None:
        raise SystemExit("no housing model of this config under results/sensor_comparison/housing: run "
                         "`snakemake --cores 2` (with this --configfile) first")
    run = transient.run_lpm(b, False, "compiled", cfg["seed"], realisation=0)
    q, psi = run["load_N"], run["angle_rad"]
    fem.project_roller_loads(housing.columns, housing.ops, q[:10], psi[:10])  # compile
    p_new, (g_new, f_new) = best_cpu(lambda: fem.project_roller_loads(housing.columns, housing.ops, q, psi),
                                     args.repeat)
    p_old, (g_old, f_old) = best_cpu(lambda: project_numpy(housing.columns, housing.ops, q, psi), args.repeat)

    record = {
        "what": "the sensor comparison's heights and projection kernels: numpy against compiled, CPU [s]",
        "command": "python benchmarks/bench_comparison_kernels.py" + (f" --configfile {args.configfile}"
                                                                      if args.configfile else ""),
        "repeat": args.repeat,
        "heights": {"points": int(m.psi_rad.size), "numpy_cpu_s": t_old, "compiled_cpu_s": t_new,
                    "numpy_over_compiled": t_old / t_new,
                    "relative_difference": relative_difference(h_new, h_old)},
        "projection": {"samples": int(q.shape[0]), "rollers": int(q.shape[1]),
                       "columns": int(housing.columns.psi_rad.size), "modes": int(housing.ops.omega.size),
                       "numpy_cpu_s": p_old, "compiled_cpu_s": p_new, "numpy_over_compiled": p_old / p_new,
                       "relative_difference_sensor": relative_difference(g_new, g_old),
                       "relative_difference_modal": relative_difference(f_new, f_old)},
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(record, indent=2) + "\n")
    print(json.dumps(record, indent=2))
    return 0


def _first_housing(paths: list[str], reads):
    """The first healthy housing model among ``paths`` made for this config (None: none is)."""
    for path in paths:
        try:
            return housing_model.load_housing(path, False, reads)
        except ValueError:  # another config's or mesh's
            continue
    return None


if __name__ == "__main__":
    raise SystemExit(main())
