"""A large calibration record: what the workflow's start, fit_resistance and diagnose cost.

Builds records of N rows by repeating the CI synthetic record (500 Hz, 6
presses per 12 s) on one continuous clock, then measures in fresh processes
(peak RSS from ``getrusage`` of the child, wall time):

- ``check``: the workflow's start-up check of a user record
  (``stages.calibration.check_record_once``), first start (parse and check)
  and second start (content hash only, result cached under results/.checked/);
- ``read``: ``io.read_measurement`` alone;
- ``fit_resistance``: the stage (read, checks, fit, fit.csv);
- ``diagnose``: the stage (whole catalogue), and the size of diagnosis.npz.

With ``--old-src DIR`` (the ``src`` folder of an older checkout) the
``diagnose`` rows run with both codes, side by side with their ratios
(``diagnose_old_vs_new``); ``--only-diagnose`` skips the other stages.

Usage: ``python benchmarks/bench_large_record.py [--rows 6000000 --diagnose-rows 180000]
[--old-src ../old/src --only-diagnose]``; writes results/benchmarks/large_record.json
(``large_record_diagnose.json`` with ``--only-diagnose``). Times depend on the machine's
load (``cpu_seconds``, with imports, depends less on it); memory does not.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

REPO = Path(__file__).resolve().parents[1]
CI_CONFIG = REPO / "config" / "ci.yaml"  # the checkout's reduced config: the record's rate and presses
OUT = REPO / "results" / "benchmarks" / "large_record.json"

CHILD = r"""
import json, sys, time
from pathlib import Path
from piezobearing import config
what, record, work, config_file = sys.argv[1], sys.argv[2], Path(sys.argv[3]), sys.argv[4]
c = config.load(config_file)
c["calibration"]["measurement"] = record
t0 = time.perf_counter()
extra = {}
if what == "check":
    from piezobearing.stages.calibration import check_record_once
    check_record_once(record, c, str(work / ".checked"))
elif what == "read":
    from piezobearing.io import read_measurement
    read_measurement(record)
elif what == "fit_resistance":
    from piezobearing.stages.calibration import fit_resistance
    fit_resistance(record, str(work / "resistance.json"), str(work / "fit.csv"), c)
elif what == "diagnose":
    from piezobearing.stages.diagnostics import diagnose
    diagnose(record, str(work / "diag"), c)
    extra["npz_MB"] = (work / "diag" / "diagnosis.npz").stat().st_size / 1e6
import resource
# VmHWM: this program's peak RSS (ru_maxrss would carry the parent's peak across fork and exec)
hwm = [l for l in Path("/proc/self/status").read_text().splitlines() if l.startswith("VmHWM:")]
peak = int(hwm[0].split()[1]) / 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
ru = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"seconds": time.perf_counter() - t0, "cpu_seconds": ru.ru_utime + ru.ru_stime,
                  "peak_rss_MB": peak, **extra}))
"""


def make_record(rows: int, path: Path) -> float:
    """A record of ``rows`` samples from the CI synthetic record repeated; its size [MB]."""
    from piezobearing import config
    from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
    from piezobearing.stages.calibration import nominal_circuit

    c = config.load(CI_CONFIG)
    m = synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"])
    n = m.time_s.size - 1
    reps = -(-rows // n)
    f = np.tile(m.force_N[:n], reps)[:rows]
    v = np.tile(m.voltage_V[:n], reps)[:rows]
    pd.DataFrame({"time_s": np.arange(rows) * m.dt_s, "force_N": f, "voltage_V": v}).to_csv(
        path, index=False, float_format="%.9g"
    )
    return path.stat().st_size / 1e6


def measure(what: str, record: Path, work: Path, src: str | None = None) -> dict:
    """One measurement in a fresh process; ``src``: import piezobearing from that folder instead."""
    env = dict(os.environ)
    if src:
        env["PYTHONPATH"] = os.pathsep.join([str(Path(src).resolve()), env.get("PYTHONPATH", "")])
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", CHILD, what, str(record), str(work), str(CI_CONFIG)],
        capture_output=True,
        text=True,
        check=True,
        env=env,
    )
    wall = time.perf_counter() - t0
    r = json.loads(out.stdout.strip().splitlines()[-1])
    r["process_seconds"] = wall  # with interpreter start and imports
    return r


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=6_000_000, help="rows of the large record (6 M: about 213 MB)")
    ap.add_argument("--diagnose-rows", type=int, nargs="*", default=[60_000, 180_000])
    ap.add_argument("--old-src", help="src folder of an older checkout: diagnose with both codes")
    ap.add_argument("--only-diagnose", action="store_true", help="measure diagnose only")
    args = ap.parse_args()
    result = {"rows": args.rows}
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        if not args.only_diagnose:
            big = d / "big.csv"
            result["record_MB"] = make_record(args.rows, big)
            # a fresh process per measurement, each reporting its own peak RSS
            result["read"] = measure("read", big, d)
            result["check_first_start"] = measure("check", big, d)
            result["check_second_start"] = measure("check", big, d)
            result["fit_resistance"] = measure("fit_resistance", big, d)
        result["diagnose"] = []
        for rows in args.diagnose_rows:
            rec = d / f"r{rows}.csv"
            row = {"rows": rows, "record_MB": make_record(rows, rec), **measure("diagnose", rec, d)}
            if args.old_src:
                old = measure("diagnose", rec, d, args.old_src)
                row["old"] = old
                row["old_over_new"] = {
                    k: old[k] / row[k] for k in ("peak_rss_MB", "npz_MB", "cpu_seconds") if row.get(k)
                }
            result["diagnose"].append(row)
    out = OUT.with_name("large_record_diagnose.json") if args.only_diagnose else OUT
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
