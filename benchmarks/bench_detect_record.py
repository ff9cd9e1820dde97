"""Time of fault detection on a 10 s, 12 kHz record: the envelope detector in-process (CPU) against the
search detector it replaces (``benchmarks/baselines/search_detector.py``) with the paper's full-length kurtogram, and the ``piezobearing detect`` command
(wall, a fresh process: imports, reading the .mat file, detection, report and figure).

The command's wall time depends on the machine's load; its CPU time (user + system of the child) is the
wall time on an idle machine. ``python benchmarks/bench_detect_record.py [DATA_DIR]`` (default ``../shared/data/cwru_fan_end``; without
it, the command's row is left out) writes results/benchmarks/detect_record.json.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from baselines import search_detector

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.signals.envelope import EnvelopeSettings

FS = 12_000.0
SECONDS = 10.0
REPEAT = 5


def record() -> tuple[np.ndarray, dict]:
    """A 10 s healthy-machine record with an outer-race impulse train, and the kinematics of an SKF 6205."""
    rng = np.random.default_rng(3)
    n = int(FS * SECONDS)
    shaft = 1797.0 / 60.0
    kin = RollingBearing.from_designation("SKF 6205").kinematics(shaft)
    t = np.arange(n) / FS
    x = rng.standard_normal(n) + sum(2.0 / k * np.cos(2 * np.pi * k * shaft * t) for k in range(1, 9))
    ring = np.exp(-np.arange(400) / FS / 1e-3) * np.sin(2 * np.pi * 3200.0 * np.arange(400) / FS)
    pulses = np.zeros(n)
    times = np.cumsum(rng.normal(1.0, 0.01, int(SECONDS * kin.bpfo_Hz) + 2) / kin.bpfo_Hz)
    pulses[(times[times < SECONDS] * FS).astype(int)] = 3.0
    return x + np.convolve(pulses, ring)[:n], kin.to_dict()


def cpu_seconds(run) -> float:
    run()  # caches (filter designs, null distributions) warm, as for the second record of a run
    start = time.process_time()
    for _ in range(REPEAT):
        run()
    return (time.process_time() - start) / REPEAT


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", nargs="?", default="../shared/data/cwru_fan_end",
                    help="a CWRU fan-end folder with fe03.mat and fe03.yaml: also time the command on it")
    args = ap.parse_args()
    x, kin = record()
    new = cpu_seconds(lambda: envelope_detector.detect(x, FS, kin, envelope_detector.Settings()))
    old_settings = search_detector.DetectorSettings()
    old_envelope = EnvelopeSettings(band_rule="kurtogram", min_bandwidth_Hz=300.0)
    old = cpu_seconds(lambda: search_detector.analyse_record(x, 1 / FS, kin, old_envelope, old_settings))
    out = {"record": f"{SECONDS:g} s at {FS:g} Hz", "repeat": REPEAT,
           "envelope_detector_cpu_s": new, "search_detector_full_length_kurtogram_cpu_s": old,
           "ratio_old_over_new": old / new, "target_cpu_s": 0.5}
    data = Path(args.data)
    if (data / "fe39.mat").exists():
        walls, cpus = [], []
        with tempfile.TemporaryDirectory() as tmp:
            for k in range(3):
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                start = time.perf_counter()
                subprocess.run([sys.executable, "-m", "piezobearing.cli", "detect", str(data / "fe03.mat"), "--config",
                                str(data / "fe03.yaml"), "--out", f"{tmp}/{k}"], check=True, capture_output=True)
                walls.append(time.perf_counter() - start)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        out["command_wall_s"] = walls
        out["command_cpu_s"] = cpus  # the wall time of an idle machine: one process, one thread mostly
        out["command_record"] = "fe03.mat (10.1 s at 12 kHz, three channels)"
        out["target_command_wall_s"] = 3.0
    path = Path("results/benchmarks/detect_record.json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
