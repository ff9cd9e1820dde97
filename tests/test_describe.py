"""Descriptions of what lies outside the catalogue (diagnosis/describe.py): the error's trend along the
record, its dependence on the input's size, samples stuck at one level; and every time-local event listed."""

from __future__ import annotations

import numpy as np

from piezobearing.diagnosis.describe import ALPHA, input_dependence, stuck_runs, trend
from piezobearing.diagnosis.record import Segments
from piezobearing.diagnosis.residual_tests import residual_tests
from piezobearing.diagnosis.settings import DiagnosticsSettings
from piezobearing.diagnosis.verdict import findings

FS = 1000.0


def test_clipped_sine_is_stuck_at_both_edges_and_a_noisy_one_is_not():
    t = np.arange(5000) / FS
    rng = np.random.default_rng(0)
    x = np.round(np.sin(2 * np.pi * 2 * t) + rng.normal(0, 0.01, t.size), 4)  # quantised to 0.1 mV
    assert stuck_runs(x, time_s=t)["n_runs"] == 0
    c = np.clip(x, -0.9, 0.9)
    s = stuck_runs(c, time_s=t)
    assert s["levels"] == [-0.9, 0.9] and s["n_runs"] >= 20  # 10 periods: a run per crest and trough (or more)
    at_edge = int(np.sum(np.abs(c) == 0.9))  # the noise leaves a few at the edge alone or in pairs: not runs
    assert 0.95 * at_edge <= s["n_samples"] <= at_edge
    assert s["runs"][0]["start_s"] < s["runs"][0]["stop_s"]


def test_error_growing_along_the_record_is_described_with_its_mechanisms():
    """Whitened residual whose std grows by 60% over the record (a clock drifting apart): the last third's
    energy is about 2x the first's; white noise gives no significant trend."""
    rng = np.random.default_rng(1)
    n, lw = 25000, 100
    z = rng.normal(size=n) * np.linspace(0.8, 1.3, n)
    e = np.mean(z.reshape(-1, lw) ** 2, axis=1)
    d = trend(np.arange(e.size) * lw / FS, e)
    assert d["significant"] and d["spearman_r"] > 0 and 1.8 < d["last_over_first_third"] < 2.6
    assert "grows along the record" in d["where"] and "clock" in d["mechanisms"]
    w = np.mean(rng.normal(size=n).reshape(-1, lw) ** 2, axis=1)
    assert trend(np.arange(w.size) * lw / FS, w)["p"] > ALPHA


def test_error_growing_with_the_press_force_is_described():
    """Thirteen presses of 2-14 N, the residual's std 1 + 5% per newton (a nonlinearity the catalogue lacks)."""
    rng = np.random.default_rng(2)
    peaks = np.linspace(2.0, 14.0, 13)
    rng.shuffle(peaks)
    n, seg = 13 * 1000, 1000
    f = np.zeros(n)
    z = rng.normal(size=n)
    starts = np.arange(13) * seg
    for a, p in zip(starts, peaks, strict=True):
        f[a + 500] = p
        z[a : a + seg] *= 1 + 0.05 * p
    segs = Segments("impulse", "force_peak", starts, starts + seg, starts + 500)
    d = input_dependence(z, f, segs, "force")
    assert d["significant"] and d["spearman_r"] > 0.7
    assert "grows with the force" in d["where"] and "nonlinearity" in d["mechanisms"]


def test_every_time_local_event_is_a_finding_not_only_five():
    """Seven spikes in white noise, 2 s apart: seven time-window findings."""
    rng = np.random.default_rng(3)
    e = rng.normal(size=20000)
    for k in range(7):
        e[1000 + 2000 * k : 1000 + 2000 * k + 20] += 8.0
    tests = residual_tests(e, None, 1 / FS, DiagnosticsSettings(), None, None)
    windows = [f for f in findings(tests) if f["test"] == "time_window"]
    assert len(windows) == 7
