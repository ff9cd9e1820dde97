"""``piezobearing detect`` on real CWRU records (tests/data/cwru/, cropped to 5 s) and the record readers as
DAQs write files: MATLAB v5/v7.3 without a time vector, a scalar RPM, a channel by suffix, CSV, WAV."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from scipy.io import loadmat, savemat, wavfile

from piezobearing import cli
from piezobearing.io import MeasurementError, read_bearing_record
from piezobearing.io.vibration import read_vibration_record
from piezobearing.stages.recording import RigError, detect_recording

DATA = Path(__file__).parent / "data" / "cwru"
TRUTH = {"fe37": "inner_race", "fe39": "none", "fe44": "outer_race"}


@pytest.mark.parametrize("name", sorted(TRUTH))
def test_detect_calls_the_real_records_right_and_writes_the_report(name, tmp_path, capsys):
    out = tmp_path / name
    code = cli.main(["detect", str(DATA / f"{name}.mat"), "--config", str(DATA / f"{name}.yaml"), "--out", str(out)])
    assert code == 0
    d = json.loads((out / "detection.json").read_text())
    assert d["fault_type"] == TRUTH[name]
    assert set(d["families"]) == {"outer_race", "inner_race", "rolling_element"}
    assert d["false_alarm_probability"] == pytest.approx(1e-3)
    assert 1785 < d["shaft_speed_found_rpm"] < 1800  # the rig file says 1797 (nominal)
    assert d["details"]["shaft"]["refined"]
    low, high = d["band_Hz"]
    assert 0 < low < high <= 6000
    report = (out / "report.md").read_text()
    assert (out / "detection.png").stat().st_size > 10_000 and "detection.png" in report
    said = capsys.readouterr().out
    if TRUTH[name] == "none":
        assert "no fault signature found" in said and "no fault signature found" in report
        assert all(not f["detected"] for f in d["families"].values())
    else:
        called = d["families"][TRUTH[name]]
        assert called["detected"] and called["margin_dB"] > 3.0
        assert sum(line["above"] for line in called["lines"]) >= 2  # harmonics, not one line


def test_options_override_the_rig_file_and_the_speed_comes_from_the_record(tmp_path):
    """No rig file: the bearing by designation, the rate by --fs, the channel by suffix, the speed from X744RPM."""
    result = detect_recording(DATA / "fe44.mat", bearing="SKF 6203", fs=12000.0, channel="_FE_time")
    assert result.record.channel == "X744_FE_time" and result.speed_rpm == 1797.0
    assert "RPM variable" in result.speed_source and result.detection.fault_type == "outer_race"
    other = detect_recording(DATA / "fe44.mat", DATA / "fe44.yaml", rpm=1750.0)
    assert other.speed_rpm == 1750.0 and other.speed_source == "--rpm"


@pytest.mark.parametrize(
    "args, message",
    [
        (["--bearing", "SKF 6203", "--channel", "_FE_time"], "no time axis in the file and no sampling rate given; give --fs HZ"),
        (["--bearing", "SKF 6203", "--fs", "12000"], "holds 2 channels (X739_DE_time, X739_FE_time) and scalar fields (X739RPM = 1797); choose one with --channel"),
        (["--fs", "12000", "--channel", "FE_time"], "no bearing given; give --bearing DESIGNATION"),
        (["--bearing", "SKF 9999", "--fs", "12000", "--channel", "FE_time"], "'SKF 9999' not in the table"),
        (["--bearing", "SKF 6203", "--fs", "12000", "--channel", "_XX_time"], "channel '_XX_time' not found"),
    ],
)
def test_what_is_missing_stops_with_one_line_naming_it(args, message, tmp_path, capsys):
    code = cli.main(["detect", str(DATA / "fe39.mat"), "--out", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == cli.EXIT_USER
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def _cwru_channels() -> tuple[np.ndarray, np.ndarray]:
    variables = loadmat(DATA / "fe44.mat")
    return variables["X744_FE_time"].ravel(), variables["X744_DE_time"].ravel()


def test_matlab_v73_csv_and_wav_give_the_same_samples(tmp_path):
    fe, de = _cwru_channels()
    with h5py.File(tmp_path / "r.mat", "w") as f:  # MATLAB v7.3 is HDF5; an n x 1 column is stored as (1, n)
        f["X744_FE_time"] = fe[None, :]
        f["X744_DE_time"] = de[None, :]
        f["X744RPM"] = np.array([[1797.0]])
    v73 = read_vibration_record(tmp_path / "r.mat", "FE_time", 12000.0)
    assert v73.speed_rpm == 1797.0 and np.array_equal(v73.samples, fe)
    v5 = tmp_path / "v5.mat"
    savemat(v5, {"acc": np.column_stack([fe, de]), "sample_rate_Hz": 12000.0})  # a matrix: acc[0], acc[1]
    assert np.array_equal(read_vibration_record(v5, "acc[1]").samples, de)
    t = np.arange(fe.size) / 12000.0
    np.savetxt(tmp_path / "r.csv", np.column_stack([t, fe]), delimiter=",", header="time_s,acc_g", comments="",
               fmt="%.10g")
    csv = read_vibration_record(tmp_path / "r.csv")
    assert csv.sample_rate_Hz == pytest.approx(12000.0, rel=1e-6) and np.allclose(csv.samples, fe, rtol=1e-9)
    wavfile.write(tmp_path / "r.wav", 12000, fe.astype(np.float32))
    wav = read_vibration_record(tmp_path / "r.wav")
    assert wav.sample_rate_Hz == 12000.0 and np.allclose(wav.samples, fe, rtol=1e-6)
    with pytest.raises(MeasurementError, match="time axis says 12000 Hz, the rate given is 48000 Hz"):
        read_vibration_record(tmp_path / "r.wav", sample_rate_Hz=48000.0)


def test_a_short_or_dead_record_and_a_bad_rig_file_are_refused(tmp_path):
    savemat(tmp_path / "short.mat", {"x": np.random.default_rng(0).standard_normal(1000)})
    with pytest.raises(MeasurementError, match="at least 0.5 s: record longer"):
        read_vibration_record(tmp_path / "short.mat", sample_rate_Hz=12000.0)
    savemat(tmp_path / "dead.mat", {"x": np.zeros(12000)})
    with pytest.raises(MeasurementError, match="constant .* a dead channel"):
        read_vibration_record(tmp_path / "dead.mat", sample_rate_Hz=12000.0)
    rig = tmp_path / "rig.yaml"
    rig.write_text("bearing: {designation: SKF 6203}\nshaft_speed: 1797\n")
    with pytest.raises(RigError, match="key 'shaft_speed' unknown; a rig file holds bearing, shaft_speed_rpm"):
        detect_recording(DATA / "fe39.mat", rig)


def test_a_running_bearing_record_names_its_channel_by_a_suffix(tmp_path):
    fe, de = _cwru_channels()
    savemat(tmp_path / "r.mat", {"X744_FE_time": fe, "X744_DE_time": de, "sample_rate_Hz": 12000.0})
    record = read_bearing_record(tmp_path / "r.mat", channels={"voltage_V": "_DE_time"})
    assert np.array_equal(record.voltage_V, de) and record.sample_rate_Hz == pytest.approx(12000.0)
