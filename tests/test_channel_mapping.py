"""`calibration.channels` for every row of the formats table (docs/reference/records.md, "Calibration records"):
a calibration record written by each format's own library under the channel names a DAQ gives it, read through
the workflow's calibration loader with the config naming those channels, gives back the record."""

import copy

import numpy as np
import pandas as pd
import pytest
from scipy.io import savemat, wavfile
from test_records import write_tdms, write_uff, write_v73

from piezobearing.io import MeasurementError, read_measurement
from piezobearing.stages.calibration import load_record


def _write_csv(path, m):
    pd.DataFrame({"t": m.time_s, "F": m.force_N, "V": m.voltage_V}).to_csv(path, index=False)
    return {"time_s": "t", "force_N": "F", "voltage_V": "V"}


def _write_mat_v5(path, m):
    savemat(path, {"t": m.time_s[:, None], "daq": np.c_[m.voltage_V, m.force_N]})
    return {"time_s": "t", "force_N": "daq[1]", "voltage_V": "daq[0]"}


def _write_mat_v73(path, m):
    write_v73(path, {"t": m.time_s, "F": m.force_N, "V": m.voltage_V})
    return {"time_s": "t", "force_N": "F", "voltage_V": "V"}


def _write_uff(path, m):
    write_uff(path, m.time_s, {"load cell": m.force_N, "pzt": m.voltage_V})
    return {"force_N": "load cell", "voltage_V": "pzt"}


def _write_tdms(path, m):
    write_tdms(path, m.dt_s, {"ai0": m.voltage_V, "ai1": m.force_N})
    return {"force_N": "Dev1/ai1", "voltage_V": "Dev1/ai0"}


def _write_wav(path, m):
    wavfile.write(path, round(1 / m.dt_s), np.c_[m.force_N, m.voltage_V].astype(np.float32))
    return {"force_N": "0", "voltage_V": "1"}


#: One row of the formats table each: file name, writer (returns the channels the config names), tolerance.
ROWS = [
    ("cal.csv", _write_csv, 1e-12),
    ("cal_v5.mat", _write_mat_v5, 1e-12),
    ("cal_v73.mat", _write_mat_v73, 1e-12),
    ("cal.uff", _write_uff, 1e-9),
    ("cal.tdms", _write_tdms, 1e-12),
    ("cal.wav", _write_wav, 1e-6),  # float32 samples
]


@pytest.mark.parametrize("name, write, rtol", ROWS, ids=[r[0] for r in ROWS])
def test_calibration_channels_name_the_columns_of_every_format(tmp_path, paper_record, paper_config, name, write,
                                                               rtol):
    m = paper_record
    config = copy.deepcopy(paper_config)
    config["calibration"]["channels"] = write(tmp_path / name, m)
    got, impulses = load_record(str(tmp_path / name), config)
    assert len(impulses) == 13
    scale = np.abs(m.voltage_V).max()
    np.testing.assert_allclose(got.voltage_V, m.voltage_V, rtol=0, atol=rtol * scale)
    np.testing.assert_allclose(got.force_N, m.force_N, rtol=0, atol=rtol * np.abs(m.force_N).max())
    np.testing.assert_allclose(got.time_s - got.time_s[0], m.time_s - m.time_s[0], rtol=0, atol=1e-9)


def test_a_csv_column_named_in_the_config_but_not_in_the_header_is_named_with_its_key(tmp_path, paper_record):
    _write_csv(tmp_path / "cal.csv", paper_record)
    with pytest.raises(MeasurementError) as e:
        read_measurement(tmp_path / "cal.csv", channels={"time_s": "t", "force_N": "Force", "voltage_V": "V"})
    msg = str(e.value)
    assert "\n" not in msg
    assert "column 'Force' (calibration.channels.force_N) missing (header has: t, F, V)" in msg


def test_a_csv_without_channels_names_the_config_key_that_maps_them(tmp_path, paper_record):
    _write_csv(tmp_path / "cal.csv", paper_record)
    with pytest.raises(MeasurementError, match=r"column 'time_s' missing \(header has: t, F, V\).*calibration\.channels"):
        read_measurement(tmp_path / "cal.csv")


def test_csv_channels_with_a_bad_cell_still_name_the_place(tmp_path, paper_record):
    """The slow path (a cell that is no number) maps the columns the same way and names the line."""
    m = paper_record
    df = pd.DataFrame({"t": m.time_s, "F": m.force_N, "V": m.voltage_V.astype(object)})
    df.loc[41, "V"] = "1,2"
    df.to_csv(tmp_path / "cal.csv", index=False)
    with pytest.raises(MeasurementError, match=r"line 43, column voltage_V: '1,2'"):
        read_measurement(tmp_path / "cal.csv", channels={"time_s": "t", "force_N": "F", "voltage_V": "V"})
