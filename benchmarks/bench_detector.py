"""Run times of the search detector against the paper's exact-bin test on one record.

A 1 s record at 2550 Hz (the paper) and at 51.2 kHz: white noise plus a
slipped outer-race impulse train; the band 500-1250 Hz. Times: the paper's
``detection.analyse`` (whole periods, one bin per harmonic), the search
detector ``search_detector.analyse_record`` (``benchmarks/baselines/search_detector.py``) (three fault types, windows, computed
null distributions) with its null distributions cached (the usual case: one
record length per run) and cold (first record), and the DAQ's ``sample``
from 51.2 kHz to 10.24 kHz; the baseline detector ``baseline.detect`` (slip, roller-passage fit,
harmonic and fold tests) and ``Baseline.from_record`` at 2550 Hz, 25.6 kHz and 51.2 kHz with the fit to f_s and
to Nyquist (CPU seconds: one BLAS thread), with the package's least squares (``signals/harmonics.py``: the normal
equations in closed form, Bluestein transforms, Cholesky) and the plain method
(``old_*``: explicit matrices and pivoted QR, ``harmonics.refine_period_qr``; scipy's CZT and two inverses in
the outer-race test; kept here for the comparison), their ratio and the indicators' largest relative
difference; the outer-race test alone (``baseline.harmonic_test``) at the free fit's fundamental and with the
healthy model's fundamental fitted over the slip window (the detector's method),
CPU seconds and their ratio; a record the +-60 V ADC clips (36 V rms of noise) at 2550 and 10240 Hz through
``detectors.baseline.detect`` without and with its clipped-noise model, CPU seconds and their ratio.
Writes results/benchmarks/detector.json.
Usage: python benchmarks/bench_detector.py
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
from baselines import search_detector

from piezobearing.signals import daq, detection, harmonics, outer_race
from piezobearing.signals.detectors import baseline
from piezobearing.signals.envelope import EnvelopeSettings
from piezobearing.signals.fault_bands import slipped_frequencies

KIN = {"shaft_Hz": 1000 / 60, "ftf_Hz": 0.5 * 1000 / 60 * (1 - 10 / 44)}
KIN.update(bpfo_Hz=11 * KIN["ftf_Hz"], bpfi_Hz=11 * (KIN["shaft_Hz"] - KIN["ftf_Hz"]),
           bsf_Hz=0.5 * 4.4 * KIN["shaft_Hz"] * (1 - (10 / 44) ** 2))


def timed(fn, repeat: int) -> float:
    t0 = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t0) / repeat


def old_harmonic_fit(x, dt_s, f0_Hz, n_harmonics):
    """The plain harmonic fit: geometric sums with w ** n, scipy's CZT, LU solve."""
    from scipy.signal import CZT

    x = np.asarray(x, float)
    n, kk = x.size, n_harmonics
    theta = 2.0 * np.pi * f0_Hz * dt_s
    m = np.arange(0, 2 * kk + 1)
    w = np.exp(1j * m * theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        geo = np.where(np.abs(1.0 - w) > 1e-12, (1.0 - w**n) / (1.0 - w), float(n))
    g = harmonics.gram_from_sums(n, geo.real, geo.imag)  # the same assembly; the old sums: w ** n, not reduced
    if n * kk > 200_000:  # the chirp z-transform on the lines k f0: O((n + K) log(n + K))
        d = CZT(n, kk, np.exp(-1j * theta), np.exp(1j * theta))(x)
    else:  # few lines: K products
        z = np.exp(-1j * theta * np.arange(n))
        zk, d = np.ones(n, complex), np.empty(kk, complex)
        for j in range(kk):
            zk = zk * z
            d[j] = zk @ x
    xt = np.empty(2 * kk + 1)
    xt[0], xt[1::2], xt[2::2] = x.sum(), d.real, -d.imag
    return np.linalg.solve(g, xt), g, xt


def old_information(gram, sigma, cb, tolerance):
    """The plain information matrix: two inverses."""
    cov = sigma**2 * np.linalg.inv(gram)[1:, 1:]
    if tolerance > 0:
        cov = cov + np.diag(tolerance**2 * np.repeat(cb[1::2] ** 2 + cb[2::2] ** 2, 2))
    return np.linalg.inv(cov)


@baseline.one_blas_thread
def old_from_record(v, dt_s, kinematics, settings):
    """``Baseline.from_record`` with explicit matrices and pivoted QR."""
    s = baseline.estimate_slip(v, dt_s, kinematics["bpfo_Hz"], settings.slip_max, settings.slip_harmonics)
    f0, _ = harmonics.refine_period_qr(v, dt_s, slipped_frequencies(kinematics, s)["bpfo_Hz"], settings.alias_folds)
    a = harmonics.harmonic_matrix(np.size(v), dt_s, f0, harmonics.below_nyquist(dt_s, f0))
    return baseline.Baseline(baseline.slip_of(kinematics, f0), harmonics.lstsq_qr(a, np.asarray(v, float)), dt_s)


def old_harmonic_fits(x, dt_s, f0_Hz, n_harmonics):
    """:func:`old_harmonic_fit` of each row, stacked as ``harmonics.harmonic_fits`` returns them."""
    fits = [old_harmonic_fit(r, dt_s, f, n_harmonics) for r, f in zip(x, f0_Hz, strict=True)]
    return tuple(np.array(a) for a in zip(*fits, strict=True))


def old_detect(x, dt_s, kinematics, base, settings):
    """``baseline.detect`` with the plain least squares (the modules' functions swapped in: the outer-race
    test's in ``signals/outer_race.py``)."""
    saved = baseline.refine_period, outer_race.harmonic_fits, outer_race._information
    baseline.refine_period, outer_race.harmonic_fits, outer_race._information = harmonics.refine_period_qr, old_harmonic_fits, old_information
    try:
        return baseline.detect(x, 1 / dt_s, kinematics, settings, base)
    finally:
        baseline.refine_period, outer_race.harmonic_fits, outer_race._information = saved


def cpu(fn):
    """(fn's result, its CPU seconds)"""
    c0 = time.process_time()
    out = fn()
    return out, time.process_time() - c0


def baseline_rows(fs: float, rng) -> tuple:
    """The baseline detector old vs new on a 1 s record at ``fs`` (a von Mises roller train, 1.5% slip, 10 dB)."""
    n = int(fs)
    t = np.arange(n) / fs
    v = 96.0 * np.exp(10.0 * (np.cos(2 * np.pi * 0.985 * KIN["bpfo_Hz"] * t) - 1.0))
    x = v + 11.0 * rng.standard_normal(n)
    out = {}
    for folds in (1.0, 0.5):
        bs = baseline.Settings(alias_folds=folds)
        base, new_b = cpu(lambda bs=bs: baseline.Baseline.from_record(v, 1 / fs, KIN, bs))
        _, old_b = cpu(lambda bs=bs: old_from_record(v, 1 / fs, KIN, bs))
        new, new_s = cpu(lambda bs=bs, base=base: baseline.detect(x, fs, KIN, bs, base))
        old, old_s = cpu(lambda bs=bs, base=base: old_detect(x, 1 / fs, KIN, base, bs))
        tag = f"alias_folds_{folds:g}"
        out[f"baseline_cpu_s_{tag}"] = new_s
        out[f"old_baseline_cpu_s_{tag}"] = old_s
        out[f"baseline_old_over_new_{tag}"] = old_s / new_s
        out[f"from_record_cpu_s_{tag}"] = new_b
        out[f"old_from_record_cpu_s_{tag}"] = old_b
        out[f"from_record_old_over_new_{tag}"] = old_b / new_b
        out[f"indicators_{tag}"] = {t: new.families[t].statistic for t in new.families}
        out[f"indicators_max_rel_diff_{tag}"] = max(
            abs(new.families[t].statistic - old.families[t].statistic) / max(abs(old.families[t].statistic), 1.0)
            for t in new.families)
    return out, x, base


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n")[0]).parse_args()  # no options: --help only
    rng = np.random.default_rng(1)
    env = EnvelopeSettings(band_rule="fixed", band_Hz=(500.0, 1250.0))
    st = search_detector.DetectorSettings()
    out = {"cpu_count": os.cpu_count(), "record_s": 1.0}
    for fs in (2550.0, 25600.0, 51200.0):
        n = int(fs)
        t = np.arange(n) / fs
        x = rng.standard_normal(n) + 3.0 * (np.mod(t * 0.985 * KIN["bpfo_Hz"], 1.0) < 2.0 / fs)
        search_detector.null_distribution.cache_clear()
        cold = timed(lambda x=x, fs=fs: search_detector.analyse_record(x, 1 / fs, KIN, env, st), 1)
        out[f"{int(fs)}_Hz"] = {
            "exact_bin_s": timed(lambda x=x, fs=fs: detection.analyse(x, 1 / fs, KIN["bpfo_Hz"], env,
                                                                detection.IndicatorSettings()), 5),
            "search_cold_s": cold,
            "search_cached_s": timed(lambda x=x, fs=fs: search_detector.analyse_record(x, 1 / fs, KIN, env, st), 5),
        }
        out[f"{int(fs)}_Hz"]["search_over_exact"] = (out[f"{int(fs)}_Hz"]["search_cached_s"]
                                                    / out[f"{int(fs)}_Hz"]["exact_bin_s"])
    for fs in (2550.0, 25600.0, 51200.0):
        rows, x, base = baseline_rows(fs, rng)
        out[f"{int(fs)}_Hz"].update(rows)
        f0, window = 0.985 * KIN["bpfo_Hz"], (0.97 * KIN["bpfo_Hz"], KIN["bpfo_Hz"])
        for name, rng_ in (("fixed_f", None), ("slip_window", window)):
            c0 = time.process_time()
            baseline.one_blas_thread(outer_race.harmonic_test)(x, 1 / fs, f0, base, 11.0, 0.0, rng_)
            out[f"{int(fs)}_Hz"][f"outer_race_test_cpu_s_{name}"] = time.process_time() - c0
        r = out[f"{int(fs)}_Hz"]
        r["outer_race_test_slip_window_over_fixed_f"] = r["outer_race_test_cpu_s_slip_window"] / r[
            "outer_race_test_cpu_s_fixed_f"]
    for fs in (2550.0, 10240.0):  # a record the +-60 V ADC clips (36 V rms of noise): the clipped model's cost
        n = int(fs)
        t = np.arange(n) / fs
        v = 96.0 * np.exp(10.0 * (np.cos(2 * np.pi * 0.985 * KIN["bpfo_Hz"] * t) - 1.0))
        x = daq.quantise(v - v.mean() + 36.0 * rng.standard_normal(n), 24, 60.0)[0]
        bs = baseline.Settings()
        base = baseline.Baseline.from_record(v - v.mean(), 1 / fs, KIN, bs)
        r = out.setdefault(f"{int(fs)}_Hz", {})
        models = (("unclipped_model", lambda x, fs, bs, base: baseline._detect_unclipped([x], 1 / fs, KIN, base, bs)),
                  ("clipped_model", lambda x, fs, bs, base: baseline.detect(x, fs, KIN, bs, base)))
        for name, fn in models:
            c0 = time.process_time()
            fn(x, fs, bs, base)
            r[f"baseline_clipped_record_cpu_s_{name}"] = time.process_time() - c0
        r["baseline_clipped_record_clipped_over_unclipped_model"] = (
            r["baseline_clipped_record_cpu_s_clipped_model"] / r["baseline_clipped_record_cpu_s_unclipped_model"])
    x = rng.standard_normal(51200)
    out["daq_sample_51200_to_10240_s"] = timed(lambda: daq.sample(x, 1 / 51200.0, 10240.0), 5)
    path = Path("results/benchmarks/detector.json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
