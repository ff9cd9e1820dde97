"""Order tracking in ``piezobearing detect``: a record with a tachometer or a speed channel is resampled at uniform
shaft angles before the envelope analysis (hide and find on a speed ramp), and a bad channel is one line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.cli import main
from piezobearing.io import MeasurementError
from piezobearing.signals import order
from piezobearing.stages.recording import RigError, detect_recording

FS = 12000.0
BEARING = RollingBearing.from_designation("SKF 6205")


def ramp_record(seed: int = 1, seconds: float = 10.0, rpm: tuple[float, float] = (900.0, 1500.0),
                amplitude: float = 2.0) -> pd.DataFrame:
    """An outer-race fault of an SKF 6205 while the shaft ramps linearly through ``rpm``: impacts every
    1/BPFO revolution (1 % jitter), each ringing a 3.2 kHz resonance, in unit noise with 5 shaft harmonics;
    a once-per-revolution TTL tachometer and the speed [rpm] beside it."""
    rng = np.random.default_rng(seed)
    n = int(FS * seconds)
    t = np.arange(n) / FS
    f0, f1 = rpm[0] / 60.0, rpm[1] / 60.0
    theta = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / seconds * t**2)
    bpfo_order = BEARING.kinematics(1.0).bpfo_Hz
    impacts = 2 * np.pi * np.cumsum(rng.normal(1.0, 0.01, int(theta[-1] / (2 * np.pi) * bpfo_order))) / bpfo_order
    times = np.interp(impacts[impacts < theta[-1]], theta, t)
    pulses = np.zeros(n)
    pulses[(times * FS).astype(int)] = amplitude * rng.uniform(0.8, 1.2, times.size)
    r = np.arange(400) / FS
    x = rng.standard_normal(n) + np.convolve(pulses, np.exp(-r / 1e-3) * np.sin(2 * np.pi * 3200.0 * r))[:n]
    x += sum(2.0 / h * np.cos(h * theta) for h in range(1, 6))
    speed = 60.0 * (f0 + (f1 - f0) * t / seconds)
    return pd.DataFrame({"time_s": t, "accel_g": x, "tacho_V": order.tachometer_signal(theta, 1), "shaft_rpm": speed})


@pytest.fixture(scope="module")
def ramp(tmp_path_factory):
    path = tmp_path_factory.mktemp("ramp") / "ramp.csv"
    ramp_record().to_csv(path, index=False)
    return path


def test_a_fault_under_a_speed_ramp_is_found_by_order_tracking_and_missed_at_a_fixed_speed(ramp):
    tracked = detect_recording(ramp, bearing="SKF 6205", channel="accel_g", tachometer="tacho_V")
    fixed = detect_recording(ramp, bearing="SKF 6205", channel="accel_g", rpm=1200.0)
    assert tracked.detection.fault_type == "outer_race"
    assert fixed.detection.fault_type == "none"  # BPFO sweeps 54-90 Hz: its energy smeared over 36 Hz of bins
    assert tracked.detection.families["outer_race"].margin_dB > fixed.detection.families["outer_race"].margin_dB + 6
    d = tracked.to_dict()
    assert d["order_tracking"]["kind"] == "tachometer"
    assert d["order_tracking"]["min_speed_rpm"] == pytest.approx(900.0, rel=0.02)
    assert d["order_tracking"]["max_speed_rpm"] == pytest.approx(1500.0, rel=0.02)
    assert d["shaft_speed_found_rpm"] == pytest.approx(1200.0, rel=0.01)
    # the line found sits at BPFO's order, not at a frequency
    above = [ln for ln in tracked.detection.families["outer_race"].lines if ln.above]
    assert above and above[0].frequency_Hz == pytest.approx(BEARING.kinematics(1.0).bpfo_Hz, rel=0.03)


def test_order_tracking_at_a_constant_speed_calls_what_the_fixed_speed_detector_calls(tmp_path):
    path = tmp_path / "constant.csv"
    ramp_record(rpm=(1200.0, 1200.0)).to_csv(path, index=False)
    tracked = detect_recording(path, bearing="SKF 6205", channel="accel_g", tachometer="tacho_V")
    fixed = detect_recording(path, bearing="SKF 6205", channel="accel_g", rpm=1200.0)
    assert tracked.detection.fault_type == fixed.detection.fault_type == "outer_race"
    assert tracked.detection.margin_dB == pytest.approx(fixed.detection.margin_dB, abs=3.0)


def test_a_speed_rpm_column_order_tracks_the_record_without_an_option(tmp_path):
    path = tmp_path / "speed.csv"
    ramp_record().rename(columns={"shaft_rpm": "speed_rpm"}).drop(columns="tacho_V").to_csv(path, index=False)
    result = detect_recording(path, bearing="SKF 6205", channel="accel_g", rpm=1200.0)
    assert result.tracking["kind"] == "speed channel" and result.tracking["channel"] == "speed_rpm"
    assert result.detection.fault_type == "outer_race"


def test_the_command_order_tracks_with_the_tachometer_option(ramp, tmp_path):
    out = tmp_path / "out"
    code = main(["detect", str(ramp), "--bearing", "SKF 6205", "--channel", "accel_g", "--tachometer", "tacho_V",
                 "--out", str(out)])
    assert code == 0
    d = json.loads((out / "detection.json").read_text())
    assert d["fault_type"] == "outer_race" and d["order_tracking"]["channel"] == "tacho_V"
    assert "order-tracked from the tachometer `tacho_V`" in (out / "report.md").read_text()


def _with(frame: pd.DataFrame, tmp_path, **columns) -> str:
    path = tmp_path / "bad.csv"
    frame.assign(**columns).to_csv(path, index=False)
    return str(path)


@pytest.mark.parametrize("case, match", [
    ("constant", r"tachometer tacho_V is constant \(5\): no pulses"),
    ("noise", r"tachometer tacho_V: the interval after pulse \d+ .* times the one before"),
    ("few", r"tachometer tacho_V holds 2 pulses; order tracking needs at least 4"),
])
def test_a_bad_tachometer_channel_is_one_line(tmp_path, case, match):
    frame = ramp_record(seconds=2.0)
    n = len(frame)
    tacho = {"constant": np.full(n, 5.0),
             "noise": np.random.default_rng(0).standard_normal(n),
             "few": np.where((np.arange(n) // 6000) % 2 == 1, 5.0, 0.0)}[case]
    path = _with(frame, tmp_path, tacho_V=tacho)
    with pytest.raises(RigError, match=match) as e:
        detect_recording(path, bearing="SKF 6205", channel="accel_g", tachometer="tacho_V")
    assert "\n" not in str(e.value)


def test_a_bad_speed_channel_or_option_is_one_line(tmp_path):
    frame = ramp_record(seconds=2.0)
    speed = frame["shaft_rpm"].to_numpy().copy()
    speed[100] = 0.0
    path = _with(frame, tmp_path, shaft_rpm=speed)
    with pytest.raises(RigError, match=r"speed channel shaft_rpm, sample 101: 0 rpm; order tracking needs a positive"):
        detect_recording(path, bearing="SKF 6205", channel="accel_g", speed_channel="shaft_rpm")
    with pytest.raises(MeasurementError, match=r"channel 'tach' not found"):
        detect_recording(path, bearing="SKF 6205", channel="accel_g", tachometer="tach")
    with pytest.raises(RigError, match=r"--pulses-per-rev = 0; give the tachometer's pulses per revolution"):
        detect_recording(path, bearing="SKF 6205", channel="accel_g", tachometer="tacho_V", pulses_per_rev=0)
    with pytest.raises(RigError, match=r"both a tachometer \(tacho_V\) and a speed channel"):
        detect_recording(path, bearing="SKF 6205", channel="accel_g", tachometer="tacho_V", speed_channel="shaft_rpm")
    with pytest.raises(RigError, match=r"the tachometer accel_g is the channel analysed"):
        detect_recording(path, bearing="SKF 6205", channel="accel_g", tachometer="accel_g")
