"""Run times of the search detector against today's exact-bin test on one record.

A 1 s record at 2550 Hz (the paper) and at 51.2 kHz: white noise plus a
slipped outer-race impulse train; the band 500-1250 Hz. Times: today's
``detection.analyse`` (whole periods, one bin per harmonic), the search
detector ``detector.analyse_record`` (three fault types, windows, computed
null distributions) with its null distributions cached (the usual case: one
record length per run) and cold (first record), and the DAQ's ``sample``
from 51.2 kHz to 10.24 kHz; the baseline detector ``baseline.detect`` (slip, roller-passage fit,
harmonic and fold tests) at 2550 Hz and 25.6 kHz with the fit to f_s and to Nyquist (CPU seconds: one BLAS
thread); the outer-race test alone (``baseline.harmonic_test``) at the free fit's fundamental (the method
until 2026-11-22) and with the healthy model's fundamental fitted over the slip window (since 2026-11-23),
CPU seconds and their ratio. Writes results/benchmarks/detector.json.
Usage: python benchmarks/bench_detector.py
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np

from piezobearing.signals import baseline as B
from piezobearing.signals import daq
from piezobearing.signals import detection as det
from piezobearing.signals import detector as D

KIN = {"shaft_Hz": 1000 / 60, "ftf_Hz": 0.5 * 1000 / 60 * (1 - 10 / 44)}
KIN.update(bpfo_Hz=11 * KIN["ftf_Hz"], bpfi_Hz=11 * (KIN["shaft_Hz"] - KIN["ftf_Hz"]),
           bsf_Hz=0.5 * 4.4 * KIN["shaft_Hz"] * (1 - (10 / 44) ** 2))


def timed(fn, repeat: int) -> float:
    t0 = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t0) / repeat


def main() -> None:
    rng = np.random.default_rng(1)
    env = det.EnvelopeSettings(band_rule="fixed", band_Hz=(500.0, 1250.0))
    st = D.DetectorSettings()
    out = {"cpu_count": os.cpu_count(), "record_s": 1.0}
    for fs in (2550.0, 25600.0, 51200.0):
        n = int(fs)
        t = np.arange(n) / fs
        x = rng.standard_normal(n) + 3.0 * (np.mod(t * 0.985 * KIN["bpfo_Hz"], 1.0) < 2.0 / fs)
        D.null_distribution.cache_clear()
        cold = timed(lambda x=x, fs=fs: D.analyse_record(x, 1 / fs, KIN, env, st), 1)
        out[f"{int(fs)}_Hz"] = {
            "exact_bin_s": timed(lambda x=x, fs=fs: det.analyse(x, 1 / fs, KIN["bpfo_Hz"], env,
                                                                det.IndicatorSettings()), 5),
            "search_cold_s": cold,
            "search_cached_s": timed(lambda x=x, fs=fs: D.analyse_record(x, 1 / fs, KIN, env, st), 5),
        }
        out[f"{int(fs)}_Hz"]["search_over_exact"] = (out[f"{int(fs)}_Hz"]["search_cached_s"]
                                                    / out[f"{int(fs)}_Hz"]["exact_bin_s"])
    for fs in (2550.0, 25600.0):
        n = int(fs)
        t = np.arange(n) / fs
        v = 96.0 * np.exp(10.0 * (np.cos(2 * np.pi * 0.985 * KIN["bpfo_Hz"] * t) - 1.0))
        x = v + 11.0 * rng.standard_normal(n)
        for folds in (1.0, 0.5):
            bs = B.BaselineSettings(alias_folds=folds)
            base = B.Baseline.from_record(v, 1 / fs, KIN, bs)
            c0 = time.process_time()
            B.detect(x, 1 / fs, KIN, base, bs)
            out[f"{int(fs)}_Hz"][f"baseline_cpu_s_alias_folds_{folds:g}"] = time.process_time() - c0
        f0, window = 0.985 * KIN["bpfo_Hz"], (0.97 * KIN["bpfo_Hz"], KIN["bpfo_Hz"])
        for name, rng_ in (("fixed_f", None), ("slip_window", window)):
            c0 = time.process_time()
            B.one_blas_thread(B.harmonic_test)(x, 1 / fs, f0, base, 11.0, 0.0, rng_)
            out[f"{int(fs)}_Hz"][f"outer_race_test_cpu_s_{name}"] = time.process_time() - c0
        r = out[f"{int(fs)}_Hz"]
        r["outer_race_test_slip_window_over_fixed_f"] = r["outer_race_test_cpu_s_slip_window"] / r[
            "outer_race_test_cpu_s_fixed_f"]
    x = rng.standard_normal(51200)
    out["daq_sample_51200_to_10240_s"] = timed(lambda: daq.sample(x, 1 / 51200.0, 10240.0), 5)
    path = Path("results/benchmarks/detector.json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
