"""The calibration diagnosis's hot path, previous method beside the current one in one process.

``clock_drift`` is a candidate in every calibration diagnosis (and the whole model in the cases that hide
it), and its windowed-sinc reading and noise gain took most of a diagnosis's time. Previous method:
numpy's ``i0`` and ``sinc`` per tap, the noise gain as the taps x frequencies complex products, and the
likelihood's FFTs through ``numpy.fft``; current: a Horner series of I0 and one sine a sample, the gain as a
cosine series of the taps' mean autocorrelation, ``scipy.fft`` (numpy's numbers bit for bit).

Times (CPU seconds of this process, numpy with one thread; previous and current alternated, best of
``--repeat``): one reading and one noise gain of the default record (25001 samples), and the whole
diagnosis of the default synthetic record with a hidden effect (``--cases``), with what each found.

Writes results/benchmarks/clock_drift.json. Usage: python benchmarks/bench_clock_drift.py [--repeat N] [--cases ...]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import piezobearing.config  # noqa: E402
from piezobearing.diagnosis import fit as fit_module  # noqa: E402
from piezobearing.diagnosis.calibration.effects import (
    ForceRecord,  # noqa: E402
    clock_drift,  # noqa: E402
)
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize  # noqa: E402
from piezobearing.diagnosis.calibration.subject import diagnose_record  # noqa: E402
from piezobearing.diagnosis.settings import DiagnosticsSettings  # noqa: E402
from piezobearing.sensor.calibration import detect_impulses  # noqa: E402
from piezobearing.stages.calibration import nominal_circuit  # noqa: E402

HIDDEN = {
    "clock_drift": [{"name": "clock_drift", "params": {"clock_drift_ppm": 100.0}}],
    "channel_delay": [{"name": "channel_delay", "params": {"delay_s": 0.015}}],
    "clean": [],
}


def kernel_previous(frac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The previous taps: numpy's i0 and sinc for every tap."""
    m = np.arange(-clock_drift.HALF + 1, clock_drift.HALF + 1)
    t = np.asarray(frac, dtype=float)[:, None] - m[None, :]
    win = np.i0(clock_drift.BETA * np.sqrt(np.clip(1 - (t / clock_drift.HALF) ** 2, 0, None))) / np.i0(clock_drift.BETA)
    h = np.sinc(t) * win
    return m, h / h.sum(axis=1, keepdims=True)


def noise_gain_previous(f_per_sample: np.ndarray, epsilon: float, n: int, k: int = 16,
                        cosines: np.ndarray | None = None) -> np.ndarray:
    """The previous noise gain: the taps x frequencies complex products, a chunk of frequencies at a time.

    ``cosines`` is the current method's table, which the effect passes; this method has no use for it."""
    shift = epsilon * np.linspace(0, n - 1, k)
    m, h = kernel_previous(shift - np.floor(shift))
    f = np.asarray(f_per_sample, dtype=float)
    out = np.empty(f.shape)
    for a in range(0, f.size, clock_drift.CHUNK):
        e = np.exp(-2j * np.pi * np.outer(m, f[a : a + clock_drift.CHUNK]))
        out[a : a + clock_drift.CHUNK] = np.sqrt(np.mean(np.abs(h @ e) ** 2, axis=0))
    return out


@contextlib.contextmanager
def previous_method():
    """clock_drift's previous kernel and gain, numpy's FFT in the likelihood."""
    saved = clock_drift.kernel, clock_drift.noise_gain, fit_module.sfft
    clock_drift.kernel, clock_drift.noise_gain, fit_module.sfft = kernel_previous, noise_gain_previous, np.fft
    try:
        yield
    finally:
        clock_drift.kernel, clock_drift.noise_gain, fit_module.sfft = saved


def cpu(fn, repeat: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return best, out


def diagnosis(config: dict, hidden: list[dict]) -> dict:
    c = config
    m = synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"], hidden)
    imps = detect_impulses(m.force_N, m.voltage_V, m.time_s[1] - m.time_s[0], 0.2, 0.8)
    _, d = diagnose_record(
        ForceRecord(m.time_s, m.force_N),
        m.voltage_V,
        nominal_circuit(c, c["calibration"]["initial_resistance_ohm"]),
        [],
        DiagnosticsSettings.from_config(c["diagnostics"]),
        imps,
    )
    return d


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cases", nargs="*", default=list(HIDDEN), choices=list(HIDDEN))
    a = ap.parse_args()
    config = piezobearing.config.load()
    n = 25001
    x = np.random.default_rng(3).normal(size=n + 16)
    f = np.fft.rfftfreq(n)
    parts = {}
    for name, new, old in (
        ("reading (drifted), 25001 samples", lambda: clock_drift.drifted(x, 1e-4, 16), None),
        ("noise gain, 12501 frequencies", lambda: clock_drift.noise_gain(f, 1e-4, n),
         lambda: noise_gain_previous(f, 1e-4, n)),
    ):
        if old is None:
            def old():
                with previous_method():
                    return clock_drift.drifted(x, 1e-4, 16)
        t_old, y_old = cpu(old, a.repeat)
        t_new, y_new = cpu(new, a.repeat)
        parts[name] = {"previous_cpu_s": t_old, "current_cpu_s": t_new, "ratio_previous_over_current": t_old / t_new,
                       "max_abs_difference": float(np.max(np.abs(y_old - y_new)))}
        print(name, parts[name], flush=True)
    cases = {}
    for case in a.cases:
        with previous_method():
            t_old, d_old = cpu(lambda case=case: diagnosis(config, HIDDEN[case]), 1)
        t_new, d_new = cpu(lambda case=case: diagnosis(config, HIDDEN[case]), 1)
        po, pn = d_old["final"]["params"], d_new["final"]["params"]
        cases[case] = {
            "previous_cpu_s": t_old,
            "current_cpu_s": t_new,
            "ratio_previous_over_current": t_old / t_new,
            "selected": [d_old["selected"], d_new["selected"]],
            "verdict": [d_old["verdict"], d_new["verdict"]],
            "final_nrmse": [d_old["final"]["nrmse"], d_new["final"]["nrmse"]],
            "final_params_max_rel_difference": max(abs(pn[k] - po[k]) / max(abs(po[k]), 1e-300) for k in po),
        }
        print(case, cases[case], flush=True)
    out = Path("results/benchmarks/clock_drift.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({
        "what": "calibration diagnosis hot path: clock_drift reading and noise gain, likelihood FFTs; previous vs current",
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(), "load_average": os.getloadavg()},
        "parts": parts,
        "diagnosis_default_record": cases,
    }, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
