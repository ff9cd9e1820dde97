"""The DAQ and the configured detector in the signal stages, on files of a stand-in bearing."""

from __future__ import annotations

import copy
import json

import pandas as pd
import pytest
from test_signals_stages import inputs, run_chain  # noqa: F401  (the fixture)

from piezobearing.signals.detectors import Detection
from piezobearing.stages import fault_types
from piezobearing.stages import signals as signal_stages

CASES = ("healthy", "faulty")


def test_indicator_carries_the_fault_type_and_every_type_test(tmp_path, inputs, paper_config):  # noqa: F811
    """fault_indicator.json: per case the paper's indicator, the fault_type and the configured detector's
    Detection (per family statistic, threshold, margin, detected), readable back as one."""
    out = run_chain(tmp_path, inputs, paper_config)
    ind = json.loads((out / "fault_indicator.json").read_text())
    assert ind["faulty"]["fault_type"] == "outer_race" and ind["healthy"]["fault_type"] == "none"
    for case in CASES:
        assert {"indicator", "threshold", "detected", "harmonics"} <= set(ind[case])
        d = Detection.from_dict(ind[case]["detection"])
        assert d.method == paper_config["signals"]["detector"]["statistic"] and d.fault_type == ind[case]["fault_type"]
        assert set(d.families) == {"outer_race", "inner_race", "rolling_element"}
    faulty, healthy = (Detection.from_dict(ind[c]["detection"]) for c in ("faulty", "healthy"))
    assert faulty.families["outer_race"].detected and faulty.margin_dB > 0
    assert not any(f.detected for f in healthy.families.values())
    nz = json.loads((out / "noisy_faulty.json").read_text())
    assert nz["anti_alias"].startswith("none") and nz["daq"]["n_clipped"] == 0  # the paper's rate: as is


def test_classification_over_seeds(tmp_path, inputs, paper_config):  # noqa: F811
    """Confusion matrix rows true type, columns classified; the stand-in outer-race fault at 10 dB; ROC per SNR."""
    cfg = copy.deepcopy(paper_config)
    cfg["signals"]["study_n_seeds"] = 10
    cfg["signals"]["detector"]["roc_snr_dB"] = [-10.0, 10.0]
    out = run_chain(tmp_path, inputs, cfg, harmonic=False)
    volt = {c: str(out / f"voltage_{c}.csv") for c in CASES}
    signal_stages.classification(volt, inputs["kinematics"], out / "cls.json", out / "cls.csv", out / "roc.csv", cfg)
    cm = json.loads((out / "cls.json").read_text())
    assert cm["classes"] == ["outer_race", "inner_race", "rolling_element", "none"]
    assert cm["rows"] == "true type" and cm["columns"] == "classified type"
    assert cm["counts"][0][0] == 10 and cm["counts"][3][3] == 10  # every seed right
    assert cm["correct_rate"]["outer_race"] == 1.0 and cm["correct_rate"]["inner_race"] is None
    roc = {r["snr_dB"]: r for r in cm["roc"]}
    assert roc[10.0]["auc"] == pytest.approx(1.0) and roc[-10.0]["auc"] < roc[10.0]["auc"]
    assert len(pd.read_csv(out / "cls.csv")) == 20 and set(pd.read_csv(out / "roc.csv")["snr_dB"]) == {-10.0, 10.0}
    with pytest.raises(ValueError, match="bearing.defects"):
        signal_stages.true_fault_type({"defects": [{"type": "outer_race"}, {"type": "inner_race"}]})
    assert signal_stages.true_fault_type({"defects": [{"type": "inner_race", "width_m": 1e-3, "angle_deg": 0.0}]}) == "inner_race"


def test_absolute_noise_reports_clipping(tmp_path, inputs, paper_config):  # noqa: F811
    """Absolute noise with a +-10 V input: the stand-in's swing clips, and noisy_{case}.json says how much."""
    cfg = copy.deepcopy(paper_config)
    cfg["signals"]["noise"].update(model="absolute", range_V=10.0, adc_bits=16)
    out = tmp_path / "out"
    signal_stages.sensor_voltage(inputs["faulty"], inputs["resistance"], None, out / "v.csv", out / "v.json", cfg)
    signal_stages.noisy(out / "v.csv", "faulty", out / "n.csv", out / "n.json", cfg)
    nz = json.loads((out / "n.json").read_text())
    v = json.loads((out / "v.json").read_text())
    assert v["voltage_peak_to_peak_V"] > 20.0
    assert nz["daq"]["clipped"] and 0 < nz["daq"]["clipped_fraction"] < 1
    assert nz["daq"]["quantisation_step_V"] == pytest.approx(20.0 / 2**16)
    assert nz["noise_std_V"] == pytest.approx(1e-6 * (nz["sample_rate_Hz"] / 2) ** 0.5)
    n = pd.read_csv(out / "n.csv")
    assert n["voltage_V"].max() <= 10.0 and list(n.columns) == ["time_s", "voltage_V", "noiseless_V"]


