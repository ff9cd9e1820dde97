"""How far a healthy bearing's residual reaches at a fault's lines: the measurement behind naming a fault from its lines.

Where the diagnosis selects no defect, it names a fault from the lines its final residual still holds
(:func:`piezobearing.diagnosis.bearing.answer.fault_evidence`). BPFO is also the roller passage's rate: a healthy
bearing whose operating point the search did not reach leaves lines there too. This script draws healthy records
far from the rig file's operating point and diagnoses each with the quasi-static search (``dynamic_rung: off``: the
rule is applied to the quasi-static final residual), and writes for each the carriers of every fault family
(:func:`~piezobearing.diagnosis.bearing.answer.carrier_levels`: the residual's line above the white floor and over
the fitted model's own line), of the final model and of the best healthy model the rule judges
(:func:`~piezobearing.diagnosis.bearing.answer.best_healthy`, where it was fitted), and the answer. The missed grooves (20-26 deg from the sensor, with and without 1.5 % slip, 2550 Hz and
25.6 kHz) are diagnosed the same way, so the rule's margin on both sides reads from one file.

Healthy draws (:func:`healthy_draw`): the paper's rig file (500 N, 20 um, 1000 rpm); the record at a load of
250-1000 N (log-uniform: x/÷ 2), a clearance of 0-60 um, cage slip 0-3 %, roller diameters scattered by a standard
deviation of 0-2 um; in odd draws a ``speed_rpm`` column and a speed of 600-1500 rpm, in even ones no column and a
speed within the fit's tolerance (+-2 %); 1 s at 2550 Hz (draws 0, 1 mod 4) or 25.6 kHz, 30 dB, LPM.

    python validation/bearing_fault_lines.py --draws 12 [--no-grooves] --out results/validation/bearing_fault_lines.json

(draws already in the output file are kept; ``--no-grooves`` leaves the grooves for a later run.)
"""

from __future__ import annotations

import argparse
import copy
import json
import shlex
import sys
from pathlib import Path

import numpy as np

from piezobearing import config as cfg
from piezobearing.diagnosis.bearing.answer import carrier_levels, fault_evidence
from piezobearing.diagnosis.bearing.lpm_records import lpm_record
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.stages.bearing_diagnosis import influence_from_config, read_influence

#: The grooves the quasi-static search misses (validation/bearing_diagnosis.py's names and values).
GROOVES = {
    "outer_race_defect_20deg": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35},
    "outer_race_defect_26deg": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45},
    "outer_race_defect+cage_slip": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35,
                                    "cage_slip_ratio": 0.015},
    "outer_race_defect_26deg+cage_slip": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.45,
                                          "cage_slip_ratio": 0.015},
}
FAMILIES = ("outer_race", "inner_race", "rolling_element")


def healthy_draw(rng: np.random.Generator, i: int, config: dict) -> tuple[dict, float, bool]:
    """A healthy record's hidden operating point far from the rig file's (see the module docstring): (hidden values
    in the catalogue's names, sample rate [Hz], whether the record has a speed_rpm column)."""
    z = int(config["bearing"]["n_rollers"])
    tach = bool(i % 2)
    hidden = {
        "radial_load_N": float(config["bearing"]["radial_load_N"] * np.exp(rng.uniform(-np.log(2.0), np.log(2.0)))),
        "radial_clearance_m": float(rng.uniform(0.0, 60e-6)),
        "cage_slip_ratio": float(rng.uniform(0.0, 0.03)),
        "speed_deviation_ratio": float(rng.uniform(-0.4, 0.5) if tach else rng.uniform(-0.02, 0.02)),
    }
    scatter = float(rng.uniform(0.0, 2e-6))
    for k, x in enumerate(scatter * rng.standard_normal(z)):
        if k:
            hidden[f"roller_{k}_offset_m"] = float(x)
    return hidden, (2550.0 if i % 4 < 2 else 25600.0), tach


def row(config: dict, influence, hidden: dict, rate: float, tach: bool, seed: int) -> dict:
    c = copy.deepcopy(config)
    c["bearing_diagnosis"]["dynamic_rung"] = "off"
    rec = lpm_record(c, influence, hidden, rate, 1.0, 30.0, seed, tachometer=tach)
    d, dj = SUBJECT.diagnose((rec, influence), c)
    return {"hidden": hidden, "sample_rate_Hz": rate, "tachometer": tach, "selected": dj["selected"],
            "verdict": dj["verdict"], "fault_type": dj["fault"]["type"], "fault_source": dj["fault"]["source"],
            "evidence": [e["type"] for e in fault_evidence(d)],
            "healthy_model": dj["fault"]["healthy_model"],
            "carriers": {k: carrier_levels(d, k) for k in FAMILIES},
            "healthy_carriers": ({k: carrier_levels(d, k, d._best_healthy) for k in FAMILIES}
                                 if getattr(d, "_best_healthy", None) is not None else None)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=24)
    ap.add_argument("--out", default="results/validation/bearing_fault_lines.json")
    ap.add_argument("--influence", default=None, help="influence_line_healthy.csv (default: solved from the config)")
    ap.add_argument("--seed", type=int, default=35)
    ap.add_argument("--no-grooves", action="store_true")
    ap.add_argument("--groove-rate", type=float, action="append", help="the grooves' sample rates [Hz] (default 2550 "
                    "and 25600)")
    ap.add_argument("--steps-per-period", type=int, default=None,
                    help="bearing_diagnosis.dynamic_steps_per_period, the dynamic rung's search step (default: the config's)")
    args = ap.parse_args()
    config = cfg.load()
    if args.steps_per_period:
        config["bearing_diagnosis"]["dynamic_steps_per_period"] = args.steps_per_period
    influence = read_influence(args.influence) if args.influence else influence_from_config(config)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    res = json.loads(out.read_text()) if out.exists() else {"healthy": [], "grooves": []}
    res["command"] = shlex.join(["python", *sys.argv])
    for i in range(len(res["healthy"]), args.draws):
        hidden, rate, tach = healthy_draw(np.random.default_rng([args.seed, i]), i, config)
        res["healthy"].append({"draw": i, **row(config, influence, hidden, rate, tach, i)})
        out.write_text(json.dumps(res, indent=1))
        r = res["healthy"][-1]
        print(f"healthy {i} {rate:.0f} Hz: {r['selected']} {r['fault_type']}/{r['fault_source']} {r['healthy_model']} "
              f"BPFO {[round(c['excess_dB'], 1) for c in r['carriers']['outer_race']]} dB, over model "
              f"{[round(c['over_model_dB'], 1) for c in r['carriers']['outer_race']]}", flush=True)
    done = {(g["case"], g["sample_rate_Hz"]) for g in res["grooves"]}
    for rate in ([] if args.no_grooves else args.groove_rate or [2550.0, 25600.0]):
        for name, hidden in GROOVES.items():
            if (name, rate) in done:
                continue
            res["grooves"].append({"case": name, **row(config, influence, hidden, rate, False, 26)})
            out.write_text(json.dumps(res, indent=1))
            r = res["grooves"][-1]
            print(f"{name} {rate:.0f} Hz: {r['selected']} {r['fault_type']}/{r['fault_source']} "
                  f"BPFO {[round(c['excess_dB'], 1) for c in r['carriers']['outer_race']]} dB, over model "
                  f"{[round(c['over_model_dB'], 1) for c in r['carriers']['outer_race']]}", flush=True)


if __name__ == "__main__":
    main()
