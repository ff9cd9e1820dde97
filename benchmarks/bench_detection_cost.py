"""The envelope detector's CPU per record, a previous revision (``--old REV``) beside this checkout, against its targets.

Two records, each a healthy machine (white noise, the first 8 shaft harmonics) with an outer-race impulse train
ringing a 3.2 kHz resonance, SKF 6205 at 1797 rpm: 10 s at 12 kHz (target: at most 0.2 s of CPU) and 3 s at
48.8 kHz (target: at most 1 s). Each side runs in a fresh process of its own (``PYTHONPATH`` its ``src``, one
thread): the detection's CPU seconds on the process's first record (every cache cold: the filter designs, the
null distributions) and the median of ``--repeat`` further calls (warm, as for the second record of a batch),
the start-up (imports, reading a file) not included. The calls of both sides are compared.

Writes ``results/benchmarks/detection_cost.json``: per record each side's cold and warm CPU seconds, the ratios
old / new, and new / target. Usage::

    python benchmarks/bench_detection_cost.py [--old main] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_workflow import export_revision  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: The records: (rate [Hz], length [s], target CPU [s]).
RECORDS = ((12_000.0, 10.0, 0.2), (48_800.0, 3.0, 1.0))

WORKER = r'''
import json, statistics, sys, time
import numpy as np
from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.signals.detectors import envelope as envelope_detector

fs, seconds, repeat = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(3)
n = int(fs * seconds)
shaft = 1797.0 / 60.0
kin = RollingBearing.from_designation("SKF 6205").kinematics(shaft)
t = np.arange(n) / fs
x = rng.standard_normal(n) + sum(2.0 / k * np.cos(2 * np.pi * k * shaft * t) for k in range(1, 9))
ring_n = int(fs * 0.004)
ring = np.exp(-np.arange(ring_n) / fs / 1e-3) * np.sin(2 * np.pi * 3200.0 * np.arange(ring_n) / fs)
pulses = np.zeros(n)
times = np.cumsum(rng.normal(1.0, 0.01, int(seconds * kin.bpfo_Hz) + 2) / kin.bpfo_Hz)
pulses[(times[times < seconds] * fs).astype(int)] = 3.0
x = x + np.convolve(pulses, ring)[:n]
settings = envelope_detector.Settings()
start = time.process_time()
d = envelope_detector.detect(x, fs, kin.to_dict(), settings)
cold = time.process_time() - start
warm = []
for _ in range(repeat):
    start = time.process_time()
    envelope_detector.detect(x, fs, kin.to_dict(), settings)
    warm.append(time.process_time() - start)
print(json.dumps({"cold_cpu_s": cold, "warm_cpu_s": statistics.median(warm), "call": d.fault_type,
                  "margin_dB": d.margin_dB}))
'''


def run_side(src: Path, fs: float, seconds: float, repeat: int) -> dict:
    """One side's measurement in a fresh single-threaded process with ``src`` first on the path."""
    env = {**os.environ, "PYTHONPATH": str(src), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", WORKER, str(fs), str(seconds), str(repeat)], env=env, check=True,
                         capture_output=True, text=True, cwd=src.parent)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="main", help="git revision of the old side (default: main)")
    ap.add_argument("--repeat", type=int, default=5, help="warm calls per side and record (their median)")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        old_src = export_revision(args.old, Path(tmp) / "old") / "src"
        for fs, seconds, target in RECORDS:
            old = run_side(old_src, fs, seconds, args.repeat)
            new = run_side(ROOT / "src", fs, seconds, args.repeat)
            row = {"record": f"{seconds:g} s at {fs:g} Hz", "target_cpu_s": target, "old": old, "new": new,
                   "ratio_old_over_new_cold": old["cold_cpu_s"] / new["cold_cpu_s"],
                   "ratio_old_over_new_warm": old["warm_cpu_s"] / new["warm_cpu_s"],
                   "new_cold_over_target": new["cold_cpu_s"] / target,
                   "same_call": old["call"] == new["call"]}
            rows.append(row)
            print(f"{row['record']}: old {old['cold_cpu_s']:.3f} s cold, {old['warm_cpu_s']:.3f} s warm; new "
                  f"{new['cold_cpu_s']:.3f} s cold, {new['warm_cpu_s']:.3f} s warm (target {target:g} s); "
                  f"calls {old['call']} / {new['call']}", flush=True)
    out = {"old": args.old, "repeat": args.repeat, "threads": 1, "records": rows}
    path = ROOT / "results/benchmarks/detection_cost.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
