"""The sensor FEM stages end to end on the CI config (coarse meshes), and their input checks.

The files are those of the suite's one CI workflow run (``ci_run``, tests/conftest.py): the stages ran there once,
not again here.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from piezobearing.stages import sensor_fem as sensor_fem_stages

pytestmark = pytest.mark.slow  # the workflow run

#: The sensor FEM files of the CI workflow run (tests/conftest.py), by the short names used below.
FILES = {
    "modal.json": "results/sensor/modal.json",
    "mode.npz": "results/sensor/first_axial_mode.npz",
    "harmonic.csv": "results/sensor/harmonic.csv",
    "band.json": "results/sensor/band.json",
    "convergence.csv": "results/sensor/convergence.csv",
    "sensor_fem.csv": "results/scorecard/sensor_fem.csv",
    "lowfreq.json": "results/sensor/lowfreq.json",
    "stack_L3.vtk": "results/sensor/mesh/stack_L3.vtk",
    "ritz_model.npz": "results/sensor/ritz_model.npz",
}


class _Results:
    """``results / "modal.json"``: a sensor FEM file of the workflow run."""

    def __init__(self, root):
        self.root = root

    def __truediv__(self, name: str):
        return self.root / FILES[name]


@pytest.fixture(scope="module")
def sensor_run(ci_run):
    """Mesh, convergence, modal, harmonic and scorecard as the CI workflow ran them (the suite's one run;
    the harmonic with the fitted R and the low-frequency stage's band edge, 30 Hz on this config)."""
    return _Results(ci_run)


def test_modal_json_lists_labelled_modes_and_the_first_axial(sensor_run):
    modal = json.loads((sensor_run / "modal.json").read_text())
    labels = [m["label"] for m in modal["modes"]]
    assert "axial" in labels and "bending/rocking" in labels and "torsion" in labels
    assert all(m["frequency_short_Hz"] < modal["modal_max_frequency_Hz"] for m in modal["modes"])
    first_axial = next(m for m in modal["modes"] if m["label"] == "axial")
    assert modal["first_resonance_short_Hz"] == first_axial["frequency_short_Hz"]
    assert modal["first_resonance_open_Hz"] > modal["first_resonance_short_Hz"]
    assert modal["first_resonance_short_Hz"] == pytest.approx(1.21e5, rel=0.03)
    assert modal["material_symmetry"]["c66=(c11-c12)/2"]["holds"] is False
    assert "sensor_fem" in modal["config"]
    mode = np.load(sensor_run / "mode.npz")
    assert 0.95 < np.abs(mode["displacement"]).max() <= 1.0 + 1e-12  # max |u| = 1 over all nodes


def test_harmonic_csv_and_band_json(sensor_run):
    df = pd.read_csv(sensor_run / "harmonic.csv")
    assert list(df.columns[:3]) == ["frequency_Hz", "voltage_per_force_V_per_N", "phase_deg"]
    assert df["frequency_Hz"].is_monotonic_increasing and df["frequency_Hz"].iloc[-1] == pytest.approx(130e3)
    band = json.loads((sensor_run / "band.json").read_text())
    assert band["band_low_Hz"] == 30.0
    assert band["reference_frequency_Hz"] < band["band_high_27_percent_Hz"] < band["band_high_Hz"]
    assert band["band_high_Hz"] < band["loaded_resonance_Hz"] < band["first_axial_open_Hz"]
    # The root-found edge sits on the curve: interpolate the sweep there.
    h = np.interp(band["band_high_Hz"], df["frequency_Hz"], df["voltage_per_force_V_per_N"])
    assert h / band["reference_sensitivity_V_per_N"] == pytest.approx(10 ** (3 / 20), rel=2e-3)
    # Mid-band: the voltage is in phase with compression, less the RC lead atan(f_c / f).
    mid = df[(df["frequency_Hz"] > 300) & (df["frequency_Hz"] < 3000)]
    lead = np.degrees(np.arctan(band["fem_corner_Hz"] / mid["frequency_Hz"]))
    np.testing.assert_allclose(mid["phase_deg"], lead, atol=0.05)


def test_scorecard_rows(sensor_run):
    sc = pd.read_csv(sensor_run / "sensor_fem.csv")
    assert len(sc) >= 6
    first = sc[sc["quantity"].str.startswith("first resonance (first axial")].iloc[0]
    assert first["paper"] == 1.21e5 and abs(first["rel_error"]) < 0.03
    assert sc["note"].str.contains("cannot be a \\+3 dB edge").any()


def test_convergence_csv(sensor_run):
    """The configured refinement levels (CI's 0.5, 0.75, 1.0): the first axial frequency changes by < 1% between
    the two finest, and falls monotonically (a conforming displacement model is too stiff). The paper config's levels
    (1.0, 1.5, 2.0) are the whole-paper run's table (docs/validation/closed_forms.md)."""
    conv = pd.read_csv(sensor_run / "convergence.csv")
    assert len(conv) == 3 and conv["n_dof"].is_monotonic_increasing
    assert abs(conv["change_short_percent"].iloc[-1]) < 1.0
    assert abs(conv["change_open_percent"].iloc[-1]) < 1.0
    assert np.all(np.diff(conv["first_axial_short_Hz"]) < 0)


def test_bad_config_and_inputs_name_the_key_or_file(ci_config, sensor_run, tmp_path):
    bad = copy.deepcopy(ci_config)
    bad["sensor_fem"]["mesh_level"] = 9
    with pytest.raises(sensor_fem_stages.SensorFemError, match="sensor_fem.mesh_level"):
        sensor_fem_stages.SensorFemParams.from_config(bad)
    (tmp_path / "r.json").write_text(json.dumps({"R": 1}))
    ritz = str(sensor_run / "ritz_model.npz")

    def harmonic(ritz_path):
        return sensor_fem_stages.sensor_harmonic(ritz_path, str(sensor_run / "modal.json"), str(tmp_path / "r.json"),
                                                 str(sensor_run / "lowfreq.json"), str(tmp_path / "h.csv"),
                                                 str(tmp_path / "b.json"), ci_config)

    with pytest.raises(sensor_fem_stages.SensorFemError, match="resistance_ohm"):
        harmonic(ritz)
    (tmp_path / "r.json").write_text(json.dumps({"resistance_ohm": 50e6}))
    with pytest.raises(sensor_fem_stages.SensorFemError, match="none.npz: file not found; run the rule sensor_modal"):
        harmonic(str(tmp_path / "none.npz"))
    (tmp_path / "row.json").write_text(json.dumps({"row": {"level": 1, "multiplier": 0.5}}))
    meshes = [str(sensor_run.root / f"results/sensor/mesh/stack_L{k}.vtk") for k in (1, 2, 3)]
    with pytest.raises(sensor_fem_stages.SensorFemError,
                       match="row.json: the row of level 1 is not this config's sensor_fem.mesh_level"):
        sensor_fem_stages.sensor_convergence(meshes, str(tmp_path / "row.json"), str(tmp_path / "c.csv"), ci_config)
    with pytest.raises(sensor_fem_stages.SensorFemError, match="mesh file not found"):
        sensor_fem_stages.sensor_modal(
            str(tmp_path / "none.vtk"), str(tmp_path / "m.json"), str(tmp_path / "m.npz"), str(tmp_path / "r.npz"),
            str(tmp_path / "row.json"), ci_config,
        )
