"""Mesh convergence and cost of one sensor design: the check that picks the sensor_design study's mesh.

For two designs (the paper's stack, and a thin wide hard disk, PZT-4 6 x 1 mm,
whose re-entrant corners and aspect ratio differ most from it), the figures of
merit of :func:`piezobearing.sensor.design.design_figures` at each mesh
multiplier, their error against the finest, and the wall time of one design.
Writes results/benchmarks/sensor_design.json.

    OMP_NUM_THREADS=1 python benchmarks/bench_sensor_design.py [--multipliers 0.5 0.75 1.0 1.5 2.0]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import time
from pathlib import Path

import piezobearing.config
from piezobearing.sensor import design as sensor_design
from piezobearing.sensor import fem
from piezobearing.sensor.mesh import stack_mesh
from piezobearing.stages.sensor_fem import SensorFemParams

KEYS = ("first_resonance_short_Hz", "first_resonance_open_Hz", "sensitivity_V_per_N", "band_high_Hz",
        "stack_stiffness_open_N_per_m")
DESIGNS = {
    "paper (APC 850, 4.7 x 3.4 mm)": {},
    "PZT-4, 6 x 1 mm": {"material": "pzt4", "pzt_diameter_m": 6.0e-3, "pzt_height_m": 1.0e-3},
}


def one_design(config: dict, multiplier: float) -> dict:
    p = SensorFemParams.from_config(config)
    st = sensor_design.DesignSettings(p.order, p.damping_ratio, p.n_ritz_modes, p.reference_frequency_Hz,
                                      p.band_ratio_dB, config["lowfreq"]["deviation_threshold"])
    t0 = time.perf_counter()
    mesh = stack_mesh(p.geometry, p.density, multiplier)
    out = sensor_design.design_figures(mesh, p.materials, fem.MeasuringCircuit(50e6, p.cable_capacitance_F), st)
    return {"multiplier": multiplier, "seconds": time.perf_counter() - t0, "n_dof": out["n_dof"],
            **{k: out[k] for k in KEYS}}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", nargs="*", default=[], help="override files merged over config/config.yaml")
    ap.add_argument("--multipliers", type=float, nargs="+", default=[0.5, 0.75, 1.0, 1.5, 2.0])
    ap.add_argument("--out", default="results/benchmarks/sensor_design.json")
    a = ap.parse_args()
    base = piezobearing.config.load(*a.config)
    one_design(base, a.multipliers[0])  # warm-up: imports and sfepy's first assembly
    result = {"threads": os.environ.get("OMP_NUM_THREADS", "unset"), "designs": {}}
    for name, over in DESIGNS.items():
        c = copy.deepcopy(base)
        c["sensor"].update(over)
        rows = [one_design(c, m) for m in a.multipliers]
        ref = rows[-1]
        for r in rows:
            r["error_percent_vs_finest"] = {k: 100 * (r[k] / ref[k] - 1) for k in KEYS}
            print(name, r["multiplier"], f"{r['seconds']:.1f} s", r["n_dof"],
                  {k: round(v, 3) for k, v in r["error_percent_vs_finest"].items()}, flush=True)
        result["designs"][name] = rows
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
