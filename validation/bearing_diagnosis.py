"""The running-bearing diagnosis against records of the dynamic LPM: hide each catalogue effect, find it.

Each case hides catalogue values in a record of the 4-DOF LPM (:mod:`piezobearing.diagnosis.bearing.lpm_records`,
not the quasi-static surrogate the diagnosis fits), at 30 dB, and runs the diagnosis of ``diagnose-bearing`` on
it. The results file holds, per case: the hidden values, what the diagnosis selected, each hidden value's fitted
value and 95 % interval, the verdict, the fault's statement and the lines it left unexplained, the dynamic rung
(tried, accepted, the NRMSE ladder: baseline, quasi-static, with the shaft's dynamics, floor) with the fitted
damping against the LPM's, the diagnosis's CPU time, and the rate the
model was held at (a record faster than ``bearing_diagnosis.max_model_rate_Hz`` is averaged down by the
diagnosis itself). A markdown table goes beside it.

    python validation/bearing_diagnosis.py --out results/validation/bearing_diagnosis.json \
        [--influence results/bearing/influence_line_healthy.csv] [--rate 2550 --rate 25600] [--case NAME ...]
        [--duration S] [--record-out DIR] [--steps-per-period N] [--final-steps-per-period N]

The cases named ``rounded_*`` and ``fine_step_*`` hold the dynamic rung against another defect geometry: their
grooves have rounded edges (a fillet of :data:`EDGE_RADIUS_M`, ``bearing.defects[].edge_radius_m``; the
catalogue's defects, which the rung fits, have sharp ones), and every one of them is integrated at a step
:data:`FINE_STEP_FACTOR` times finer than the other records' (2.7 us, against the rung's final 48 steps a period
of the shaft's mode, 7.7 us). ``fine_step_outer_race_defect_20deg`` and ``_0deg`` keep sharp edges: they separate what the
step does from what the edges do. Their rows give, besides the width found, the hidden width at the surface and
the width of the sharp groove a roller sinks as deep into (:meth:`piezobearing.bearing.lpm.Defect.equivalent_sharp_width_m`).
``--group edges`` runs only these cases; ``--nearest`` then adds to each rounded row the width of the sharp groove
whose noiseless force is nearest the record's (:func:`nearest_sharp_width`), with no diagnosis.

``--group housing_mode`` runs the records seen through one housing mode inside the DAQ's band
(:data:`HOUSING_MODE_CASES`): the effect no rung of the diagnosis holds, where a groove must still be named and a
healthy bearing must not be.

``--group rig_dynamics`` runs the records of a shaft or pedestal other than the rig file's
(:data:`RIG_DYNAMICS_CASES`); ``--shaft-mass-scan off`` holds the shaft's mass at the rig file's (the dynamic
rung's scan of the mass left out).

``--steps-per-period`` and ``--final-steps-per-period``: the config's ``bearing_diagnosis.dynamic_steps_per_period``
(the dynamic rung's integration steps per period of the shaft's mode in its search) and
``dynamic_final_steps_per_period`` (in the selected dynamic model's final refit and intervals), to see what the
time step does to a fitted width (the same keys a ``--config`` file sets).
"""

from __future__ import annotations

import argparse
import copy
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

from piezobearing import config as cfg
from piezobearing.bearing.geometry import BearingGeometry
from piezobearing.bearing.lpm import Defect
from piezobearing.diagnosis.bearing.lpm_records import MAX_STEP_S, lpm_record, lpm_sensor_force
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.io import write_bearing_record
from piezobearing.stages.bearing_diagnosis import influence_from_config, read_influence

