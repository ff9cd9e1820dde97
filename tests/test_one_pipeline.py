"""One pipeline: a parameter study's case runs the workflow's own code path.

The rules' stages (called as their scripts call them: file in, file out, each with only the config keys its
rule declares) and the study's in-memory chain (:func:`piezobearing.stages.studies.workflow_chain`, the same
functions the stages call, no files) must give the same results to the bit for the same config.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from piezobearing.chain import signals as signals_outputs
from piezobearing.housing.transient import CASES
from piezobearing.io import as_read, json_as_read, read_harmonic, read_json, read_series
from piezobearing.signals import detection
from piezobearing.signals.envelope import EnvelopeSettings
from piezobearing.stages import bearing as bearing_stages
from piezobearing.stages import signals as signals_stages
from piezobearing.stages.studies import KINDS, _fault_detection_row, workflow_chain
from piezobearing.workflow.registry import declared, declared_config


def _results(record: dict) -> dict:
    """A record without its ``config`` entry: a rule records the keys it declares, the study its whole sections."""
    return {k: v for k, v in record.items() if k != "config"}


def _rule(cfg: dict, rule: str):
    """What the rule's script hands its stage: the declared keys only (registry.READS)."""
    return declared_config(declared(cfg, rule), rule)


@pytest.fixture(scope="module")
def both(tmp_path_factory, ci_config):
    """The rules' files and the study's chain on one CI-sized config (0.35 s record, coarse housing mesh,
    5 noise seeds, the sensor FEM correction from a stand-in FEM response)."""
    d = tmp_path_factory.mktemp("rules")
    cfg = copy.deepcopy(ci_config)
    cfg["bearing"].update(duration_s=0.35, settle_s=0.01, shaft_speed_rpm=1200.0)
    cfg["housing"].update(mesh_level=0.35, n_modes=4, method="reduced", direct_check_s=0.0)
    cfg["signals"].update(study_n_seeds=5, sensor_fem_correction=True)
    cfg["signals"]["detector"]["roc_snr_dB"] = [0.0]
    res = d / "resistance.json"
    res.write_text(json.dumps({"resistance_ohm": 50.0e6}))
    f = np.linspace(10.0, 200.0e3, 400)
    harm = d / "harmonic.csv"
    pd.DataFrame({"frequency_Hz": f, "voltage_per_force_V_per_N": 1.5 * (1 + 0.1 * (f / 121.0e3) ** 2),
                  "phase": 0.0 * f}).to_csv(harm, index=False)

    # the rules, in the workflow's order, through their files
    kin = d / "kinematics.json"
    npz = {c: d / f"contact_forces_{c}.npz" for c in CASES}
    bearing_stages.bearing_lpm(kin, npz, {c: d / f"contact_forces_{c}.csv" for c in CASES}, d / "lpm.json",
                               _rule(cfg, "bearing_lpm"))
    for c in CASES:
        bearing_stages.housing_mesh(c, d / f"mesh_{c}.npz", d / f"mesh_{c}.vtk", d / f"mesh_{c}.json",
                                    _rule(cfg, "housing_mesh"))
        bearing_stages.housing_transient(c, d / f"mesh_{c}.npz", npz[c], d / f"sensor_force_{c}.csv",
                                         d / f"modes_{c}.json", d / f"housing_transient_{c}.json",
                                         d / f"influence_{c}.csv", _rule(cfg, "housing_transient"))
        signals_stages.sensor_voltage(d / f"sensor_force_{c}.csv", res, harm, d / f"voltage_{c}.csv",
                                      d / f"voltage_{c}.json", _rule(cfg, "sensor_voltage"))
        signals_stages.noisy(d / f"voltage_{c}.csv", c, d / f"noisy_{c}.csv", d / f"noisy_{c}.json",
                             _rule(cfg, "noisy"))
        signals_stages.envelope(d / f"noisy_{c}.csv", d / f"voltage_{c}.csv", kin, d / f"envelope_{c}.csv",
                                d / f"envelope_{c}.json", _rule(cfg, "envelope"))
    signals_stages.indicator({c: d / f"envelope_{c}.json" for c in CASES}, kin,
                             {c: str(d / f"noisy_{c}.csv") for c in CASES}, {c: d / f"noisy_{c}.json" for c in CASES},
                             d / "fault_indicator.json", _rule(cfg, "fault_indicator"))
    signals_stages.classification({c: d / f"voltage_{c}.csv" for c in CASES}, kin, d / "classification.json",
                                  d / "classification.csv", d / "roc.csv", _rule(cfg, "fault_classification"))

    # the study's chain: the same functions, in memory
    run = workflow_chain(cfg, read_json(res), read_harmonic(harm), str(res))
    return cfg, d, run, res, harm


