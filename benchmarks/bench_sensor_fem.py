"""Benchmark of the sensor FEM: the modal and harmonic stages on the default mesh.

Runs the two stage computations (as the workflow does, each assembling and
factorizing on its own) for the config's mesh level, plus the coarsest level,
and the accuracy of the harmonic reduction against direct solves on the
coarsest mesh. Writes results/benchmarks/sensor_fem.json.

    OMP_NUM_THREADS=1 python benchmarks/bench_sensor_fem.py [--config config/ci.yaml]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from pathlib import Path

import numpy as np

from piezobearing import config
from piezobearing.sensor import fem
from piezobearing.sensor.analysis import SensorFemParams, harmonic_results, modal_results
from piezobearing.sensor.calibration import SensorCircuit
from piezobearing.sensor.mesh import stack_mesh

BUDGET_S = 120.0  # the budget for modal + harmonic on the default mesh (2 cores)


def time_stages(p: SensorFemParams, multiplier: float) -> dict:
    mesh = stack_mesh(p.geometry, p.density, multiplier)
    t0 = time.perf_counter()
    modal, _ = modal_results(mesh, p)
    t1 = time.perf_counter()
    _, band = harmonic_results(mesh, p, SensorCircuit(resistance_ohm=50e6), 30.0)
    t2 = time.perf_counter()
    return {
        "multiplier": multiplier,
        "n_cells": mesh.n_cells,
        "n_dof_displacement": modal["mesh"]["n_dof_displacement"],
        "n_dof_potential": modal["mesh"]["n_dof_potential"],
        "modal_s": t1 - t0,
        "harmonic_s": t2 - t1,
        "total_s": t2 - t0,
        "first_axial_short_Hz": modal["first_resonance_short_Hz"],
        "band_high_Hz": band["band_high_Hz"],
    }


def reduction_error(p: SensorFemParams) -> dict:
    """Largest relative error of the reduced harmonic model against direct complex solves (coarsest mesh)."""
    mesh = stack_mesh(p.geometry, p.density, p.multipliers[0])
    rs = fem.reduce(fem.assemble(mesh, p.materials, p.order), fem.stack_conditions(p.geometry.z_interfaces_m))
    model = fem.reduced_model(rs, fem.modes(rs, p.n_ritz_modes, "short"), 0.0)
    circ = fem.MeasuringCircuit(50e6, p.cable_capacitance_F)
    freqs = [1.0, 30.0, 1e3, 3e4, 6e4, 1e5, 1.3e5]
    t0 = time.perf_counter()
    direct = np.array([fem.direct_voltage_per_force(rs, f, circ) for f in freqs])
    t_direct = (time.perf_counter() - t0) / len(freqs)
    t0 = time.perf_counter()
    reduced = model.voltage_per_force(np.array(freqs), circ)
    t_red = (time.perf_counter() - t0) / len(freqs)
    # both circuits (measuring, open) per frequency: one factorisation each (old) against one for both (new)
    c0 = time.process_time()
    per_circuit = np.array([[fem.direct_voltage_per_force(rs, f, c) for c in (circ, None)] for f in freqs])
    c1 = time.process_time()
    per_frequency = np.array([fem.direct_voltages_per_force(rs, f, [circ, None]) for f in freqs])
    c2 = time.process_time()
    return {
        "frequencies_Hz": freqs,
        "max_rel_error": float(np.abs(reduced / direct - 1).max()),
        "direct_complex_solve_s_per_frequency": t_direct,
        "reduced_s_per_frequency": t_red,
        "direct_two_circuits_cpu_s_old_one_factorisation_per_circuit": c1 - c0,
        "direct_two_circuits_cpu_s_new_one_factorisation_per_frequency": c2 - c1,
        "direct_two_circuits_new_over_old": (c2 - c1) / (c1 - c0),
        "direct_two_circuits_max_rel_difference": float(np.abs(per_frequency / per_circuit - 1).max()),
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default=None, help="override file merged over config/config.yaml")
    ap.add_argument("--out", default="results/benchmarks/sensor_fem.json")
    args = ap.parse_args()
    c = config.load(*([args.config] if args.config else []))
    p = SensorFemParams.from_config(c)
    default = time_stages(p, p.multiplier)
    coarse = time_stages(p, p.multipliers[0])
    out = {
        "default_mesh": default,
        "coarsest_mesh": coarse,
        "budget_s": BUDGET_S,
        "default_total_over_budget": default["total_s"] / BUDGET_S,
        "reduction": reduction_error(p),
        "peak_rss_GB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
        "omp_num_threads": os.environ.get("OMP_NUM_THREADS"),
        "cpu_count": os.cpu_count(),
        "config": args.config or "config/config.yaml",
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