def test_detector_study_figures_annotate_each_case():
    """The detection maps of the three detector studies: one cell per case, annotated with its rate in %."""
    import matplotlib

    matplotlib.use("Agg")
    from piezobearing.plotting.studies import SUMMARY_FIGURES

    rows = [{"bearing__defects__0__type": t, "bearing__shaft_speed_rpm": s, "correct_rate_faulty": 0.5 + 0.1 * i,
             "false_alarm_rate_healthy": 0.0, "n_seeds": 50, "noise_model": "relative"}
            for i, (t, s) in enumerate([("outer_race", 500.0), ("inner_race", 1000.0), ("rolling_element", 1500.0)])]
    fig = SUMMARY_FIGURES["fault_type_speed"](pd.DataFrame(rows))
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert sorted(texts) == ["50", "60", "70"]
    assert set(SUMMARY_FIGURES) >= {"daq_noise", "defect_position", "fault_type_speed"}


def test_extra_fault_types_and_their_config(paper_config):
    """The types a confusion-matrix row needs a record for, and that record's config: the first defect as that type."""
    from piezobearing.chain.signals import fault_type_config
    from piezobearing.workflow.targets import extra_fault_types

    assert extra_fault_types(paper_config) == ["inner_race", "rolling_element"]  # the faulty case is outer race
    c = copy.deepcopy(paper_config)
    c["bearing"]["defects"] = []
    assert extra_fault_types(c) == []  # no defect: no size to give the other types
    c["bearing"]["defects"] = [dict(paper_config["bearing"]["defects"][0], type="inner_race", angle_deg=30.0)]
    assert extra_fault_types(c) == ["outer_race", "rolling_element"]
    t = fault_type_config(c, "rolling_element")
    assert t["bearing"]["defects"] == [dict(c["bearing"]["defects"][0], type="rolling_element")]
    assert t["housing"]["method"] == "reduced" and t["housing"]["direct_check_s"] == 0.0
    assert c["bearing"]["defects"][0]["type"] == "inner_race"  # the input untouched


def test_fault_type_records_and_their_confusion_rows(tmp_path, inputs, ci_config):  # noqa: F811
    """Rule fault_type_voltage on the CI bearing: the inner-race record carries the shaft-rate line of the load
    zone, which the outer-race record (periodic at BPFO, no slip) lacks; both get a row of the confusion matrix."""
    import numpy as np

    cfg = copy.deepcopy(ci_config)
    cfg["signals"]["study_n_seeds"] = 4
    cfg["signals"]["detector"]["roc_snr_dB"] = []
    types, line = [], {}
    for t in ("outer_race", "inner_race"):
        paths = [tmp_path / f"sensor_force_{t}.csv", tmp_path / f"voltage_{t}.csv", tmp_path / f"voltage_{t}.json"]
        fault_types.fault_type_voltage(t, inputs["resistance"], None, *paths, cfg)
        f = pd.read_csv(paths[0])["force_N"].to_numpy()
        dt = 1.0 / json.loads(paths[2].read_text())["sample_rate_Hz"]
        w = np.hanning(f.size)
        a = 2 * np.abs(np.fft.rfft(w * (f - f.mean()))) / w.sum()
        k = int(round(cfg["bearing"]["shaft_speed_rpm"] / 60 * f.size * dt))
        line[t] = a[k - 1 : k + 2].max()
        types.append(str(paths[1]))
    assert line["inner_race"] > 0.1 and line["inner_race"] > 100 * line["outer_race"]  # [N]
    out = tmp_path / "out"
    out.mkdir()
    volt = {"healthy": types[0], "faulty": types[0]}  # files stand in for the main chain's (not what is tested)
    signal_stages.classification(volt, inputs["kinematics"], out / "cls.json", out / "cls.csv", out / "roc.csv", cfg, types[1:])
    cm = json.loads((out / "cls.json").read_text())
    assert cm["true_types"]["inner_race"] == "inner_race"
    assert sum(cm["counts"][cm["classes"].index("inner_race")]) == 4