#: name -> (hidden catalogue values, the effects that carry them)
CASES = {
    "outer_race_defect": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.15}, ["outer_race_defect"]),
    "outer_race_defect_wide": ({"outer_defect_width_m": 1.2e-3, "outer_defect_angle_rad": -1.0}, ["outer_race_defect"]),
    "inner_race_defect": ({"inner_defect_width_m": 0.6e-3, "inner_defect_angle_rad": 0.7}, ["inner_race_defect"]),
    "rolling_element_defect": ({"roller_defect_width_m": 0.8e-3, "roller_defect_spin_rad": 1.0,
                                "roller_defect_index": 3.0}, ["rolling_element_defect"]),
    "radial_load": ({"radial_load_N": 800.0}, ["radial_load"]),
    "clearance": ({"radial_clearance_m": 35e-6}, ["clearance"]),
    "load_share": ({"load_share_ratio": 0.5}, ["load_share"]),
    "cage_slip": ({"cage_slip_ratio": 0.015}, ["cage_slip"]),
    "shaft_speed": ({"speed_deviation_ratio": -0.02}, ["shaft_speed"]),
    "roller_scatter": ({"roller_4_offset_m": 2e-6}, ["roller_scatter"]),
    "mains_pickup": ({"mains_frequency_Hz": 50.02, "mains_h1_cos_V": 3.0, "mains_h1_sin_V": 3.0}, ["mains_pickup"]),
    "outer_race_defect+cage_slip": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35,
                                     "cage_slip_ratio": 0.015}, ["outer_race_defect", "cage_slip"]),
    "outer_race_defect+clearance": ({"outer_defect_width_m": 0.9e-3, "outer_defect_angle_rad": 0.0,
                                     "radial_clearance_m": 40e-6}, ["outer_race_defect", "clearance"]),
    "outer_race_defect_20deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35},
                                ["outer_race_defect"]),
    "outer_race_defect_26deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45},
                                ["outer_race_defect"]),
    "outer_race_defect_26deg+cage_slip": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45,
                                           "cage_slip_ratio": 0.015}, ["outer_race_defect", "cage_slip"]),
    "healthy_1500rpm_tachometer": ({"speed_deviation_ratio": 0.5}, []),
    "outer_race_defect_ramp_tachometer": ({"outer_defect_width_m": 0.9e-3, "outer_defect_angle_rad": 0.0,
                                           "speed_deviation_ratio": -0.1, "speed_ramp_Hz_per_s": 100.0 / 60.0},
                                          ["outer_race_defect"]),
}
#: Fillet radius of the rounded-edge cases' grooves [m]: a quarter of the 0.6 mm width (the walls then 0.3 mm
#: apart), a chosen test geometry between the sharp edge and the fully rounded one (rho = w/2), not a measured spall.
EDGE_RADIUS_M = 0.15e-3
#: The rounded-edge and fine-step cases' LPM step is MAX_STEP_S / FINE_STEP_FACTOR (2.7 us).
FINE_STEP_FACTOR = 4
EDGE_CASES = {
    "rounded_outer_race_defect_0deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.0,
                                        "defect_edge_radius_m": EDGE_RADIUS_M}, ["outer_race_defect"]),
    "rounded_outer_race_defect_20deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35,
                                         "defect_edge_radius_m": EDGE_RADIUS_M}, ["outer_race_defect"]),
    "rounded_outer_race_defect_26deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45,
                                         "defect_edge_radius_m": EDGE_RADIUS_M}, ["outer_race_defect"]),
    "rounded_outer_race_defect_20deg+cage_slip": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35,
                                                   "cage_slip_ratio": 0.015, "defect_edge_radius_m": EDGE_RADIUS_M},
                                                  ["outer_race_defect", "cage_slip"]),
    "rounded_outer_race_defect_26deg+cage_slip": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45,
                                                   "cage_slip_ratio": 0.015, "defect_edge_radius_m": EDGE_RADIUS_M},
                                                  ["outer_race_defect", "cage_slip"]),
    "rounded_inner_race_defect": ({"inner_defect_width_m": 0.6e-3, "inner_defect_angle_rad": 0.7,
                                   "defect_edge_radius_m": EDGE_RADIUS_M}, ["inner_race_defect"]),
    "fine_step_outer_race_defect_20deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35},
                                          ["outer_race_defect"]),
    "fine_step_outer_race_defect_0deg": ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.0},
                                         ["outer_race_defect"]),
}
CASES.update(EDGE_CASES)
#: A housing mode inside the DAQ's band (record conditions ``housing_mode_Hz``, ``housing_mode_damping_ratio``:
#: :func:`~piezobearing.housing.one_mode.through_mode` on the LPM's force): 1.1 kHz at 2 % inside a 2550 Hz record's
#: band; the paper housing's first mode (2731 Hz at 1.16 %, results/bearing/housing_modes_healthy.json) inside a
#: 25.6 kHz record's. The cases ending ``_given`` give the diagnosis the record's mode in the rig file
#: (``bearing_diagnosis.housing_mode_Hz``, ``housing_mode_damping_ratio``: for the paper housing, what its FEM gives,
#: results/bearing/housing_modes_healthy.json), the others do not.
HOUSING_MODE_CASES = {
    f"housing_mode_{name}_{kind}{given}": ({**hidden, "housing_mode_Hz": f, "housing_mode_damping_ratio": zeta}, effects)
    for name, f, zeta, givens in (("1100Hz", 1100.0, 0.02, ("",)), ("2731Hz", 2731.0, 0.0116, ("", "_given")))
    for kind, (hidden, effects) in (
        ("outer_race_defect_0deg", ({"outer_defect_width_m": 0.9e-3, "outer_defect_angle_rad": 0.0},
                                    ["outer_race_defect"])),
        ("healthy", ({}, [])),
    )
    for given in givens
}
CASES.update(HOUSING_MODE_CASES)
#: A rig whose shaft or pedestal is not what its rig file says (the record's LPM with its own ``shaft_mass_kg`` or
#: ``pedestal_stiffness_N_per_m``, :data:`~piezobearing.diagnosis.bearing.lpm_records.RIG_DYNAMICS`; the rig file keeps
#: the paper config's 1 kg and 2e9 N/m): twice and half the shaft's mass (its mode at 1.8 and 3.7 kHz, 2.6 kHz in
#: the rig file) and half the pedestal's stiffness, each under a groove under the sensor, a groove 20 deg from it
#: (whose sensor force the shaft's ring dominates), an inner-race groove, and a healthy bearing.
RIG_DYNAMICS_CASES = {
    f"{rig}_{kind}": ({**hidden, **dyn}, effects)
    for rig, dyn in (("shaft_2kg", {"shaft_mass_kg": 2.0}), ("shaft_0.5kg", {"shaft_mass_kg": 0.5}),
                     ("pedestal_1e9", {"pedestal_stiffness_N_per_m": 1.0e9}))
    for kind, (hidden, effects) in (
        ("outer_race_defect_0deg", ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.0},
                                    ["outer_race_defect"])),
        ("outer_race_defect_20deg", ({"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35},
                                     ["outer_race_defect"])),
        ("inner_race_defect", ({"inner_defect_width_m": 0.6e-3, "inner_defect_angle_rad": 0.7},
                               ["inner_race_defect"])),
        ("healthy", ({}, [])),
    )
}
CASES.update(RIG_DYNAMICS_CASES)
#: Record conditions that are not catalogue parameters and are not fitted (kept out of a row's values).
CONDITIONS = ("defect_edge_radius_m", "housing_mode_Hz", "housing_mode_damping_ratio", "pedestal_stiffness_N_per_m")
#: The records' SNR [dB].
SNR_DB = 30.0
#: Cases whose record has a speed_rpm column (the tachometer): the speed the LPM ran at, 1500 rpm where the rig
#: file says 1000; a ramp from 900 rpm at 100 rpm/s (900 to 1000 rpm over a 1 s record, 1100 over 2 s).
TACHOMETER = ("healthy_1500rpm_tachometer", "outer_race_defect_ramp_tachometer")


