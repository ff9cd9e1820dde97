"""The signal stages end to end on files: force CSVs of a stand-in bearing → fault_indicator.json, study, scorecard."""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest
from test_signals import BPFO, DT, bearing_force

from piezobearing.sensor.calibration import SensorCircuit, frequency_response
from piezobearing.signals import envelope
from piezobearing.stages import signals as signal_stages
from piezobearing.stages.scorecard import scorecard_signals


@pytest.fixture()
def inputs(tmp_path, paper_config):
    """Force records (healthy, faulty), kinematics.json, resistance.json, a flat sensor-FEM response."""
    n = 2600
    t = np.arange(n) * DT
    paths = {}
    for case, imp in (("healthy", 0.0), ("faulty", 10.0)):
        p = tmp_path / f"sensor_force_{case}.csv"
        pd.DataFrame({"time_s": t, "force_N": bearing_force(n, imp)}).to_csv(p, index=False, float_format="%.10g")
        paths[case] = str(p)
    kin = {"shaft_Hz": 1000 / 60, "ftf_Hz": BPFO / 11, "bpfo_Hz": BPFO, "bpfi_Hz": 11 * (1000 / 60 - BPFO / 11),
           "bsf_Hz": 30.0}
    paths["kinematics"] = str(tmp_path / "kinematics.json")
    (tmp_path / "kinematics.json").write_text(json.dumps(kin))
    paths["resistance"] = str(tmp_path / "resistance.json")
    (tmp_path / "resistance.json").write_text(json.dumps({"resistance_ohm": 50e6}))
    f = np.array([10.0, 100.0, 1000.0, 1e4, 1e5])
    rc = np.abs(frequency_response(f, SensorCircuit.from_config(paper_config["sensor"], 50e6)))
    paths["harmonic"] = str(tmp_path / "harmonic.csv")
    pd.DataFrame({"frequency_Hz": f, "voltage_per_force_V_per_N": 0.8 * rc, "phase": 0.0}).to_csv(
        paths["harmonic"], index=False)
    return paths


def run_chain(tmp_path, inputs, config, harmonic=True):
    out = tmp_path / "out"
    for case in ("healthy", "faulty"):
        signal_stages.sensor_voltage(inputs[case], inputs["resistance"], inputs["harmonic"] if harmonic else None,
                          out / f"voltage_{case}.csv", out / f"voltage_{case}.json", config)
        signal_stages.noisy(out / f"voltage_{case}.csv", case, out / f"noisy_{case}.csv", out / f"noisy_{case}.json", config)
        signal_stages.envelope(out / f"noisy_{case}.csv", out / f"voltage_{case}.csv", inputs["kinematics"],
                    out / f"envelope_{case}.csv", out / f"envelope_{case}.json", config)
    cases = ("healthy", "faulty")
    signal_stages.indicator({c: out / f"envelope_{c}.json" for c in cases}, inputs["kinematics"],
                 {c: str(out / f"noisy_{c}.csv") for c in cases}, {c: out / f"noisy_{c}.json" for c in cases},
                 out / "fault_indicator.json", config)
    return out


def test_chain_detects_the_stand_in_fault(tmp_path, inputs, paper_config):
    out = run_chain(tmp_path, inputs, paper_config)
    v = json.loads((out / "voltage_faulty.json").read_text())
    assert v["fem_correction"]["factor"] == pytest.approx(0.8, rel=1e-9)
    assert v["tau_s"] == pytest.approx(50e6 * SensorCircuit().capacitance_F, rel=1e-12)
    nz = json.loads((out / "noisy_faulty.json").read_text())
    assert nz["realised_snr_dB"] == pytest.approx(10.0, abs=0.5)
    env = json.loads((out / "envelope_faulty.json").read_text())
    assert env["n_samples"] == 2340 and abs(env["bpfo_bin_offset"]) < 1e-6  # (2600 - 255 skipped) -> 65 periods of 36
    ind = json.loads((out / "fault_indicator.json").read_text())
    assert ind["faulty"]["detected"] and not ind["healthy"]["detected"]
    assert [h["k"] for h in ind["faulty"]["harmonics"]] == [1, 2, 3]
    for key in ("indicator", "threshold", "detected", "harmonics"):
        assert key in ind["healthy"] and key in ind["faulty"]
    assert ind["config"]["signals"]["snr_dB"] == 10.0
    # the naive test on the raw spectrum fires for the healthy bearing (roller passages at BPFO)
    assert ind["healthy"]["raw_spectrum_test"]["detected"]
    assert ind["healthy"]["in_band_snr_dB"] < -20 < ind["faulty"]["in_band_snr_dB"]
    df = pd.read_csv(out / "envelope_faulty.csv")
    assert list(df.columns) == ["frequency_Hz", "amplitude_V", "noiseless_amplitude_V"]