def test_healthy_stays_healthy_at_a_daq_noise(tmp_path, inputs, paper_config, monkeypatch):  # noqa: F811
    """Hide-and-find on the stage chain at a real DAQ's noise (absolute, 1e-5 V/sqrt(Hz): 0.36 mV rms against the
    stand-in's 44 V swing), the stand-in's roller over the sensor at t = 0 as in the LPM (bearing.start_angle_deg 0):
    the healthy record is classified none and over 10 seeds its folds stay quiet, the fault is outer_race in every
    seed. The sensor circuit starts in its
    periodic steady state; started at rest, the free decay left after signals.skip_s (7.6 tau: 10 mV of 22 V)
    is what the folds pick up (indicator 2.6 against at most 0.06 over the 10 seeds with the periodic start)."""
    import numpy as np
    from test_signals import DT, bearing_force

    from piezobearing.chain import signals as signals_outputs

    n, shift = 2600, 14  # the stand-in's bump is centred at 0.4 of a roller passage (36 steps): 14 steps earlier
    for case, imp in (("healthy", 0.0), ("faulty", 10.0)):
        pd.DataFrame({"time_s": np.arange(n) * DT, "force_N": bearing_force(n + shift, imp)[shift:]}).to_csv(
            inputs[case], index=False, float_format="%.10g")
    cfg = copy.deepcopy(paper_config)
    # 24 bits (the default): the detector reads clipping at the ADC's end codes (signals.daq.end_codes_V); by the
    # rule "two samples on the record's extreme" alone, one healthy seed in ten here shared its top code by chance,
    # was read as clipped and called an outer-race fault
    cfg["signals"]["noise"].update(model="absolute", noise_density_V_per_sqrtHz=1.0e-5, adc_bits=24)
    cfg["signals"]["study_n_seeds"] = 10
    cfg["signals"]["detector"]["roc_snr_dB"] = []
    out = run_chain(tmp_path, inputs, cfg, harmonic=False)
    ind = json.loads((out / "fault_indicator.json").read_text())
    assert (ind["healthy"]["fault_type"], ind["faulty"]["fault_type"]) == ("none", "outer_race")
    volt = {c: str(out / f"voltage_{c}.csv") for c in CASES}
    signal_stages.classification(volt, inputs["kinematics"], out / "cls.json", out / "cls.csv", out / "roc.csv", cfg)
    seeds = pd.read_csv(out / "cls.csv")
    healthy = seeds[seeds["case"] == "healthy"]
    # the start's leftover shows in the folds (its cells at phase 0); the outer-race harmonic test needs
    # refine_period's Gauss-Newton step by QR where the folds coincide (f_s = 36 BPFO exactly): the closed-form
    # step alone calls 3 of these 10 healthy records an outer-race fault (indicator 5-460)
    assert not healthy["inner_race_detected"].any() and not healthy["rolling_element_detected"].any()
    assert (healthy["fault_type"] == "none").all()
    assert (seeds[seeds["case"] == "faulty"]["fault_type"] == "outer_race").all()

    def leftover(d):  # the kept voltage's change over one roller passage (36 steps) at its start [V]
        v = pd.read_csv(d / "voltage_healthy.csv")["voltage_V"].to_numpy()
        return np.abs(v[36:72] - v[:36]).max()

    rest = signals_outputs.rc_voltage
    monkeypatch.setattr(signals_outputs, "rc_voltage", lambda f, dt, g, tau, period_s: rest(f, dt, g, tau))
    old = run_chain(tmp_path / "rest", inputs, cfg, harmonic=False)
    assert leftover(out) < 1e-6 and leftover(old) > 5e-3  # the free decay over one passage: 10 mV x (1 - e^-1.08)
    folds = json.loads((old / "fault_indicator.json").read_text())["healthy"]["detection"]["families"]
    assert max(folds[t]["statistic"] for t in ("inner_race", "rolling_element")) > 2 * max(
        healthy["inner_race_indicator"].max(), healthy["rolling_element_indicator"].max())