def run_case(config: dict, influence, name: str, sample_rate_Hz: float, duration_s: float, seed: int,
             record_dir: Path | None = None) -> dict:
    hidden, effects = CASES[name]
    step = MAX_STEP_S / FINE_STEP_FACTOR if name in EDGE_CASES else MAX_STEP_S
    rec = lpm_record(config, influence, hidden, sample_rate_Hz, duration_s, SNR_DB, seed, tachometer=name in TACHOMETER,
                     max_step_s=step)
    if record_dir is not None:
        record_dir.mkdir(parents=True, exist_ok=True)
        write_bearing_record(rec, record_dir / f"{name}_{sample_rate_Hz:.0f}Hz.csv")
    if name.endswith("_given"):
        given = {k: hidden[k] for k in ("housing_mode_Hz", "housing_mode_damping_ratio")}
        config = {**config, "bearing_diagnosis": {**config["bearing_diagnosis"], **given}}
    c0 = time.process_time()
    d = SUBJECT.diagnose((rec, influence), config)[1]
    cpu = time.process_time() - c0
    final = d["final"]
    found = {}
    for k, v in hidden.items():
        if k in CONDITIONS:
            continue
        val = final["params"].get(k)
        ci = final["ci95"].get(k)
        inside = None if ci is None or ci[0] is None else bool(ci[0] <= v <= ci[1])
        iv = d["identifiability"].get("intervals", {}).get(k, {})
        found[k] = {"hidden": v, "found": val, "ci95": ci, "inside": inside, "ci_method": iv.get("method"),
                    "ci95_jacobian": iv.get("jacobian_ci"), "correlation_factor": iv.get("correlation_factor")}
    return {
        "case": name,
        "sample_rate_Hz": sample_rate_Hz,
        "duration_s": duration_s,
        "hidden_effects": effects,
        "selected": d["selected"],
        "verdict": d["verdict"],
        "fault_type": d["fault"]["type"],
        "values": found,
        "shaft_speed_Hz": {"found": final["params"].get("shaft_speed_Hz"), "ci95": final["ci95"].get("shaft_speed_Hz")},
        "fault_statement": d["fault"].get("statement"),
        "fault_source": d["fault"].get("source"),
        "unidentified": d["fault"].get("unidentified"),
        "dynamic_rung": {k: v for k, v in d["dynamic_rung"].items() if k != "evidence"},
        "damping": {"found": final["params"].get("bearing_damping_N_s_per_m"),
                    "ci95": final["ci95"].get("bearing_damping_N_s_per_m"),
                    "rig": config["bearing"]["bearing_damping_N_s_per_m"]},
        "housing_mode": {k: {"found": final["params"].get(k), "ci95": final["ci95"].get(k), "hidden": hidden.get(k)}
                         for k in ("housing_mode_Hz", "housing_mode_damping_ratio")},
        "cpu_s": cpu,
        "fault_sidebands": d["fault"].get("sidebands"),
        "model_rate": d["model_rate"],
        "nrmse": final["nrmse"],
        "noise_floor_nrmse": final["noise_floor_nrmse"],
        "unexplained": [u.get("where") for u in d["unexplained"]],
        "lpm_max_step_s": step,
        "geometry": geometry(config, hidden),
    }


