"""A user's calibration CSV: every problem gets one line naming the file, the place and the fix."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import dry_run_errors

from piezobearing.io import MeasurementError, read_measurement
from piezobearing.stages.calibration import load_record


@pytest.fixture()
def good(paper_record) -> pd.DataFrame:
    return paper_record.to_frame()


def write(df: pd.DataFrame, tmp_path: Path, name="m.csv") -> Path:
    p = tmp_path / name
    df.to_csv(p, index=False)
    return p


def expect(path, config, *fragments):
    with pytest.raises(MeasurementError) as e:
        load_record(str(path), config)
    msg = str(e.value)
    assert "\n" not in msg
    assert str(path) in msg
    for f in fragments:
        assert f in msg, msg
    return msg


def test_good_file_is_read_unchanged(good, tmp_path, paper_config):
    p = write(good, tmp_path)
    before = p.read_bytes()
    m, imps = load_record(str(p), paper_config)
    assert len(imps) == 13
    np.testing.assert_allclose(m.voltage_V, good["voltage_V"])
    assert p.read_bytes() == before


def test_missing_file(tmp_path, paper_config):
    expect(tmp_path / "nope.csv", paper_config, "file not found")


def test_misnamed_column(good, tmp_path, paper_config):
    p = write(good.rename(columns={"force_N": "force"}), tmp_path)
    expect(p, paper_config, "column 'force_N' missing", "time_s,force_N,voltage_V")


def test_missing_column(good, tmp_path, paper_config):
    expect(write(good.drop(columns="voltage_V"), tmp_path), paper_config, "'voltage_V' missing")


def test_non_numeric_cell_names_line_and_column(good, tmp_path, paper_config):
    df = good.astype({"voltage_V": object})
    df.loc[41, "voltage_V"] = "1,2"
    expect(write(df, tmp_path), paper_config, "line 43", "column voltage_V", "'1,2'")


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_and_inf(good, tmp_path, paper_config, bad):
    df = good.copy()
    df.loc[10, "force_N"] = bad
    expect(write(df, tmp_path), paper_config, "line 12", "column force_N", "not a finite number")


@pytest.mark.parametrize("cell", ["nan", "NaN", "NA", "inf"])
def test_cell_written_as_nan_is_quoted_not_called_empty(good, tmp_path, paper_config, cell):
    df = good.astype({"voltage_V": object})
    df.loc[20, "voltage_V"] = cell
    msg = expect(write(df, tmp_path), paper_config, "line 22", "column voltage_V", f"'{cell}' is not a finite")
    assert "empty" not in msg


@pytest.mark.parametrize("sep", [";", "\t"])
def test_other_separator_is_named(good, tmp_path, paper_config, sep):
    p = tmp_path / "m.csv"
    good.to_csv(p, index=False, sep=sep)
    expect(p, paper_config, f"separated by {sep!r}", "comma-separated", "time_s,force_N,voltage_V")


def test_non_monotonic_time(good, tmp_path, paper_config):
    df = good.copy()
    df.loc[100, "time_s"] = df.loc[98, "time_s"]
    expect(write(df, tmp_path), paper_config, "line 102", "time does not increase", "sort")


def test_uneven_time_step_stops_unless_resampling_asked(good, tmp_path, paper_config):
    df = good.drop(index=range(500, 505)).reset_index(drop=True)  # a gap of 6 ms in a 1 ms clock
    p = write(df, tmp_path)
    expect(p, paper_config, "line 502", "uneven time step", "resample_to_uniform: true")
    cfg = {**paper_config, "calibration": {**paper_config["calibration"], "resample_to_uniform": True}}
    m, _ = load_record(str(p), cfg)
    assert np.allclose(np.diff(m.time_s), 1e-3)


def test_time_in_milliseconds_is_caught(good, tmp_path, paper_config):
    df = good.copy()
    df["time_s"] = 1e3 * df["time_s"]  # a 1 kHz record written in ms reads as 1 Hz
    expect(write(df, tmp_path), paper_config, "column time_s", "milliseconds", "seconds")


def test_fewer_than_two_impulses(good, tmp_path, paper_config):
    df = good[good["time_s"] < 1.8]  # only the first press
    expect(write(df, tmp_path), paper_config, "1 impulse(s) found", "at least 2")


def test_inverted_polarity_is_reported_not_fitted(good, tmp_path, paper_config):
    df = good.copy()
    df["voltage_V"] = -df["voltage_V"]
    expect(write(df, tmp_path), paper_config, "polarity inverted", "swap the electrode leads")


def test_release_faster_than_press_is_not_called_inverted(paper_config, tmp_path):
    # A fast release makes the negative swing the larger one; the polarity is still right.
    from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
    from piezobearing.stages.calibration import nominal_circuit

    syn = {**paper_config["synthesis"], "fall_time_s": [0.10, 0.15]}
    m = synthesize(PressProtocol.from_config(syn), nominal_circuit(paper_config), 3)
    _, imps = load_record(str(write(m.to_frame(), tmp_path)), paper_config)
    assert len(imps) == 13
    assert all(-m.voltage_V[i.start : i.stop].min() > m.voltage_V[i.start : i.stop].max() for i in imps)


def test_header_only_and_garbage(tmp_path, paper_config):
    p = tmp_path / "empty.csv"
    p.write_text("time_s,force_N,voltage_V\n")
    expect(p, paper_config, "data rows")
    q = tmp_path / "bin.csv"
    q.write_bytes(b"\xff\xfe\x00\x01garbage")
    with pytest.raises(MeasurementError):
        read_measurement(q)


def test_workflow_stops_with_one_line_and_no_traceback(good, tmp_path):
    df = good.rename(columns={"voltage_V": "volts"})
    p = write(df, tmp_path)
    cfg = tmp_path / "user.yaml"
    cfg.write_text(f"calibration:\n  measurement: {p}\n")
    out, err = dry_run_errors(cfg)
    assert out.returncode != 0
    assert len(err) == 1 and "column 'voltage_V' missing" in err[0]
    assert "Traceback" not in out.stderr + out.stdout