@pytest.mark.slow
def test_the_study_chain_equals_the_rules_files_to_the_bit(both):
    cfg, d, run, _, _ = both
    assert run["indicator"] == read_json(d / "fault_indicator.json")
    assert _results(run["lpm"]) == _results(read_json(d / "lpm.json"))
    assert run["kinematics"]["bpfo_Hz"] == read_json(d / "kinematics.json")["bpfo_Hz"]
    for c in CASES:
        assert _results(run["transient"][c]) == _results(read_json(d / f"housing_transient_{c}.json"))
        t, v, dt = read_series(d / f"voltage_{c}.csv", "voltage_V")
        assert np.array_equal(run["voltage"][c][0], t) and np.array_equal(run["voltage"][c][1], v)
        assert run["voltage"][c][2] == dt
        y, v, dts, rec = run["noisy"][c]
        assert np.array_equal(y, read_series(d / f"noisy_{c}.csv", "voltage_V")[1]) and dts > 0
        assert np.array_equal(v, read_series(d / f"noisy_{c}.csv", "noiseless_V")[1])
        assert _results(rec) == _results(read_json(d / f"noisy_{c}.json"))
        table, record = run["envelope"][c]
        assert table.equals(pd.read_csv(d / f"envelope_{c}.csv"))
        assert _results(record) == _results(read_json(d / f"envelope_{c}.json"))
    # the faulty bearing is detected and the healthy one is not: the chain is the physics, not a stub
    assert run["indicator"]["faulty"]["detected"] and not run["indicator"]["healthy"]["detected"]
    # the classification rule's function on the chain's voltages (as detector_case calls it)
    voltages = {c: run["voltage"][c][1:] for c in CASES}
    record, rows, roc = signals_outputs.fault_classification(voltages, run["kinematics"], cfg)
    assert _results(json_as_read(record)) == _results(read_json(d / "classification.json"))
    assert as_read(rows).equals(pd.read_csv(d / "classification.csv"))
    assert as_read(roc).equals(pd.read_csv(d / "roc.csv"))


@pytest.mark.slow
def test_a_fault_detection_row_reports_the_rules_values(both):
    """The fault_detection kind's summary row of the chain carries the rules' numbers."""
    cfg, d, run, _, _ = both
    row = _fault_detection_row(cfg, run)
    ind = read_json(d / "fault_indicator.json")
    for c in CASES:
        assert row[f"noiseless_indicator_{c}"] == ind[c]["noiseless"]["indicator"]
        assert row[f"in_band_snr_{c}_dB"] == ind[c]["in_band_snr_dB"]
        tr = read_json(d / f"housing_transient_{c}.json")
        assert row[f"sensor_force_peak_to_peak_{c}_N"] == tr["sensor_force_max_N"] - tr["sensor_force_min_N"]
    assert row["defect_max_drop_m"] == read_json(d / "lpm.json")["faulty"]["defect_max_drop_m"]
    assert row["detection_rate_faulty"] == 1.0 and row["indicator_faulty"] > row["threshold"]
    # the row's noise replicate 0 is the noisy rule's record (the DAQ samples at the model's rate here)
    s = cfg["signals"]
    _, v, dt = run["voltage"]["faulty"]
    r0 = detection.snr_sweep(v, dt, run["kinematics"]["bpfo_Hz"], "faulty", [s["snr_dB"]], 1, cfg["seed"],
                             EnvelopeSettings.from_config(s), detection.IndicatorSettings.from_config(s))[0]
    assert ind["faulty"]["indicator"] == pytest.approx(r0["indicator"], rel=1e-9)


def test_a_calibration_circuit_case_equals_the_calibration_rules_files(tmp_path, ci_config):
    """The calibration_circuit kind (in memory, no file) reports the calibration rules' numbers to the bit."""
    from piezobearing.stages import calibration as calibration_stages

    cfg = copy.deepcopy(ci_config)
    cfg["synthesis"]["resistance_ohm"] = 20.0e6
    meas = tmp_path / "measurement.csv"
    calibration_stages.synthesize_calibration(_rule(cfg, "synthesize_calibration"), meas)
    calibration_stages.extract_sensitivity(meas, tmp_path / "sensitivity.json", _rule(cfg, "extract_sensitivity"))
    calibration_stages.fit_resistance(meas, tmp_path / "resistance.json", tmp_path / "fit.csv",
                                      _rule(cfg, "fit_resistance"))
    calibration_stages.lowfreq(tmp_path / "resistance.json", tmp_path / "lowfreq.json", tmp_path / "lowfreq.csv",
                               _rule(cfg, "lowfreq_sensitivity"))
    case = tmp_path / "case"
    row = KINDS["calibration_circuit"](cfg, case)
    s, r, lf = (read_json(tmp_path / f) for f in ("sensitivity.json", "resistance.json", "lowfreq.json"))
    assert row["impulse_sensitivity_V_per_N"] == s["sensitivity_V_per_N"]
    assert row["resistance_fitted_ohm"] == r["resistance_ohm"] and row["nrmse"] == r["nrmse"]
    assert row["linear_from_Hz"] == lf["linear_from_Hz"]
    # the fit recovers the synthetic truth (20 MOhm)
    assert row["resistance_fitted_ohm"] == pytest.approx(20.0e6, rel=0.01)
    assert not case.exists()  # in memory
