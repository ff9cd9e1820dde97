"""The sensor FEM stages end to end on the CI config (coarse meshes), and their input checks."""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from piezobearing.stages import sensor_fem as st
from piezobearing.stages.scorecard import scorecard_sensor_fem


@pytest.fixture(scope="module")
def ci_run(tmp_path_factory, ci_config):
    """Mesh, convergence, modal, harmonic and scorecard on the CI config into a temporary folder."""
    d = tmp_path_factory.mktemp("sensor_fem")
    c = ci_config
    p = st.SensorFemParams.from_config(c)
    meshes = [str(d / f"stack_L{k}.vtk") for k in range(1, len(p.multipliers) + 1)]
    st.sensor_mesh(meshes, str(d / "mesh.json"), c)
    st.sensor_convergence(meshes, str(d / "convergence.csv"), c)
    st.sensor_modal(meshes[p.mesh_level - 1], str(d / "modal.json"), str(d / "mode.npz"), c)
    (d / "resistance.json").write_text(json.dumps({"resistance_ohm": 50e6}))
    (d / "lowfreq.json").write_text(json.dumps({"linear_from_Hz": 30.0}))
    st.sensor_harmonic(
        meshes[p.mesh_level - 1],
        str(d / "modal.json"),
        str(d / "resistance.json"),
        str(d / "lowfreq.json"),
        str(d / "harmonic.csv"),
        str(d / "band.json"),
        c,
    )
    scorecard_sensor_fem(
        str(d / "modal.json"), str(d / "band.json"), str(d / "convergence.csv"), str(d / "sensor_fem.csv")
    )
    return d


def test_modal_json_lists_labelled_modes_and_the_first_axial(ci_run):
    modal = json.loads((ci_run / "modal.json").read_text())
    labels = [m["label"] for m in modal["modes"]]
    assert "axial" in labels and "bending/rocking" in labels and "torsion" in labels
    assert all(m["frequency_short_Hz"] < modal["modal_max_frequency_Hz"] for m in modal["modes"])
    first_axial = next(m for m in modal["modes"] if m["label"] == "axial")
    assert modal["first_resonance_short_Hz"] == first_axial["frequency_short_Hz"]
    assert modal["first_resonance_open_Hz"] > modal["first_resonance_short_Hz"]
    assert modal["first_resonance_short_Hz"] == pytest.approx(1.21e5, rel=0.03)
    assert modal["material_symmetry"]["c66=(c11-c12)/2"]["holds"] is False
    assert "sensor_fem" in modal["config"]
    mode = np.load(ci_run / "mode.npz")
    assert 0.95 < np.abs(mode["displacement"]).max() <= 1.0 + 1e-12  # max |u| = 1 over all nodes


def test_harmonic_csv_and_band_json(ci_run):
    df = pd.read_csv(ci_run / "harmonic.csv")
    assert list(df.columns[:3]) == ["frequency_Hz", "voltage_per_force_V_per_N", "phase_deg"]
    assert df["frequency_Hz"].is_monotonic_increasing and df["frequency_Hz"].iloc[-1] == pytest.approx(130e3)
    band = json.loads((ci_run / "band.json").read_text())
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


def test_scorecard_rows(ci_run):
    sc = pd.read_csv(ci_run / "sensor_fem.csv")
    assert len(sc) >= 6
    first = sc[sc["quantity"].str.startswith("first resonance (first axial")].iloc[0]
    assert first["paper"] == 1.21e5 and abs(first["rel_error"]) < 0.03
    assert sc["note"].str.contains("cannot be a \\+3 dB edge").any()


def test_convergence_csv(ci_run):
    conv = pd.read_csv(ci_run / "convergence.csv")
    assert len(conv) == 3 and conv["n_dof"].is_monotonic_increasing


def test_bad_config_and_inputs_name_the_key_or_file(ci_config, ci_run, tmp_path):
    bad = copy.deepcopy(ci_config)
    bad["sensor_fem"]["mesh_level"] = 9
    with pytest.raises(st.SensorFemError, match="sensor_fem.mesh_level"):
        st.SensorFemParams.from_config(bad)
    (tmp_path / "r.json").write_text(json.dumps({"R": 1}))
    mesh = str(ci_run / "stack_L3.vtk")
    with pytest.raises(st.SensorFemError, match="resistance_ohm"):
        st.sensor_harmonic(
            mesh,
            str(ci_run / "modal.json"),
            str(tmp_path / "r.json"),
            str(ci_run / "lowfreq.json"),
            str(tmp_path / "h.csv"),
            str(tmp_path / "b.json"),
            ci_config,
        )
    with pytest.raises(st.SensorFemError, match="mesh file not found"):
        st.sensor_modal(
            str(tmp_path / "none.vtk"), str(tmp_path / "m.json"), str(tmp_path / "m.npz"), ci_config
        )
