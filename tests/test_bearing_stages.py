"""The bearing stages end to end on a tiny case: files, columns, keys, and the spectra the signals stage needs."""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from piezobearing.housing.checks import harmonic_amplitudes, off_harmonic_fraction
from piezobearing.stages import bearing as bearing_stages


@pytest.fixture(scope="module")
def run(tmp_path_factory, ci_config):
    cfg = copy.deepcopy(ci_config)
    cfg["bearing"]["duration_s"] = 0.2
    cfg["bearing"]["settle_s"] = 0.01
    cfg["housing"].update(mesh_level=0.35, n_modes=4, direct_check_s=0.01)
    d = tmp_path_factory.mktemp("bearing")
    paths = {
        c: {
            k: d / f"{k}_{c}"
            for k in ("npz", "csv", "mesh", "vtk", "meshjson", "force", "modes", "json", "inf")
        }
        for c in bearing_stages.CASES
    }
    bearing_stages.bearing_lpm(
        d / "kinematics.json",
        {c: paths[c]["npz"].with_suffix(".npz") for c in bearing_stages.CASES},
        {c: paths[c]["csv"].with_suffix(".csv") for c in bearing_stages.CASES},
        d / "lpm.json",
        cfg,
    )
    for c in bearing_stages.CASES:
        p = paths[c]
        bearing_stages.housing_mesh(
            c,
            p["mesh"].with_suffix(".npz"),
            p["vtk"].with_suffix(".vtk"),
            p["meshjson"].with_suffix(".json"),
            cfg,
        )
        bearing_stages.housing_transient(
            c,
            p["mesh"].with_suffix(".npz"),
            p["npz"].with_suffix(".npz"),
            p["force"].with_suffix(".csv"),
            p["modes"].with_suffix(".json"),
            p["json"].with_suffix(".json"),
            p["inf"].with_suffix(".csv"),
            cfg,
        )
    return cfg, d, paths


def test_kinematics_file_for_the_signals_stage(run):
    _, d, _ = run
    kin = json.loads((d / "kinematics.json").read_text())
    for key in ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz"):
        assert key in kin
    assert kin["bpfo_Hz"] == pytest.approx(70.83, rel=1e-3)
    assert "config" in kin


def test_sensor_force_files(run):
    cfg, _, paths = run
    dt = cfg["bearing"]["time_step_s"]
    for c in bearing_stages.CASES:
        df = pd.read_csv(paths[c]["force"].with_suffix(".csv"))
        assert list(df.columns) == ["time_s", "force_N"]
        np.testing.assert_allclose(np.diff(df["time_s"]), dt, rtol=1e-6)
        assert (
            np.isfinite(df["force_N"]).all() and (df["force_N"] > -1e-6).all()
        )  # the sensor is in compression
        tr = json.loads(paths[c]["json"].with_suffix(".json").read_text())
        assert tr["direct_check"]["rms_rel_diff"] < 0.02
        modes = json.loads(paths[c]["modes"].with_suffix(".json").read_text())
        assert modes["natural_frequencies_Hz"][0] > modes["nyquist_Hz"]


def test_spectra_healthy_and_faulty(run):
    """Both records are periodic at BPFO; the defect adds the sharp, harmonic-rich dips."""
    cfg, d, paths = run
    bpfo = json.loads((d / "kinematics.json").read_text())["bpfo_Hz"]
    dt = cfg["bearing"]["time_step_s"]
    f = {c: pd.read_csv(paths[c]["force"].with_suffix(".csv"))["force_N"].to_numpy() for c in bearing_stages.CASES}
    for c in bearing_stages.CASES:
        assert off_harmonic_fraction(f[c], dt, bpfo) < 1e-3
    amp = {c: harmonic_amplitudes(f[c], dt, bpfo, 17) for c in bearing_stages.CASES}
    # healthy: the roller-passage modulation, dominated by the first harmonic
    assert amp["healthy"][0] > 5 * amp["healthy"][2:].max()
    # faulty: the impulses spread over the harmonics
    assert amp["faulty"][4:].sum() > 5 * amp["healthy"][4:].sum()
    assert np.ptp(f["faulty"]) > 1.2 * np.ptp(f["healthy"])


def test_contact_force_files(run):
    cfg, d, paths = run
    lpm = json.loads((d / "lpm.json").read_text())
    assert lpm["healthy"]["harris_roller_at_bottom"]["max_rel_diff"] < 0.01
    assert lpm["faulty"]["impact_frequency_Hz"] == pytest.approx(lpm["kinematics"]["bpfo_Hz"], rel=0.01)
    df = pd.read_csv(paths["faulty"]["csv"].with_suffix(".csv"))
    z = cfg["bearing"]["n_rollers"]
    assert df.shape[1] == 1 + 2 * z
    npz = np.load(paths["faulty"]["npz"].with_suffix(".npz"))
    assert npz["fine_load_N"].shape[1] == z and len(npz["fine_time_s"]) > 30 * len(npz["time_s"])


def test_a_second_run_writes_identical_files(run, tmp_path):
    """Result files hold no wall-clock times and no unseeded randomness: a rerun is byte-identical."""
    cfg, d, paths = run
    p = paths["healthy"]
    bearing_stages.bearing_lpm(
        tmp_path / "kinematics.json",
        {c: tmp_path / f"contact_{c}.npz" for c in bearing_stages.CASES},
        {c: tmp_path / f"contact_{c}.csv" for c in bearing_stages.CASES},
        tmp_path / "lpm.json",
        cfg,
    )
    bearing_stages.housing_transient(
        "healthy",
        p["mesh"].with_suffix(".npz"),
        p["npz"].with_suffix(".npz"),
        tmp_path / "force.csv",
        tmp_path / "modes.json",
        tmp_path / "transient.json",
        tmp_path / "influence.csv",
        cfg,
        tmp_path / "quasi_static.npz",
    )
    conv = copy.deepcopy(cfg)
    conv["housing"]["convergence_levels"] = [0.25, 0.3, 0.35]
    # b takes the level 0.35 (housing.mesh_level) from the transient's quasi-static force instead of
    # factorising that mesh again: the same bytes as a, which solves every level itself
    for k, qs in (("a", None), ("b", tmp_path / "quasi_static.npz")):
        bearing_stages.mesh_convergence(
            p["npz"].with_suffix(".npz"), tmp_path / f"conv_{k}.json", tmp_path / f"conv_{k}.csv", conv, qs
        )
    pairs = [
        (d / "kinematics.json", tmp_path / "kinematics.json"),
        (d / "lpm.json", tmp_path / "lpm.json"),
        *[(paths[c]["csv"].with_suffix(".csv"), tmp_path / f"contact_{c}.csv") for c in bearing_stages.CASES],
        (p["force"].with_suffix(".csv"), tmp_path / "force.csv"),
        (p["modes"].with_suffix(".json"), tmp_path / "modes.json"),
        (p["json"].with_suffix(".json"), tmp_path / "transient.json"),
        (p["inf"].with_suffix(".csv"), tmp_path / "influence.csv"),
        (tmp_path / "conv_a.json", tmp_path / "conv_b.json"),
        (tmp_path / "conv_a.csv", tmp_path / "conv_b.csv"),
    ]
    for first, second in pairs:
        assert first.read_bytes() == second.read_bytes(), first.name
