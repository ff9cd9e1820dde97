"""Records as DAQs export them: one reader for CSV, MATLAB v5 and v7.3, UFF58, TDMS and WAV.

Each format is written with its own library and read back; the running-bearing record's checks
(uniform clock from 2 kHz, at least 0.5 s, gaps, clipping) name the file, the place and the fix.
"""

from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
import pyuff
from nptdms import ChannelObject, TdmsWriter
from scipy.io import savemat, wavfile

from piezobearing.io import MeasurementError, read_bearing_record, read_measurement
from piezobearing.stages.calibration import load_record

FS = 2560.0


def bearing_signal(n=int(FS), fs=FS):
    t = np.arange(n) / fs
    v = 2.0 * np.sin(2 * np.pi * 70.8 * t) + 0.3 * np.sin(2 * np.pi * 141.6 * t + 0.4)
    rpm = np.full(n, 1000.0)
    return t, v, rpm


def write_v73(path: Path, arrays: dict) -> None:
    """A MATLAB v7.3 file as MATLAB writes it: HDF5 with a 512-byte header, column vectors stored as (1, n)."""
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, a in arrays.items():
            d = f.create_dataset(name, data=np.atleast_2d(np.asarray(a, dtype=float)))
            d.attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Sun Nov 22 00:00:00 2026 HDF5 schema 1.00 .")


def write_uff(path: Path, t, channels: dict) -> None:
    """One dataset 58 (time response, double precision) per channel, its name in ID line 1."""
    zero_units = {
        f"{axis}_{k}": 0
        for axis in ("ordinate", "orddenom", "z_axis")
        for k in ("spec_data_type", "len_unit_exp", "force_unit_exp", "temp_unit_exp")
    }
    sets = [
        pyuff.prepare_58(
            binary=0, id1=name, id2="", id3="", id4="", id5="", func_type=1, ver_num=0, load_case_id=0,
            rsp_ent_name="rig", rsp_node=1 + i, rsp_dir=3, ref_ent_name="rig", ref_node=0, ref_dir=0,
            ord_data_type=4, num_pts=len(t), abscissa_spacing=1, abscissa_min=float(t[0]),
            abscissa_inc=float(t[1] - t[0]), z_axis_value=0.0, abscissa_spec_data_type=17,
            abscissa_len_unit_exp=0, abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0,
            abscissa_axis_units_lab="s", ordinate_axis_units_lab="", orddenom_axis_units_lab="",
            z_axis_axis_units_lab="", data=np.asarray(y, dtype=float), x=np.asarray(t, dtype=float), **zero_units,
        )
        for i, (name, y) in enumerate(channels.items())
    ]
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")


def write_tdms(path: Path, dt, channels: dict, group="Dev1") -> None:
    objs = [
        ChannelObject(group, name, np.asarray(y), properties={"wf_increment": dt, "wf_start_offset": 0.0})
        for name, y in channels.items()
    ]
    with TdmsWriter(str(path)) as w:
        w.write_segment(objs)


def test_bearing_record_in_every_format_reads_back_the_same(tmp_path):
    t, v, rpm = bearing_signal()
    pd.DataFrame({"time_s": t, "voltage_V": v, "speed_rpm": rpm}).to_csv(tmp_path / "r.csv", index=False)
    savemat(tmp_path / "r5.mat", {"time_s": t[:, None], "voltage_V": v[:, None], "speed_rpm": rpm[:, None]})
    write_v73(tmp_path / "r73.mat", {"time_s": t, "voltage_V": v, "speed_rpm": rpm})
    write_uff(tmp_path / "r.uff", t, {"voltage_V": v, "speed_rpm": rpm})
    write_tdms(tmp_path / "r.tdms", 1 / FS, {"voltage_V": v, "speed_rpm": rpm})
    wavfile.write(tmp_path / "r.wav", int(FS), v.astype(np.float32))
    for name in ("r.csv", "r5.mat", "r73.mat", "r.uff", "r.tdms", "r.wav"):
        rec = read_bearing_record(tmp_path / name)
        assert rec.sample_rate_Hz == pytest.approx(FS, rel=1e-9), name
        tol = 1e-7 if name == "r.wav" else 1e-12  # float32 WAV
        np.testing.assert_allclose(rec.voltage_V, v, atol=tol * 3, err_msg=name)
        assert rec.warnings == ()
        if name != "r.wav":
            np.testing.assert_allclose(rec.speed_rpm, rpm, err_msg=name)


def test_channels_named_in_the_config(tmp_path):
    t, v, rpm = bearing_signal()
    savemat(tmp_path / "m.mat", {"t": t, "data": np.c_[0 * v, v], "fs_note": 1.0})
    rec = read_bearing_record(tmp_path / "m.mat", channels={"time_s": "t", "voltage_V": "data[1]"})
    np.testing.assert_allclose(rec.voltage_V, v)
    write_tdms(tmp_path / "m.tdms", 1 / FS, {"ai0": v * 0, "ai1": v, "tach": rpm})
    rec = read_bearing_record(tmp_path / "m.tdms", channels={"voltage_V": "Dev1/ai1", "speed_rpm": "tach"})
    np.testing.assert_allclose(rec.voltage_V, v)
    np.testing.assert_allclose(rec.speed_rpm, rpm)
    stereo = np.c_[np.round(v / 4 * 32768), np.zeros_like(v)].astype(np.int16)
    wavfile.write(tmp_path / "m.wav", int(FS), stereo)
    rec = read_bearing_record(tmp_path / "m.wav", channels={"voltage_V": "0"}, wav_full_scale_V=4.0)
    np.testing.assert_allclose(rec.voltage_V, v, atol=2.0 / 32768)


