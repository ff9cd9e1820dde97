"""The detector interface: every method through ``detectors.detect`` on a synthetic faulty and a healthy record.

Hide and find at the paper's bearing (N 305 at 1000 rpm, BPFO 70.8 Hz) and rate (2550 Hz), with each method's
settings from the default config and the paper's white noise at 10 dB over the roller passages' power: an
outer-race fault's impacts (10 V, ringing a 900 Hz resonance in the paper's 500-1250 Hz band; 13-26 dB over
the thresholds) are called ``outer_race`` and the healthy record ``none`` (margins -1.5 to -10 dB). The result round-trips through
JSON.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from piezobearing import config
from piezobearing.bearing.geometry import BearingGeometry, kinematic_frequencies
from piezobearing.signals import detectors

FS = 2550.0
FR = 1000.0 / 60.0
G = 10.0 / 44.0
FTF = 0.5 * FR * (1 - G)
KIN = {"shaft_Hz": FR, "ftf_Hz": FTF, "bpfo_Hz": 11 * FTF, "bpfi_Hz": 11 * (FR - FTF),
       "bsf_Hz": 0.5 * 44.0 / 10.0 * FR * (1 - G**2)}
N = int(4 * FS)  # 4 s: 283 roller passages


def passages(n: int = N) -> np.ndarray:
    """The healthy sensor: one smooth bump per roller passing it, periodic at BPFO [V] (a von Mises bump)."""
    t = np.arange(n) / FS
    v = 40.0 * np.exp(10.0 * (np.cos(2 * np.pi * (t * KIN["bpfo_Hz"] + 0.3)) - 1.0))
    return v - v.mean()


def outer_race_impacts(n: int = N, amp_V: float = 10.0) -> np.ndarray:
    """An outer-race defect: every roller strikes it at BPFO and rings a 900 Hz resonance (decay 5 ms) [V]."""
    t = np.arange(n) / FS
    x = np.zeros(n)
    for t0 in (0.21 + np.arange(int(n / FS * KIN["bpfo_Hz"]) + 1)) / KIN["bpfo_Hz"]:
        tau = t - t0
        on = tau >= 0
        x[on] += amp_V * np.exp(-tau[on] / 5e-3) * np.sin(2 * np.pi * 900.0 * tau[on])
    return x


@pytest.fixture(scope="module")
def records():
    rng = np.random.default_rng(11)
    noise = np.sqrt(np.mean(passages() ** 2) / 10.0) * rng.standard_normal((2, N))  # the paper's 10 dB (3.4 V)
    return {"healthy": passages() + noise[0], "faulty": passages() + outer_race_impacts() + noise[1]}


@pytest.mark.parametrize("method", detectors.METHODS)
def test_each_method_finds_the_outer_race_fault_and_not_a_healthy_one(method, records):
    reference = passages() if method == "baseline" else None
    found = detectors.detect(records["faulty"], FS, KIN, method, reference=reference)
    clean = detectors.detect(records["healthy"], FS, KIN, method, reference=reference)
    assert found.method == clean.method == method
    assert found.fault_type == "outer_race", found.families
    assert found.families["outer_race"].detected and found.margin_dB > 0
    assert clean.fault_type == "none", clean.families
    assert not any(f.detected for f in clean.families.values()) and clean.margin_dB <= 0
    for d in (found, clean):
        assert set(d.families) <= set(detectors.FAULT_TYPES)
        for name, f in d.families.items():
            assert f.family == name
            assert f.margin_dB == pytest.approx(10 * math.log10(f.statistic / f.threshold))
            assert not f.detected or f.statistic > f.threshold
            for line in f.lines:
                assert line.above == (line.level_dB > line.threshold_dB)
        assert 0 < d.false_alarm_probability < 0.01
        assert d.shaft_rate_Hz == pytest.approx(FR)


def test_band_based_methods_report_their_band_and_lines(records):
    for method in ("paper", "envelope"):
        d = detectors.detect(records["faulty"], FS, KIN, method)
        assert d.band_Hz == (500.0, 1250.0)  # the config's fixed band
        labels = [ln.label for ln in d.families["outer_race"].lines]
        assert labels[:3] == ["1xBPFO", "2xBPFO", "3xBPFO"]
        assert d.families["outer_race"].lines[0].frequency_Hz == pytest.approx(KIN["bpfo_Hz"], abs=1.0)
    assert detectors.detect(records["faulty"], FS, KIN, "baseline", reference=passages()).band_Hz is None


def test_detection_round_trips_through_json(records):
    for method in detectors.METHODS:
        d = detectors.detect(records["healthy"], FS, KIN, method, reference=passages())
        back = detectors.Detection.from_dict(json.loads(json.dumps(d.to_dict())))
        assert back == d


def test_kinematics_from_a_bearing_object_and_bad_inputs(records):
    kin = kinematic_frequencies(BearingGeometry.from_config(config.load()["bearing"]), FR)
    a = detectors.detect(records["faulty"], FS, kin, "paper")
    b = detectors.detect(records["faulty"], FS, KIN, "paper")
    assert a.families["outer_race"].statistic == pytest.approx(b.families["outer_race"].statistic, rel=1e-9)
    with pytest.raises(ValueError, match="unknown; use one of paper, envelope, baseline"):
        detectors.detect(records["faulty"], FS, KIN, "cepstrum")
    with pytest.raises(ValueError, match="needs a healthy reference"):
        detectors.detect(records["faulty"], FS, KIN, "baseline")
    with pytest.raises(ValueError, match="bpfi_Hz"):
        detectors.detect(records["faulty"], FS, {"shaft_Hz": FR, "bpfo_Hz": 70.8}, "envelope")
    with pytest.raises(TypeError, match="paper.Settings"):
        detectors.detect(records["faulty"], FS, KIN, "paper", settings=detectors.envelope.Settings.from_config(
            config.load()["signals"]))


def test_detect_many_equals_detect_record_by_record(records):
    xs = [records["healthy"], records["faulty"]]
    for method in detectors.METHODS:
        many = detectors.detect_many(xs, FS, KIN, method, reference=passages())
        assert many == [detectors.detect(x, FS, KIN, method, reference=passages()) for x in xs]
