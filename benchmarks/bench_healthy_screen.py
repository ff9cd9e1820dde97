"""The dynamic healthy model (the lines rule's best healthy model with the shaft's dynamics) with the screen's start
added to the grid's two best points (:func:`piezobearing.diagnosis.bearing.healthy.dynamic_healthy`) against the fits
from the grid's two best points alone, the method before (``baselines/healthy_grid_starts.py``), on the healthy
records of ``validation/bearing_fault_lines.py`` whose lines rule fits it (1 s at 30 dB of the dynamic LPM, the paper
rig; draw 3, 256 N in 48 um at 25.6 kHz, is the record the screen's size was chosen on).

For each record the quasi-static diagnosis runs once (``dynamic_rung: off``) and its quasi-static best healthy model is
the start of both methods: each method's CPU seconds (one core), NRMSE and the floor's, and the ratio old / new of
the CPU.

Writes results/benchmarks/healthy_screen.json. Usage:
    python benchmarks/bench_healthy_screen.py [--draws 2 3 4 6 8] [--out FILE]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np
from baselines import healthy_grid_starts

from piezobearing import config as cfg
from piezobearing.diagnosis.bearing import answer, healthy
from piezobearing.diagnosis.bearing.lpm_records import lpm_record
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.stages.bearing_diagnosis import influence_from_config

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "validation"))
from bearing_fault_lines import healthy_draw  # noqa: E402


def one(config: dict, influence, i: int) -> dict:
    """Draw ``i``: both methods from the same quasi-static best healthy model."""
    hidden, rate, tach = healthy_draw(np.random.default_rng([35, i]), i, config)
    c = copy.deepcopy(config)
    c["bearing_diagnosis"]["dynamic_rung"] = "off"
    rec = lpm_record(c, influence, hidden, rate, 1.0, 30.0, i, tachometer=tach)
    caught = {}

    def catch(d, qs):  # the diagnosis's own call: keep (d, qs), fit nothing
        caught.update(d=d, qs=qs)
        return qs

    with mock.patch.object(answer, "dynamic_healthy", catch):
        SUBJECT.diagnose((rec, influence), c)
    row = {"draw": i, "sample_rate_Hz": rate}
    if not caught:
        return {**row, "fitted": False}
    d, qs = caught["d"], caught["qs"]
    row.update(fitted=True, quasi_static_nrmse=qs.nrmse, floor_nrmse=qs.floor_nrmse)
    for name, method in (("old", healthy_grid_starts.dynamic_healthy), ("new", healthy.dynamic_healthy)):
        t = time.process_time()
        f = method(d, qs)
        row[name] = {"cpu_s": time.process_time() - t, "nrmse": f.nrmse, "chi2": f.chi2,
                     "radial_clearance_um": 1e6 * f.values["radial_clearance_m"],
                     "radial_load_N": f.values["radial_load_N"]}
    row["cpu_ratio_old_over_new"] = row["old"]["cpu_s"] / row["new"]["cpu_s"]
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, nargs="+", default=[2, 3, 4, 6, 8],
                    help="healthy draws of validation/bearing_fault_lines.py (default: those whose lines rule fits "
                         "the dynamic healthy model)")
    ap.add_argument("--out", default="results/benchmarks/healthy_screen.json")
    args = ap.parse_args()
    config = cfg.load()
    influence = influence_from_config(config)
    rows = []
    for i in args.draws:
        rows.append(one(config, influence, i))
        r = rows[-1]
        if r["fitted"]:
            print(f"draw {i}: old {r['old']['cpu_s']:.0f} s, NRMSE {100 * r['old']['nrmse']:.2f} %; new "
                  f"{r['new']['cpu_s']:.0f} s, {100 * r['new']['nrmse']:.2f} % (floor {100 * r['floor_nrmse']:.2f} %)",
                  flush=True)
        else:
            print(f"draw {i}: the dynamic healthy model is not fitted", flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"cpu_count": os.cpu_count(), "command": "python benchmarks/bench_healthy_screen.py",
                               "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