def test_a_missing_channel_lists_what_the_file_holds(tmp_path):
    t, v, _ = bearing_signal()
    write_tdms(tmp_path / "m.tdms", 1 / FS, {"ai0": v, "ai1": v})
    with pytest.raises(MeasurementError) as e:
        read_bearing_record(tmp_path / "m.tdms")
    msg = str(e.value)
    assert "\n" not in msg and "m.tdms" in msg and "Dev1/ai0" in msg and "bearing.channels.voltage_V" in msg
    wavfile.write(tmp_path / "i.wav", int(FS), np.zeros(4000, np.int16))
    with pytest.raises(MeasurementError, match="wav_full_scale_V"):
        read_bearing_record(tmp_path / "i.wav")
    (tmp_path / "x.xlsx").write_bytes(b"PK")
    with pytest.raises(MeasurementError, match="unknown record format '.xlsx'"):
        read_bearing_record(tmp_path / "x.xlsx")
    (tmp_path / "bad.mat").write_bytes(b"not a mat file at all")
    with pytest.raises(MeasurementError, match="not a readable MATLAB"):
        read_bearing_record(tmp_path / "bad.mat")


def test_calibration_record_through_the_same_reader(paper_record, paper_config, tmp_path):
    m = paper_record
    savemat(tmp_path / "cal.mat", {"t": m.time_s, "F": m.force_N, "V": m.voltage_V})
    cfg = {**paper_config, "calibration": {**paper_config["calibration"], "channels": {"time_s": "t", "force_N": "F", "voltage_V": "V"}}}
    got, imps = load_record(str(tmp_path / "cal.mat"), cfg)
    assert len(imps) == 13
    np.testing.assert_allclose(got.voltage_V, m.voltage_V)
    bad = m.voltage_V.copy()
    bad[40] = np.nan
    write_tdms(tmp_path / "cal.tdms", m.dt_s, {"force_N": m.force_N, "voltage_V": bad})
    with pytest.raises(MeasurementError) as e:
        read_measurement(tmp_path / "cal.tdms")
    assert "sample 41, column voltage_V" in str(e.value) and "not a finite number" in str(e.value)


def bad(tmp_path, df, *fragments):
    p = tmp_path / "rig.csv"
    df.to_csv(p, index=False)
    with pytest.raises(MeasurementError) as e:
        read_bearing_record(p)
    msg = str(e.value)
    assert "\n" not in msg and str(p) in msg, msg
    for f in fragments:
        assert f in msg, msg


def test_bearing_record_checks_name_place_and_fix(tmp_path):
    t, v, rpm = bearing_signal()
    df = pd.DataFrame({"time_s": t, "voltage_V": v, "speed_rpm": rpm})
    bad(tmp_path, df.drop(columns="voltage_V"), "column 'voltage_V' missing", "time_s,voltage_V[,speed_rpm]")
    bad(tmp_path, df.drop(index=range(1000, 1010)), "line 1002", "gap of", "10 samples lost")
    slow = pd.DataFrame({"time_s": np.arange(2000) / 1000.0, "voltage_V": np.sin(np.arange(2000))})
    bad(tmp_path, slow, "1000 Hz", "at least 2000 Hz")
    bad(tmp_path, df.iloc[:1000], "0.391 s recorded", "at least 0.5 s")
    ms = df.assign(time_s=1e3 * df.time_s)
    bad(tmp_path, ms, "milliseconds")
    d2 = df.copy()
    d2.loc[7, "speed_rpm"] = -3.0
    bad(tmp_path, d2, "line 9", "column speed_rpm", "positive")
    d3 = df.astype({"voltage_V": object})
    d3.loc[99, "voltage_V"] = "1,5"
    bad(tmp_path, d3, "line 101", "column voltage_V", "'1,5'")
    jit = df.copy()
    jit.loc[500:, "time_s"] += 0.2 / FS
    bad(tmp_path, jit, "line 502", "uneven time step")


def test_clipping_is_reported_with_its_place_not_refused(tmp_path):
    t, v, _ = bearing_signal()
    clipped = np.clip(v, -10, 1.9)
    p = tmp_path / "rig.csv"
    pd.DataFrame({"time_s": t, "voltage_V": clipped}).to_csv(p, index=False)
    rec = read_bearing_record(p)
    assert rec.speed_rpm is None
    assert len(rec.warnings) == 1 and "clipped at 1.9 V" in rec.warnings[0] and "line " in rec.warnings[0]
    at = clipped == 1.9
    assert np.all(rec.voltage_V[rec.clipped] == 1.9)  # only samples at the clipping level
    assert 0.9 * at.sum() <= rec.clipped.sum() <= at.sum()  # all but runs shorter than 3 samples
