"""The running-bearing diagnosis across a rig's plausible range: every record ends with a verdict.

Draws a rig file and a record's hidden truth (:func:`piezobearing.diagnosis.bearing.lpm_records.draw_conditions`:
the file's load 100-2000 N and clearance 0-60 um; the record's load within x/÷ 1.5 of it, clearance 0-60 um,
slip 0-3 %, speed -3..+3 %, roller scatter 0-2 um, a groove 0.1-1.2 mm at any angle on any race or a roller in
two draws of three), makes the record with the dynamic LPM (0.5 s at 2550 Hz, 30 dB) and diagnoses it (the
first ranking: ``diagnostics.max_steps`` 1). Writes each draw's conditions, verdict and selection, the fault's
type and source, whether the dynamic rung was tried and accepted, and the diagnosis's CPU time, or its error, and
the count of crashes.

    python validation/bearing_feasibility.py --draws 40 --out results/validation/bearing_feasibility.json \
        [--influence results/bearing/influence_line_healthy.csv]

With ``--envelope-only`` it makes the same records and runs the envelope detector of ``piezobearing detect``
(:mod:`piezobearing.signals.detectors.envelope`, its default settings, the record's rig-file speed) on each instead
of the diagnosis: whether the record itself shows a fault family above the detector's threshold (each family's
call and margin over its threshold).
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from piezobearing import config as cfg
from piezobearing.bearing.geometry import BearingGeometry, kinematic_frequencies
from piezobearing.diagnosis.bearing.lpm_records import draw_conditions, lpm_record
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.stages.bearing_diagnosis import influence_from_config, read_influence


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=40)
    ap.add_argument("--out", default="results/validation/bearing_feasibility.json")
    ap.add_argument("--influence", default=None, help="influence_line_healthy.csv (default: solved from the config)")
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--envelope-only", action="store_true",
                    help="run the envelope detector on each record instead of the diagnosis")
    args = ap.parse_args()
    config = cfg.load()
    config["diagnostics"]["max_steps"] = 1
    influence = read_influence(args.influence) if args.influence else influence_from_config(config)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows = []
    for i in range(args.draws):
        rig, hidden = draw_conditions(np.random.default_rng([args.seed, i]), copy.deepcopy(config))
        row = {"draw": i, "rig_radial_load_N": rig["bearing"]["radial_load_N"],
               "rig_radial_clearance_m": rig["bearing"]["radial_clearance_m"], "hidden": hidden}
        try:
            rec = lpm_record(rig, influence, hidden, 2550.0, 0.5, 30.0, i)
            if args.envelope_only:
                shaft_Hz = rig["bearing"]["shaft_speed_rpm"] / 60.0
                kin = kinematic_frequencies(BearingGeometry.from_config(rig["bearing"]), shaft_Hz).to_dict()
                e = envelope_detector.detect(rec.voltage_V, rec.sample_rate_Hz, kin, envelope_detector.Settings())
                row.update(verdict=e.fault_type, envelope={
                    "fault_type": e.fault_type,
                    "margin_dB": {t: f.margin_dB for t, f in e.families.items()},
                    "detected": {t: f.detected for t, f in e.families.items()}})
                rows.append(row)
                out.write_text(json.dumps({"command": "python validation/bearing_feasibility.py --envelope-only",
                                           "draws": len(rows), "rows": rows}, indent=1))
                print(f"draw {i}: envelope detector {e.fault_type}", flush=True)
                continue
            c0 = time.process_time()
            d = SUBJECT.diagnose((rec, influence), rig)[1]
            rung = d.get("dynamic_rung") or {}
            row.update(verdict=d["verdict"], selected=d["selected"], fault_type=d["fault"]["type"],
                       fault_source=d["fault"].get("source"), cpu_s=time.process_time() - c0,
                       dynamic_rung={"tried": rung.get("tried"), "accepted": rung.get("accepted")})
        except Exception as e:  # noqa: BLE001 - what this script counts
            row.update(verdict=None, error=f"{type(e).__name__}: {e}")
        rows.append(row)
        crashes = sum(r["verdict"] is None for r in rows)
        out.write_text(json.dumps({"command": "python validation/bearing_feasibility.py", "draws": len(rows),
                                   "crashes": crashes, "rows": rows}, indent=1))
        print(f"draw {i}: {row.get('verdict')} {row.get('selected', row.get('error'))}", flush=True)


if __name__ == "__main__":
    main()
