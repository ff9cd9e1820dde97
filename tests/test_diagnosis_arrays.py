"""What a diagnosis keeps of a long record: display-thinned series, the zoom at the full rate, no
series held per ranked candidate (memory and diagnosis.npz grow with what is kept, not with the record)."""

from __future__ import annotations

import numpy as np
import pytest

from piezobearing.diagnosis import engine
from piezobearing.diagnosis.record import Segments


def test_envelope_thin_keeps_every_bins_extremes_in_order():
    rng = np.random.default_rng(1)
    x = rng.normal(size=100_003)
    x[54_321] = 40.0  # one spike a stride decimation would lose
    y = engine.envelope_thin(x, 1000)
    bs = -(-x.size // 500)
    bins = -(-x.size // bs)
    assert y.size == 2 * bins and 990 <= y.size <= 1000
    assert y.max() == 40.0 and y.min() == x.min()
    for b in (0, 17, bins - 1):
        chunk = x[b * bs : (b + 1) * bs]
        first, second = y[2 * b], y[2 * b + 1]
        assert {first, second} == {chunk.min(), chunk.max()}
        assert (first == chunk.min()) == (np.argmin(chunk) <= np.argmax(chunk))
    t = engine.thinned_time(np.arange(x.size) * 1e-3, 1000)
    assert t.size == y.size and np.all(np.diff(t) > 0) and t[-1] <= (x.size - 1) * 1e-3
    short = np.arange(10.0)
    assert engine.envelope_thin(short, 1000) is short


def test_zoom_window_is_where_the_residual_is_largest():
    r = np.ones(1000)
    r[600:700] = 5.0
    seg = Segments(
        "impulse", "force_peak", np.arange(0, 1000, 100), np.arange(100, 1001, 100), np.arange(50, 1000, 100)
    )
    assert engine.zoom_window(r, seg, 1) == (600, 700)
    lo, hi = engine.zoom_window(r, seg, 3)
    assert lo <= 600 and hi >= 700 and hi - lo == 300
    assert engine.zoom_window(r, Segments.none(), 1) == (0, 1000)


@pytest.fixture(scope="module")
def mains_diagnosis(ci_config):
    from piezobearing.diagnosis.calibration.subject import SUBJECT

    hidden = [{"name": "mains_pickup", "params": {"mains_h1_cos_V": 0.02}}]
    obs = SUBJECT.synthesise(ci_config, ci_config["seed"], hidden)
    d, diag = SUBJECT.diagnose(obs, ci_config)
    return d, diag


def test_arrays_thin_series_and_keep_the_zoom_at_full_rate(mains_diagnosis):
    d, diag = mains_diagnosis
    n = d.record.n
    full = engine.arrays(d)
    assert n <= engine.DISPLAY_POINTS and np.array_equal(full["voltage_V"], d.voltage_V)
    a = engine.arrays(d, points=600)
    for key in ("time_s", "voltage_V", "force_N", "baseline_model_V", "final_residual_V", "quiet_mask"):
        assert 500 <= a[key].size <= 600 and a[key].size == a["time_s"].size, key
    assert a["voltage_V"].max() == d.voltage_V.max() and a["voltage_V"].min() == d.voltage_V.min()
    z0, z1 = int(a["zoom_start"]), int(a["zoom_stop"])
    r = d.baseline.residual_V
    ms = [np.mean(r[s:e] ** 2) for s, e in zip(d.segments.start, d.segments.stop, strict=True)]
    k = int(np.argmax(ms))
    assert (z0, z1) == (d.segments.start[k], d.segments.stop[k])
    assert np.array_equal(a["zoom_voltage_V"], d.voltage_V[z0:z1])
    assert np.array_equal(a["zoom_final_model_V"], d.final.model_V[z0:z1])
    assert float(a["t0_s"]) + z0 * float(a["dt_s"]) == pytest.approx(d.record.time_s[z0])


def test_figures_draw_from_thinned_arrays(mains_diagnosis):
    from piezobearing.plotting.diagnostics import all_figures

    d, diag = mains_diagnosis
    figs = all_figures(engine.arrays(d, points=600), diag)
    overlay = figs["overlay"]
    zoom = overlay.axes[1]
    assert zoom.get_xlim()[1] - zoom.get_xlim()[0] < 0.5 * (d.record.time_s[-1] - d.record.time_s[0])


def test_ranked_candidates_hold_no_series(mains_diagnosis):
    d, diag = mains_diagnosis
    assert diag["selected"] == ["mains_pickup"]
    for c in d.ranking[1:]:
        assert c.fit.model_V.size == c.fit.residual_V.size == c.fit.result.residual.size == 0
        assert np.isfinite(c.fit.residual_rms_V) and c.fit.summary()["nrmse"] == c.fit.nrmse
    for c in d.ranking:
        assert not getattr(c.fit.model, "_cache", {})
    assert d.final.residual_V.size == d.record.n
    assert diag["ranking"][1]["nrmse"] == d.ranking[1].fit.nrmse


def test_clock_drift_interpolates_in_chunks_with_the_same_numbers(monkeypatch):
    """The windowed-sinc reading of clock_drift works through the record in chunks (its kernel arrays
    are samples x 32: a 600k-sample record took 1.6 GB at once); the result is bit-identical. Its taps are
    the Kaiser-windowed sinc (numpy's sinc and i0) to 1e-13 of the largest tap, and its noise gain (a cosine series of the taps'
    mean autocorrelation) is the rms over the offsets of |sum_m h[m] exp(-2 pi i m f)| to 1e-12 relative."""
    from piezobearing.diagnosis.calibration.effects import clock_drift

    x = np.random.default_rng(3).normal(size=3 * clock_drift.CHUNK + 17)
    chunked = clock_drift.drifted(x, 1e-4, 25)
    monkeypatch.setattr(clock_drift, "CHUNK", x.size)
    assert np.array_equal(chunked, clock_drift.drifted(x, 1e-4, 25))
    mu = np.r_[0.0, np.random.default_rng(4).random(50), 0.5, 1 - 1e-9]
    m, h = clock_drift.kernel(mu)
    t = mu[:, None] - m[None, :]
    ref = np.sinc(t) * np.i0(clock_drift.BETA * np.sqrt(np.clip(1 - (t / clock_drift.HALF) ** 2, 0, None)))
    np.testing.assert_allclose(h, ref / ref.sum(axis=1, keepdims=True), rtol=0, atol=1e-13 * np.abs(h).max())
    assert np.array_equal(h[0], m == 0)  # mu = 0 reads the sample itself
    f = np.fft.rfftfreq(x.size)
    shift = 1e-4 * np.linspace(0, x.size - 1, 16)
    _, hs = clock_drift.kernel(shift - np.floor(shift))
    direct = np.sqrt(np.mean(np.abs(hs @ np.exp(-2j * np.pi * np.outer(m, f))) ** 2, axis=0))
    np.testing.assert_allclose(clock_drift.noise_gain(f, 1e-4, x.size), direct, rtol=1e-12, atol=1e-14 * direct.max())
