"""The dynamic rung (``shaft_dynamics``): its error against the LPM, its cost, and the whole search with and without it.

``--accuracy``: records of 0.5 s at 2550 Hz of the paper's rig (its housing mesh's influence line), each
hidden case's box-averaged sensor force by
- the LPM integrated at a quarter of its records' step (2.7 us): the reference;
- the LPM at its records' step (10.9 us, :mod:`piezobearing.diagnosis.bearing.lpm_records`);
- the quasi-static chain (the rung's mass 0);
- the shaft's dynamics linearised about the quasi-static state (``baselines/linearised_shaft.py``, a numpy loop);
- the rung at 12, 16 (its setting), 24 and 48 steps per period of the shaft's mode;
as the rms of the difference from the reference over the reference's rms (means removed), and the CPU of one
evaluation of the rung's voltage for a 2 s record.

``--search``: the whole diagnosis (``piezobearing diagnose-bearing``'s, from record to JSON) of 2 s LPM records at
2550 Hz (and one at 25.6 kHz) with ``bearing_diagnosis.dynamic_rung: off`` (the method before the rung) and
``auto``, side by side: CPU time, verdict, selection, final and floor NRMSE.

``--cost --old-src DIR``: what the dynamic rung costs, a previous package (``DIR``, its ``src``: e.g.
``git archive main src config | tar -x -C DIR``) against this checkout, each in a fresh process with one BLAS
thread: the whole diagnosis of 2 s LPM records (:data:`COST`: the inner-race groove at 2550 Hz, the slowest search
of ``--search``; the 20 deg groove with 1.5 % slip at 2550 Hz and at 25.6 kHz), its CPU seconds and the rung's
(the console's ``dynamic rung: ... s CPU``), the verdict, the selection and the hidden width against its 95 %
interval; ratios old / new of the CPU.

Writes results/benchmarks/shaft_dynamics.json. Usage:
    python benchmarks/bench_shaft_dynamics.py [--accuracy] [--search] [--cost --old-src DIR] [--out FILE]
        [--case NAME ...]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from piezobearing import config as cfg
from piezobearing.bearing.lpm import line_contact_stiffness
from piezobearing.bearing.surrogate import Operating, OuterGroove, phase_edges
from piezobearing.diagnosis.bearing import chain, lpm_records
from piezobearing.diagnosis.bearing.subject import SUBJECT, rig_from_config
from piezobearing.stages.bearing_diagnosis import influence_from_config

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baselines import linearised_shaft  # noqa: E402

CASES = {
    "healthy": {},
    "outer 0.6 mm at 0.15 rad": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.15},
    "outer 0.6 mm at 0.35 rad": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35},
    "outer 0.6 mm at 0.35 rad, slip 1.5 %": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35,
                                             "cage_slip_ratio": 0.015},
    "outer 0.6 mm at 0.45 rad": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45},
    "inner 0.6 mm at 0.7 rad": {"inner_defect_width_m": 0.6e-3, "inner_defect_angle_rad": 0.7},
    "roller 0.8 mm": {"roller_defect_width_m": 0.8e-3, "roller_defect_spin_rad": 1.0, "roller_defect_index": 3.0},
    "outer 0.9 mm at 0, clearance 40 um": {"outer_defect_width_m": 0.9e-3, "outer_defect_angle_rad": 0.0,
                                           "radial_clearance_m": 40e-6},
}
SEARCH = ("healthy", "outer 0.6 mm at 0.15 rad", "outer 0.6 mm at 0.35 rad, slip 1.5 %", "inner 0.6 mm at 0.7 rad")


def values_of(config: dict, hidden: dict) -> dict:
    return {"start_phase_rad": float(np.radians(config["bearing_diagnosis"]["synthetic_start_phase_deg"])),
            "shaft_speed_Hz": config["bearing"]["shaft_speed_rpm"] / 60.0, **hidden}


def err(f: np.ndarray, ref: np.ndarray) -> float:
    r = ref - ref.mean()
    return float(np.sqrt(np.mean((f - f.mean() - r) ** 2) / np.mean(r**2)))


def linearised(rig, config, values: dict) -> np.ndarray:
    """The baseline's box-averaged sensor force on the rung's grid at 20 steps per period (its setting)."""
    dyn = chain.dynamics_of(rig, {**values, "shaft_mass_kg": config["bearing"]["shaft_mass_kg"]})
    op = Operating(values.get("radial_load_N", rig.radial_load_N), values.get("radial_clearance_m", rig.radial_clearance_m))
    t_ext = rig.time_s[0] + rig.dt_s * np.arange(-rig.n_pre, rig.n)
    phi = chain.cage_phase(t_ext, values["shaft_speed_Hz"], rig.geometry, 0.0, values.get("cage_slip_ratio", 0.0))
    phi = phi - phi[rig.n_pre] + values["start_phase_rad"]
    outer = None
    if values.get("outer_defect_width_m", 0.0) > 0:
        outer = OuterGroove(values["outer_defect_angle_rad"], values["outer_defect_width_m"], rig.geometry)
    rig20 = replace(rig, steps_per_period=20, cache={}, grid={})
    first, s, psi, drop, _, _ = chain.fine_grid(rig20, values, phase_edges(phi), op, outer, None, dyn)
    f = linearised_shaft.sensor_force(psi, drop, op.radial_load_N, op.radial_clearance_m,
                                      line_contact_stiffness(rig.geometry.roller_length_m), rig.influence, dyn,
                                      rig.dt_s / s)
    return f.reshape(-1, s).mean(axis=1)[-rig.n:]


def accuracy(config: dict, influence, names) -> dict:
    fs = 2550.0
    t = np.arange(int(0.5 * fs)) / fs
    t2 = np.arange(int(2.0 * fs)) / fs
    mass = config["bearing"]["shaft_mass_kg"]
    out = {}
    for name in names:
        hidden = CASES[name]
        ref = lpm_records.lpm_sensor_force(config, influence, hidden, t, lpm_records.MAX_STEP_S / 4)
        c0 = time.process_time()
        own = lpm_records.lpm_sensor_force(config, influence, hidden, t)
        cpu_lpm = time.process_time() - c0
        rig = rig_from_config(config, influence, t)
        values = values_of(config, hidden)
        qs = chain.sensor_force(rig, values)[0][rig.n_pre:]
        c0 = time.process_time()
        lin = linearised(rig, config, values)
        cpu_lin = time.process_time() - c0
        row = {"lpm_records_step": err(own, ref), "quasi_static": err(qs, ref), "linearised": err(lin, ref),
               "cpu_lpm_0.5s_s": cpu_lpm, "cpu_linearised_0.5s_numpy_s": cpu_lin}
        for steps in (12, 16, 24, 48):
            rs = replace(rig, steps_per_period=steps, cache={}, grid={})
            f = chain.sensor_force(rs, {**values, "shaft_mass_kg": mass})[0][rig.n_pre:]
            row[f"rung_{steps}_per_period"] = err(f, ref)
        rig2 = rig_from_config(config, influence, t2)
        chain.voltage(rig2, {**values, "shaft_mass_kg": mass})  # compile and tabulate
        c0 = time.process_time()
        for k in range(3):
            chain.voltage(rig2, {**values, "shaft_mass_kg": mass, "bearing_damping_N_s_per_m": 1000.0 + k})
        row["cpu_rung_voltage_2s_s"] = (time.process_time() - c0) / 3
        c0 = time.process_time()
        for k in range(3):
            chain.voltage(rig2, {**values, "dc_offset_V": 0.0, "radial_load_N": 500.0 + 1e-3 * (k + 1)})
        row["cpu_quasi_static_voltage_2s_s"] = (time.process_time() - c0) / 3
        out[name] = row
        print(f"{name}: " + ", ".join(f"{k} {v:.4g}" for k, v in row.items()), flush=True)
    return out


def search(config: dict, influence, names, rates=(2550.0,)) -> dict:
    out = {}
    for rate in rates:
        for name in names:
            rec = lpm_records.lpm_record(config, influence, CASES[name], rate, 2.0, 30.0, 26)
            for mode in ("off", "auto"):
                c = copy.deepcopy(config)
                c["bearing_diagnosis"]["dynamic_rung"] = mode
                c0 = time.process_time()
                d = SUBJECT.diagnose((rec, influence), c)[1]
                cpu = time.process_time() - c0
                row = {"cpu_s": cpu, "verdict": d["verdict"], "selected": d["selected"], "fault": d["fault"]["type"],
                       "fault_source": d["fault"]["source"], "nrmse": d["final"]["nrmse"],
                       "floor_nrmse": d["final"]["noise_floor_nrmse"], "rung_tried": d["dynamic_rung"]["tried"],
                       "rung_accepted": d["dynamic_rung"]["accepted"]}
                out[f"{name} @ {rate:.0f} Hz, dynamic_rung {mode}"] = row
                print(f"{name} @ {rate:.0f} Hz, {mode}: " + ", ".join(f"{k} {v}" for k, v in row.items()), flush=True)
    return out


#: The records of ``--cost``: (case, sample rate [Hz]).
COST = (("inner 0.6 mm at 0.7 rad", 2550.0), ("outer 0.6 mm at 0.35 rad, slip 1.5 %", 2550.0),
        ("outer 0.6 mm at 0.35 rad, slip 1.5 %", 25600.0))


def cost_worker(name: str, rate: float) -> dict:
    """One ``--cost`` record diagnosed by whichever package this process imports (printed as JSON)."""
    config = cfg.load()
    influence = influence_from_config(config)
    hidden = CASES[name]
    rec = lpm_records.lpm_record(config, influence, hidden, rate, 2.0, 30.0, 26)
    notes = []
    c0 = time.process_time()
    d = SUBJECT.diagnose((rec, influence), copy.deepcopy(config), notes.append)[1]
    cpu = time.process_time() - c0
    rung = [float(m.split()[2]) for m in notes if m.startswith("dynamic rung: ") and m.endswith(")") and " s CPU" in m]
    key = next(k for k in hidden if k.endswith("width_m"))
    ci = d["final"]["ci95"].get(key)
    return {"cpu_s": cpu, "rung_cpu_s": rung[-1] if rung else 0.0, "verdict": d["verdict"],
            "selected": d["selected"], "width_m": d["final"]["params"].get(key), "width_ci95_m": ci,
            "hidden_width_m": hidden[key], "inside": None if not ci or ci[0] is None else bool(ci[0] <= hidden[key] <= ci[1]),
            "rung_accepted": d["dynamic_rung"]["accepted"]}


def cost(old_src: Path) -> dict:
    """:data:`COST` by the package in ``old_src`` and by this checkout's, each record in a fresh process."""
    here = Path(__file__).resolve()
    out = {}
    for name, rate in COST:
        row = {}
        for side, src in (("old", Path(old_src).resolve()), ("new", here.parents[1] / "src")):
            env = {**os.environ, "PYTHONPATH": str(src), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                   "MKL_NUM_THREADS": "1"}
            p = subprocess.run([sys.executable, str(here), "--cost-worker", name, str(rate)], env=env,
                               capture_output=True, text=True, check=True)
            row[side] = json.loads(p.stdout.strip().splitlines()[-1])
        row["cpu_ratio_old_over_new"] = row["old"]["cpu_s"] / row["new"]["cpu_s"]
        row["rung_cpu_ratio_old_over_new"] = row["old"]["rung_cpu_s"] / max(row["new"]["rung_cpu_s"], 1e-9)
        out[f"{name} @ {rate:.0f} Hz"] = row
        print(f"{name} @ {rate:.0f} Hz: " + json.dumps(row), flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--accuracy", action="store_true")
    ap.add_argument("--search", action="store_true")
    ap.add_argument("--case", action="append", help="cases (default all): " + ", ".join(CASES).replace("%", "%%"))
    ap.add_argument("--out", default="results/benchmarks/shaft_dynamics.json")
    ap.add_argument("--cost", action="store_true")
    ap.add_argument("--old-src", type=Path, default=None, help="the previous package's src folder (--cost)")
    ap.add_argument("--cost-worker", nargs=2, metavar=("CASE", "RATE"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.cost_worker:
        print(json.dumps(cost_worker(args.cost_worker[0], float(args.cost_worker[1]))))
        return
    config = cfg.load()
    influence = influence_from_config(config)
    out_path = Path(args.out)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out = json.loads(out_path.read_text()) if out_path.exists() else {}
    out["cpu_count"] = os.cpu_count()
    if args.accuracy:
        out["accuracy"] = accuracy(config, influence, args.case or list(CASES))
        out_path.write_text(json.dumps(out, indent=1))
    if args.search:
        res = search(config, influence, args.case or SEARCH)
        res.update(search(config, influence, ["outer 0.6 mm at 0.35 rad, slip 1.5 %"], (25600.0,)))
        out["search"] = res
        out_path.write_text(json.dumps(out, indent=1))
    if args.cost:
        if args.old_src is None:
            ap.error("--cost needs --old-src DIR (the previous package's src)")
        out["cost"] = {"old_src": str(args.old_src), "records_s": 2.0, "cost": cost(args.old_src)}
        out_path.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
