"""What a real record brings beyond its signal: samples filled across gaps of its clock.

The record is the CI configuration's synthetic calibration (12 s at 500 Hz,
6 presses) with samples dropped from the CSV as a DAQ buffer overrun drops
them; ``calibration.resample_to_uniform`` puts it back on a uniform clock by
linear interpolation, and the diagnosis must not take the interpolation for
a measurement.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from piezobearing.diagnosis.calibration.subject import SUBJECT
from piezobearing.io import read_measurement


@pytest.fixture(scope="module")
def gapped(ci_config, tmp_path_factory):
    """The CI record with 30 samples (60 ms) lost on the rising flank of its third press, as a CSV,
    and the indices lost."""
    m, imps = SUBJECT.synthesise(ci_config, ci_config["seed"], [])
    a = imps[2].force_peak_index - 20
    lost = np.arange(a, a + 30)
    keep = np.ones(m.time_s.size, dtype=bool)
    keep[lost] = False
    path = tmp_path_factory.mktemp("gap") / "gapped.csv"
    pd.DataFrame({"time_s": m.time_s[keep], "force_N": m.force_N[keep], "voltage_V": m.voltage_V[keep]}).to_csv(
        path, index=False, float_format="%.10g"
    )
    cfg = {**ci_config, "calibration": {**ci_config["calibration"], "resample_to_uniform": True}}
    return path, lost, cfg, m


def test_resampling_marks_exactly_the_lost_samples(gapped):
    path, lost, _, m = gapped
    r = read_measurement(path, resample_to_uniform=True)
    assert r.time_s.size == m.time_s.size
    assert np.array_equal(np.flatnonzero(r.filled), lost)
    # jitter within 1.5 steps moves measured samples onto the grid: nothing is marked filled
    df = pd.read_csv(path)
    rng = np.random.default_rng(0)
    t = m.time_s + rng.uniform(-0.2, 0.2, m.time_s.size) * m.dt_s
    jit = path.with_name("jitter.csv")
    pd.DataFrame({"time_s": t, "force_N": m.force_N, "voltage_V": m.voltage_V}).to_csv(jit, index=False)
    assert read_measurement(jit, resample_to_uniform=True).filled is None
    assert df.shape[0] == m.time_s.size - lost.size


def test_filled_samples_are_left_out_of_the_fit_and_named(gapped):
    """Marked, the gapped clean record is explained and the report says where samples were filled; the
    same interpolated samples taken as measured leave a misfit at the gap (the interpolated force misses
    the press's shape and the circuit carries that error for its settling time)."""
    path, lost, cfg, m = gapped
    obs = SUBJECT.read(str(path), cfg)
    _, d = SUBJECT.diagnose(obs, cfg)
    g = d["filled_gaps"]
    assert g["n_samples"] == lost.size and len(g["gaps"]) == 1
    assert g["gaps"][0]["start_s"] == pytest.approx(m.time_s[lost[0]])
    assert g["gaps"][0]["duration_s"] == pytest.approx(lost.size * m.dt_s)
    assert g["n_left_out"] > lost.size  # the model's memory around the gap too
    assert d["selected"] == [] and d["verdict"] == "explained"
    assert d["final"]["chi2_per_sample"] == pytest.approx(1.0, abs=0.05)  # chi2 ~ the samples it counts
    assert "not measured but filled across 1 gap(s)" in SUBJECT.report(d, {})

    _, taken = SUBJECT.diagnose((replace(obs[0], filled=None), obs[1]), cfg)
    assert taken["filled_gaps"]["n_samples"] == 0
    assert taken["verdict"] == "unexplained"
    gap_t = m.time_s[lost[0]]
    windows = [u["time_s"] for u in taken["unexplained"] if u["test"] == "time_window"]
    assert any(a - 0.2 <= gap_t <= b + 0.2 for a, b in windows), taken["unexplained"]


def test_validate_names_the_filled_gap(gapped, capsys):
    """``piezobearing validate --resample-to-uniform`` accepts the gapped file and says in one line how many
    samples were filled, where, and that the diagnosis leaves them out."""
    from piezobearing.cli import main

    path, lost, _, m = gapped
    assert main(["validate", str(path), "--resample-to-uniform"]) == 0
    warn = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("WARNING")]
    assert len(warn) == 1, warn
    assert f"{lost.size} samples lost in 1 gap(s)" in warn[0] and "60 ms" in warn[0]
    assert f"t = {m.time_s[lost[0]]:.4g} s" in warn[0] and "leaves them out" in warn[0]