def geometry(config: dict, hidden: dict) -> dict:
    """Per hidden groove: its edge radius, its width at the surface and the width of the sharp groove a roller
    sinks as deep into (what the sharp-edged catalogue can at best match by depth) [m]."""
    g = BearingGeometry.from_config(config["bearing"])
    rho = hidden.get("defect_edge_radius_m", 0.0)
    out = {}
    for key, race in (("outer_defect_width_m", "outer"), ("inner_defect_width_m", "inner")):
        if hidden.get(key, 0.0) > 0:
            d = Defect(0.0, hidden[key], 1.0e-3, f"{race}_race", edge_radius_m=rho)
            out[key] = {"edge_radius_m": rho, "surface_width_m": hidden[key],
                        "equivalent_sharp_width_m": d.equivalent_sharp_width_m(g.relative_radius_m(race)),
                        "max_drop_m": d.max_drop_m(g.relative_radius_m(race))}
    return out


def nearest_sharp_width(config: dict, influence, hidden: dict, sample_rate_Hz: float, duration_s: float,
                        step_s: float) -> dict:
    """The sharp groove whose noiseless sensor force is nearest (rms over the record) the rounded groove's, every
    other hidden value as in the record, both LPMs at ``step_s``: the width the sharp-edged catalogue can at best
    find from the record (9 widths from 4 um below the equivalent width to 2 um above the surface width, the
    least squares' parabola through the nearest three). Returns {key: {width_m, rms_N, noise_sigma_N}}."""
    out = {}
    t = np.arange(int(round(duration_s * sample_rate_Hz))) / sample_rate_Hz
    for key, geo in geometry(config, hidden).items():
        if not geo["edge_radius_m"]:
            continue
        ref = lpm_sensor_force(config, influence, hidden, t, step_s)
        sharp = {k: v for k, v in hidden.items() if k not in CONDITIONS}
        ws = np.linspace(geo["equivalent_sharp_width_m"] - 4e-6, geo["surface_width_m"] + 2e-6, 9)
        d2 = np.array([np.mean((ref - lpm_sensor_force(config, influence, {**sharp, key: w}, t, step_s)) ** 2)
                       for w in ws])
        k = int(np.clip(np.argmin(d2), 1, ws.size - 2))
        a, b, c = np.polyfit(ws[k - 1:k + 2], d2[k - 1:k + 2], 2)
        best = float(-b / (2 * a)) if a > 0 else float(ws[np.argmin(d2)])
        rms = float(np.sqrt(max(np.polyval([a, b, c], best), 0.0)))
        sigma = float(np.sqrt(np.mean((ref - ref.mean()) ** 2)) / 10 ** (SNR_DB / 20))
        out[key] = {"width_m": best, "rms_N": rms, "noise_sigma_N": sigma}
    return out