def test_study_events_and_scorecard(tmp_path, inputs, paper_config):
    config = copy.deepcopy(paper_config)
    config["signals"].update(study_snr_min_dB=-10.0, study_snr_max_dB=20.0, study_snr_step_dB=5.0, study_n_seeds=20)
    out = run_chain(tmp_path, inputs, config, harmonic=False)
    volt = {c: out / f"voltage_{c}.csv" for c in ("healthy", "faulty")}
    signal_stages.snr_study(volt, inputs["kinematics"], out / "study.csv", out / "summary.csv", out / "study.json", config)
    study = json.loads((out / "study.json").read_text())
    assert study["faulty"]["detected_all_seeds_at_snr"] and study["healthy"]["detected_no_seed_at_snr"]
    assert -10.0 < study["faulty"]["detection_limit_dB"] <= 10.0
    summ = pd.read_csv(out / "summary.csv")
    assert set(summ["n_seeds"]) == {20} and set(summ["band_rule"]) == {"fixed", "kurtogram"}
    assert study["band_rule"] == config["signals"]["band_rule"] and "faulty" in study["other_band_rule"]
    # replicate 0 at the configured SNR is the record of the noisy stage
    rows = pd.read_csv(out / "study.csv")
    r0 = rows[(rows["case"] == "faulty") & (rows["snr_dB"] == 10.0) & (rows["seed"] == 0)
              & (rows["band_rule"] == config["signals"]["band_rule"])]
    ind = json.loads((out / "fault_indicator.json").read_text())
    assert float(r0["indicator"].iloc[0]) == pytest.approx(ind["faulty"]["indicator"], rel=1e-6)
    signal_stages.defect_events(volt["healthy"], volt["faulty"], inputs["kinematics"], out / "events.csv")
    assert len(pd.read_csv(out / "events.csv")) == 65
    scorecard_signals(out / "fault_indicator.json", out / "study.json", inputs["kinematics"], out / "scorecard.csv")
    sc = pd.read_csv(out / "scorecard.csv")
    assert sc.loc[sc["quantity"].str.startswith("BPFO"), "ours"].item() == pytest.approx(BPFO)
    assert sc.loc[sc["quantity"].str.contains("faulty bearing"), "ours"].item() == 1.0
    assert sc.loc[sc["quantity"].str.contains("healthy bearing"), "ours"].item() == 0.0


def test_bad_files_name_the_problem(tmp_path, inputs, paper_config):
    bad = tmp_path / "bad.csv"
    pd.DataFrame({"time_s": [0, 1, 2], "force": [1, 2, 3]}).to_csv(bad, index=False)
    with pytest.raises(signal_stages.SignalFileError, match="column 'force_N' missing"):
        signal_stages.read_series(bad, "force_N")
    t = np.arange(20) * DT
    t[10] += 0.3 * DT
    pd.DataFrame({"time_s": t, "force_N": 1.0}).to_csv(bad, index=False)
    with pytest.raises(signal_stages.SignalFileError, match="uneven"):
        signal_stages.read_series(bad, "force_N")
    k = tmp_path / "k.json"
    k.write_text(json.dumps({"bpfo_Hz": 70.0}))
    with pytest.raises(signal_stages.SignalFileError, match="shaft_Hz"):
        signal_stages.kinematics(k)
    config = copy.deepcopy(paper_config)
    config["signals"]["skip_s"] = 10.0
    with pytest.raises(signal_stages.SignalFileError, match="skip_s"):
        signal_stages.sensor_voltage(inputs["healthy"], inputs["resistance"], None, tmp_path / "v.csv", tmp_path / "v.json", config)
    with pytest.raises(ValueError, match="band_rule"):
        envelope.choose_band(np.zeros(100), DT, envelope.EnvelopeSettings(band_rule="magic"))


def test_snr_grid_always_holds_the_configured_snr(paper_config):
    s = dict(paper_config["signals"], study_snr_min_dB=-9.0, study_snr_max_dB=19.0, study_snr_step_dB=4.0)
    g = signal_stages.snr_grid(s)
    assert 10.0 in g and g[0] == -9.0 and g[-1] == 19.0
