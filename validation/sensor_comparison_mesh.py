"""How the housing mesh moves the sensor comparison's answer: modes, effective mass, both sensors' margins.

For each housing mesh level (``--levels``; default the config's ``housing.convergence_levels`` and its
``housing.mesh_level``) builds the healthy and faulty housing models of the sensor comparison
(:func:`piezobearing.housing.reduced.build_housing`: modes to the cutoff, every mounting place) and
records the modes below the accelerometer DAQ's Nyquist frequency (the detector's band lies below it), the
cumulative effective mass there and at the cutoff; then runs the paper's case (the config's speed and defect)
through both sensors at every mounting place, the frame at rest and under the configured base motion
(:func:`piezobearing.comparison.rig.compare`, the config's seeds and record), and records each sensor's
margin, margin over the healthy rig and clean RMS. Everything but the mesh level is the config's.

    python validation/sensor_comparison_mesh.py --configfile config/ci.yaml --levels 0.35 0.5 0.7 1.0 \
        --resistance results/calibration/resistance.json --harmonic results/sensor/harmonic.csv \
        --out results/validation/sensor_comparison_mesh.json

``--duration``: another record length [s] (the mesh's effect against the record's). ``--resistance`` and
``--harmonic``: the workflow's resistance fit and sensor FEM response on that config
(run the workflow first); without ``--harmonic`` the sensor FEM's correction is off.
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from piezobearing import config as cfgmod
from piezobearing.chain import signals as sout
from piezobearing.comparison import rig as cmp
from piezobearing.housing import fem
from piezobearing.housing.reduced import build_housing
from piezobearing.io import read_harmonic, read_json


def housing_record(housing, band_top_Hz: float) -> dict:
    """The modes below ``band_top_Hz`` and the cumulative effective mass fraction there and at the cutoff."""
    f = housing.ops.omega / (2 * np.pi)
    frac = housing.base.effective_mass_fraction()
    below = int(np.searchsorted(f, band_top_Hz))
    return {
        "n_dofs": housing.n_dofs,
        "n_modes": int(f.size),
        "highest_mode_Hz": float(f[-1]),
        "modes_below_band_top_Hz": [float(v) for v in f[:below]],
        "effective_mass_fraction_below_band_top_yz": [float(frac[0, below - 1]), float(frac[1, below - 1])]
        if below else [0.0, 0.0],
        "effective_mass_fraction_at_cutoff_yz": [float(frac[0, -1]), float(frac[1, -1])],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configfile", default=None, help="merged over config/config.yaml (default: the paper's)")
    ap.add_argument("--levels", type=float, nargs="*", default=None)
    ap.add_argument("--positions", nargs="*", default=list(fem.MOUNTING_POSITIONS))
    ap.add_argument("--duration", type=float, default=None, help="record length [s] (default: bearing.duration_s)")
    ap.add_argument("--resistance", required=True)
    ap.add_argument("--harmonic", default=None)
    ap.add_argument("--out", default="results/validation/sensor_comparison_mesh.json")
    args = ap.parse_args()
    config = cfgmod.load(args.configfile) if args.configfile else cfgmod.load()
    h = config["housing"]
    levels = args.levels or sorted({*h["convergence_levels"], h["mesh_level"]})
    config["signals"]["sensor_fem_correction"] = args.harmonic is not None
    if args.duration is not None:
        config["bearing"]["duration_s"] = args.duration
    circuit = sout.sensor_circuit(config, read_json(args.resistance), args.resistance)
    harmonic = read_harmonic(args.harmonic) if args.harmonic else None
    band_top = 0.5 * config["accelerometer"]["daq"]["sample_rate_Hz"]
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    record = {"command": "python validation/sensor_comparison_mesh.py", "configfile": args.configfile,
              "levels": levels, "band_top_Hz": band_top, "n_seeds": config["sensor_comparison"]["n_seeds"],
              "duration_s": config["bearing"]["duration_s"], "meshes": []}
    for level in levels:
        cfg = copy.deepcopy(config)
        cfg["housing"]["mesh_level"] = level
        t0, c0 = time.perf_counter(), time.process_time()
        housings = {faulty: build_housing(cfg, faulty) for faulty in (False, True)}
        mesh = {"level": level, "housing_cpu_s": time.process_time() - c0, "housing_wall_s": time.perf_counter() - t0,
                **{case: housing_record(housings[case == "faulty"], band_top) for case in ("healthy", "faulty")},
                "cases": []}
        for position in args.positions:
            for base_level in (0.0, config["base_motion"]["level"]):
                c = copy.deepcopy(cfg)
                c["accelerometer"]["position"] = position
                c["base_motion"]["level"] = base_level
                res = cmp.compare(c, circuit, harmonic, housings)
                mesh["cases"].append({
                    "position": position, "base_motion_level": base_level,
                    "disturbance_rms_m_per_s2": res["disturbance_rms_m_per_s2"],
                    **{f"{s}_{k}": res["sensors"][s][k] for s in cmp.SENSORS
                       for k in ("margin_dB", "margin_over_healthy_dB", "detection_rate_over_healthy")},
                    **{f"{s}_clean_rms_V": res["sensors"][s]["levels"]["faulty"]["clean_rms_V"] for s in cmp.SENSORS},
                })
                print(level, mesh["cases"][-1], flush=True)
        record["meshes"].append(mesh)
        out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