def edge_table(rows: list[dict]) -> str:
    """The rounded-edge and fine-step rows: verdict, angle, width against the surface and equivalent widths."""
    out = ["| case | rate [Hz] | edge radius [mm] | verdict | angle found [95 % interval] (hidden) [rad] | width found "
           "[95 % interval] [mm] | surface width (in?) | equivalent sharp width (in?) | nearest sharp width (in?) | "
           "NRMSE % (baseline / quasi-static / dynamic / floor) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        for key, geo in r["geometry"].items():
            v = r["values"][key]
            ang = r["values"].get(key.replace("width_m", "angle_rad"), {})
            aci = ang.get("ci95")
            a = (f"{ang['found']:.4f} [{aci[0]:.4f}, {aci[1]:.4f}] ({ang['hidden']:.2f})"
                 if ang.get("found") is not None and aci and aci[0] is not None
                 else f"not fitted ({ang.get('hidden', float('nan')):.2f})")
            ci = v["ci95"] if v["found"] is not None and v["ci95"] and v["ci95"][0] is not None else None
            w = f"{1e3 * v['found']:.4f} [{1e3 * ci[0]:.4f}, {1e3 * ci[1]:.4f}]" if ci else "not fitted"

            def held(x, ci=ci):
                return "-" if not ci else ("yes" if ci[0] <= x <= ci[1] else "no")
            n = (r.get("nearest_sharp") or {}).get(key)
            near = f"{1e3 * n['width_m']:.4f} ({held(n['width_m'])})" if n else "-"
            out.append(f"| {r['case']} | {r['sample_rate_Hz']:.0f} | {1e3 * geo['edge_radius_m']:.2f} | {r['verdict']} "
                       f"| {a} | {w} | {1e3 * geo['surface_width_m']:.4f} ({held(geo['surface_width_m'])}) "
                       f"| {1e3 * geo['equivalent_sharp_width_m']:.4f} ({held(geo['equivalent_sharp_width_m'])}) "
                       f"| {near} | {ladder(r)} |")
    return "\n".join(out)


def ladder(r: dict) -> str:
    """Baseline / quasi-static final / with the dynamics / floor NRMSE [%] (the dynamic rung's ladder where tried),
    with the housing mode's rung where tried: ... / with the dynamics / with the housing mode / floor."""
    rung = r.get("dynamic_rung") or {}
    lad = rung.get("ladder")
    if not lad:
        return f"{100 * r['nrmse']:.2f} / floor {100 * r['noise_floor_nrmse']:.2f}"
    hm = (rung.get("housing_mode") or {}).get("ladder")
    if hm:
        lad = [*lad[:3], {"nrmse": hm[2]["nrmse"], "model": "housing"}, hm[3]]
    return " / ".join(f"{100 * x['nrmse']:.2f}" + (" (+ housing mode)" if x["model"] == "housing" else "")
                      for x in lad)


def table(rows: list[dict]) -> str:
    out = ["| case | rate [Hz] (model) | hidden | found [95 % interval] | selected | verdict | NRMSE % (baseline / "
           "quasi-static / dynamic / floor) |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        hid = "; ".join(f"{k} {v['hidden']:.4g}" for k, v in r["values"].items())
        fnd = "; ".join(
            f"{v['found']:.4g} [{v['ci95'][0]:.4g}, {v['ci95'][1]:.4g}]" if v["found"] is not None and v["ci95"]
            else "not fitted" for v in r["values"].values()
        )
        out.append(f"| {r['case']} | {r['sample_rate_Hz']:.0f} ({r['model_rate']['model_rate_Hz']:.0f}) | {hid} | {fnd} | {', '.join(r['selected']) or 'none'} "
                   f"| {r['verdict']} | {ladder(r)} |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/validation/bearing_diagnosis.json")
    ap.add_argument("--config", default=None, help="YAML merged over config/config.yaml")
    ap.add_argument("--influence", default=None, help="influence_line_healthy.csv (default: solved from the config)")
    ap.add_argument("--rate", type=float, action="append", help="sample rates [Hz] (default 2550 and 25600)")
    ap.add_argument("--case", action="append", help=f"cases (default all): {', '.join(CASES)}")
    ap.add_argument("--nearest", action="store_true",
                    help="add to each rounded-edge row of --out the nearest sharp width (noiseless LPM forces; no "
                         "diagnosis)")
    ap.add_argument("--group", choices=["edges", "housing_mode", "rig_dynamics"], default=None,
                    help="edges: the rounded-edge and fine-step cases only (with their own table, .edges.md); "
                         "housing_mode: the records seen through a housing mode; rig_dynamics: records of a shaft "
                         "or pedestal other than the rig file's")
    ap.add_argument("--duration", type=float, default=1.0, help="record length [s]")
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--record-out", type=Path, default=None, help="folder to write each case's record to (CSV)")
    ap.add_argument("--shaft-mass-scan", choices=["auto", "off"], default=None,
                    help="bearing_diagnosis.shaft_mass_scan (default: the config's, auto)")
    ap.add_argument("--steps-per-period", type=int, default=None,
                    help="bearing_diagnosis.dynamic_steps_per_period (default: the config's)")
    ap.add_argument("--final-steps-per-period", type=int, default=None,
                    help="bearing_diagnosis.dynamic_final_steps_per_period (default: the config's)")
    args = ap.parse_args()
    config = cfg.load(*([args.config] if args.config else []))
    for key, value in (("shaft_mass_scan", args.shaft_mass_scan),
                       ("dynamic_steps_per_period", args.steps_per_period),
                       ("dynamic_final_steps_per_period", args.final_steps_per_period)):
        if value:
            config["bearing_diagnosis"][key] = value
    influence = read_influence(args.influence) if args.influence else influence_from_config(config)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows = json.loads(out.read_text())["cases"] if out.exists() else []
    if args.nearest:
        for r in rows:
            if r["case"] in EDGE_CASES and "nearest_sharp" not in r:
                r["nearest_sharp"] = nearest_sharp_width(config, influence, CASES[r["case"]][0], r["sample_rate_Hz"],
                                                         r["duration_s"], r["lpm_max_step_s"])
                print(r["case"], r["sample_rate_Hz"], r["nearest_sharp"], flush=True)
        out.write_text(json.dumps({**json.loads(out.read_text()), "cases": rows}, indent=1))
        out.with_suffix(".edges.md").write_text(edge_table([r for r in rows if r["case"] in EDGE_CASES]) + "\n")
        return
    done = {(r["case"], r["sample_rate_Hz"]) for r in rows}
    for rate in args.rate or [2550.0, 25600.0]:
        group = {"edges": EDGE_CASES, "housing_mode": HOUSING_MODE_CASES,
                 "rig_dynamics": RIG_DYNAMICS_CASES}.get(args.group, CASES)
        for name in args.case or list(group):
            if (name, rate) in done:
                continue
            c = copy.deepcopy(config)
            rows.append(run_case(c, influence, name, rate, args.duration, args.seed, args.record_out))
            out.write_text(json.dumps({"command": shlex.join(["python", *sys.argv]), "snr_dB": SNR_DB,
                                       "cases": rows}, indent=1))
            out.with_suffix(".md").write_text(table(rows) + "\n")
            edges = [r for r in rows if r["case"] in EDGE_CASES]
            if edges:
                out.with_suffix(".edges.md").write_text(edge_table(edges) + "\n")
            print(table(rows[-1:]).splitlines()[-1], flush=True)


if __name__ == "__main__":
    main()
