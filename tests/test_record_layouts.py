"""Records as published: MATLAB v5 (written by scipy.io as MATLAB writes it) and v7.3 (HDF5 with MATLAB's
userblock, ``MATLAB_class`` attributes and object references into ``#refs#``) holding structs, nested structs,
struct arrays and cell arrays of channels with their names, rates and speeds in integer, float and text
fields, column vectors and a DC offset; each layout read by its MATLAB path and detected as the flat file is."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
from scipy.io import loadmat, savemat

from piezobearing import cli
from piezobearing.io import MeasurementError
from piezobearing.io.matlab import mat_contents
from piezobearing.io.vibration import read_record_contents, read_vibration_record
from piezobearing.stages.recording import Rig, detect_recording, read_rig

DATA = Path(__file__).parent / "data" / "cwru"
RATE = 12000
#: fe44's shaft speed as the rig file states it [rpm], and in revolutions per second [Hz].
RPM = 1797.0


# --------------------------------------------------------------------------- files as MATLAB writes them


class StructArray(list):
    """A MATLAB struct array (1 x n), each element a dict of the same fields."""


def _matlab_header(path: Path) -> None:
    """MATLAB's 512-byte userblock of a v7.3 file: 116 bytes of text, the subsystem offset, version, endian."""
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 ."
    with open(path, "r+b") as f:
        f.write(text.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM")


def _put(parent, refs, name: str, value, counter) -> h5py.HLObject:
    """Write ``value`` as MATLAB does under ``parent[name]`` (arrays transposed: MATLAB is column-major)."""
    if isinstance(value, dict):
        g = parent.create_group(name)
        g.attrs["MATLAB_class"] = np.bytes_("struct")
        names = np.empty(len(value), dtype=object)
        names[:] = [np.frombuffer(k.encode(), dtype="S1") for k in value]
        g.attrs.create("MATLAB_fields", names, dtype=h5py.vlen_dtype(np.dtype("S1")))
        for k, v in value.items():
            _put(g, refs, k, v, counter)
        return g
    if isinstance(value, StructArray):
        g = parent.create_group(name)
        g.attrs["MATLAB_class"] = np.bytes_("struct")
        for k in value[0]:
            targets = [_put(refs, refs, f"{next(counter):x}", element[k], counter).ref for element in value]
            g.create_dataset(k, data=np.array(targets, dtype=h5py.ref_dtype).reshape(len(value), 1))
        return g
    if isinstance(value, list):  # a 1 x n cell array
        targets = [_put(refs, refs, f"{next(counter):x}", v, counter).ref for v in value]
        d = parent.create_dataset(name, data=np.array(targets, dtype=h5py.ref_dtype).reshape(len(value), 1))
        d.attrs["MATLAB_class"] = np.bytes_("cell")
        return d
    if isinstance(value, str):
        d = parent.create_dataset(name, data=np.array([[ord(c)] for c in value], dtype=np.uint16))
        d.attrs["MATLAB_class"] = np.bytes_("char")
        d.attrs["MATLAB_int_decode"] = np.int32(2)
        return d
    a = np.atleast_2d(np.asarray(value))
    d = parent.create_dataset(name, data=a.T)
    d.attrs["MATLAB_class"] = np.bytes_({"float64": "double", "float32": "single"}.get(a.dtype.name, a.dtype.name))
    return d


def write_v73(path: Path, variables: dict) -> None:
    """A MATLAB v7.3 file of ``variables`` (dict: struct, StructArray, list: cell, str: char, arrays)."""
    counter = itertools.count()
    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")
        for name, value in variables.items():
            _put(f, refs, name, value, counter)
    _matlab_header(path)


def _v5(value):
    """``value`` as scipy.io.savemat writes MATLAB's classes: dict a struct, StructArray a struct array, list a
    cell array, str a char array."""
    if isinstance(value, StructArray):
        fields = list(value[0])
        a = np.empty((1, len(value)), dtype=[(k, object) for k in fields])
        for i, element in enumerate(value):
            for k in fields:
                a[0, i][k] = _v5(element[k])
        return a
    if isinstance(value, dict):
        return {k: _v5(v) for k, v in value.items()}
    if isinstance(value, list):
        a = np.empty((1, len(value)), dtype=object)
        for i, v in enumerate(value):
            a[0, i] = _v5(v)
        return a
    return value


def write_v5(path: Path, variables: dict) -> None:
    savemat(path, {k: _v5(v) for k, v in variables.items()}, oned_as="column")


WRITERS = {"v5": write_v5, "v7.3": write_v73}


@pytest.fixture(scope="module")
def cwru():
    """fe44 (outer-race fault, 5 s at 12 kHz): its fan-end and drive-end channels as columns."""
    v = loadmat(DATA / "fe44.mat")
    return v["X744_FE_time"], v["X744_DE_time"]


def _published(fe: np.ndarray, de: np.ndarray) -> dict:
    """A second rig's layout: the signal, its rate (an integer), the shaft speed [Hz] and the load in a struct;
    the record with a DC offset, as a DAQ without AC coupling writes it."""
    return {"bearing": {"gs": fe + 2.5, "sr": np.int32(RATE), "rate": RPM / 60.0, "load": 0.0, "unit": "g"},
            "drive_end": {"gs": de}}


# --------------------------------------------------------------------------- each layout, read as written


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_a_nested_struct_is_read_by_its_dotted_path_with_its_rate_and_speed_in_fields(version, cwru, tmp_path):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    WRITERS[version](path, _published(fe, de))
    rec = read_vibration_record(path, "bearing.gs", "bearing.sr")
    assert np.array_equal(rec.samples, fe.ravel() + 2.5)
    assert rec.sample_rate_Hz == RATE and rec.rate_source == "field bearing.sr" and rec.channel == "bearing.gs"
    held = read_record_contents(path)
    assert held.kind == f"MATLAB {version}"
    assert held.scalars == {"bearing.sr": RATE, "bearing.rate": pytest.approx(RPM / 60.0, rel=1e-15),
                            "bearing.load": 0.0}
    assert held.texts == {"bearing.unit": "g"}
    assert set(held.channels) == {"bearing.gs", "drive_end.gs"}


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_the_published_layout_is_detected_as_the_flat_file_is(version, cwru, tmp_path):
    """The rig file names the fields (sample_rate_Hz: bearing.sr, shaft_speed_Hz: bearing.rate); the DC offset
    changes nothing the detector decides on."""
    fe, de = cwru
    path = tmp_path / "rec.mat"
    WRITERS[version](path, _published(fe, de))
    rig = tmp_path / "rig.yaml"
    rig.write_text("bearing: {designation: SKF 6203}\nchannel: bearing.gs\nsample_rate_Hz: bearing.sr\n"
                   "shaft_speed_Hz: bearing.rate\n")
    got = detect_recording(path, rig)
    flat = detect_recording(DATA / "fe44.mat", DATA / "fe44.yaml")
    assert got.speed_rpm == pytest.approx(RPM, rel=1e-12) and "bearing.rate [Hz]" in got.speed_source
    assert got.detection.fault_type == flat.detection.fault_type == "outer_race"
    for family, e in flat.detection.families.items():
        assert got.detection.families[family].margin_dB == pytest.approx(e.margin_dB, rel=1e-6)


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_a_struct_array_of_channels_is_read_by_name_and_by_path(version, cwru, tmp_path):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    WRITERS[version](path, {"ch": StructArray([{"name": "drive end", "data": de, "fs": float(RATE)},
                                               {"name": "fan end", "data": fe, "fs": float(RATE)}])})
    by_name = read_vibration_record(path, "fan end", "ch(2).fs")
    assert by_name.channel == "ch(2).data" and np.array_equal(by_name.samples, fe.ravel())
    assert np.array_equal(read_vibration_record(path, "ch(1).data", RATE).samples, de.ravel())
    assert read_record_contents(path).names == {"drive end": "ch(1).data", "fan end": "ch(2).data"}


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_a_name_two_channels_share_names_neither(version, cwru, tmp_path):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    WRITERS[version](path, {"ch": StructArray([{"name": "acc", "data": de}, {"name": "acc", "data": fe}])})
    with pytest.raises(MeasurementError, match=r"several channels are named 'acc'; give its path \(ch\(1\).data, "
                       r"ch\(2\).data\)"):
        read_vibration_record(path, "acc", RATE)
    assert np.array_equal(read_vibration_record(path, "ch(2).data", RATE).samples, fe.ravel())


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_a_cell_array_of_channel_structs_and_of_plain_vectors(version, cwru, tmp_path):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    WRITERS[version](path, {"run": {"signals": [{"label": "DE", "values": de.T}, {"label": "FE", "values": fe.T}],
                                    "raw": [de, fe], "fs": "12000"}})
    rec = read_vibration_record(path, "FE", "run.fs")  # a row vector; the rate as text
    assert rec.channel == "run.signals{2}.values" and rec.sample_rate_Hz == RATE
    assert np.array_equal(rec.samples, fe.ravel())
    assert np.array_equal(read_vibration_record(path, "run.raw{1}", RATE).samples, de.ravel())


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_integer_samples_and_fields_of_every_class(version, tmp_path):
    """An ADC's int16 counts with a mid-scale offset; an int32 rate and a uint16 speed in rpm."""
    counts = (2048 + 400 * np.random.default_rng(1).standard_normal(RATE)).astype(np.int16)
    path = tmp_path / "adc.mat"
    WRITERS[version](path, {"daq": {"counts": counts[:, None], "rate": np.int32(RATE), "rpm": np.uint16(1797)}})
    rec = read_vibration_record(path, "counts", "daq.rate")
    assert rec.samples.dtype == float and np.array_equal(rec.samples, counts.astype(float))
    assert rec.speed_rpm == 1797.0  # a scalar whose name ends in rpm is the speed the file states
    assert mat_contents(path).arrays["daq.rate"].dtype == np.int32


@pytest.mark.parametrize("version", sorted(WRITERS))
def test_a_struct_without_the_channel_asked_for_lists_every_channel_and_field(version, cwru, tmp_path, capsys):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    WRITERS[version](path, _published(fe, de))
    code = cli.main(["detect", str(path), "--bearing", "SKF 6203", "--fs", "bearing.sr", "--channel", "bearing.acc",
                     "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == cli.EXIT_USER and len(err.strip().splitlines()) == 1
    assert (f"{path}: channel 'bearing.acc' not found (the file holds channels bearing.gs [60000], drive_end.gs "
            "[60000]; scalar fields bearing.sr = 12000, bearing.rate = 29.95, bearing.load = 0; text fields "
            "bearing.unit = 'g'); give one of those channels by its path") in err
    assert cli.main(["detect", str(path), "--list"]) == 0
    listing = capsys.readouterr().out
    for line in ("channels (2):", "bearing.gs", "drive_end.gs", "scalar fields (3):", "bearing.sr", "12000",
                 "bearing.rate", "text fields (1):", "bearing.unit"):
        assert line in listing


def test_a_rate_field_that_is_missing_or_text_stops_with_one_line(cwru, tmp_path):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    write_v5(path, {"bearing": {"gs": fe, "sr": "fast", "rate": 29.95}})
    with pytest.raises(MeasurementError, match=r"field 'bearing.sr' \(the sampling rate, --fs or sample_rate_Hz\) "
                       r"holds the text 'fast', not a number"):
        read_vibration_record(path, "bearing.gs", "bearing.sr")
    with pytest.raises(MeasurementError, match=r"field 'bearing.fs' .* not found \(the file holds channels "
                       r"bearing.gs \[60000\]; scalar fields bearing.rate = 29.95; text fields bearing.sr = 'fast'\)"):
        read_vibration_record(path, "bearing.gs", "bearing.fs")
    with pytest.raises(MeasurementError, match="field 'bearing.gs' .* holds 60000 values, not one"):
        read_vibration_record(path, "bearing.gs", "bearing.gs")
    csv = tmp_path / "r.csv"
    np.savetxt(csv, fe[:12000], header="acc", comments="")
    rec = read_vibration_record(csv, sample_rate_Hz=12000.0)
    with pytest.raises(MeasurementError, match="names a field, but a .csv file holds no fields"):
        rec.field_value("bearing.rate", "the shaft speed")


def test_the_rig_file_takes_a_field_or_a_number_and_refuses_both_speed_units(tmp_path):
    rig = tmp_path / "rig.yaml"
    rig.write_text("bearing: {designation: SKF 6203}\nsample_rate_Hz: bearing.sr\nshaft_speed_rpm: '1797'\n")
    assert read_rig(rig) == Rig(read_rig(rig).bearing, 1797.0, "bearing.sr", None, str(rig), None)
    rig.write_text("shaft_speed_rpm: 1797\nshaft_speed_Hz: bearing.rate\n")
    with pytest.raises(ValueError, match="both shaft_speed_rpm and shaft_speed_Hz given"):
        read_rig(rig)
    rig.write_text("sample_rate_Hz: 'twelve k'\n")
    with pytest.raises(ValueError, match="sample_rate_Hz = 'twelve k' is neither a number nor a field's path"):
        read_rig(rig)


def test_detect_writes_the_field_the_speed_came_from(cwru, tmp_path):
    fe, de = cwru
    path = tmp_path / "rec.mat"
    write_v73(path, _published(fe, de))
    out = tmp_path / "out"
    assert cli.main(["detect", str(path), "--bearing", "SKF 6203", "--channel", "bearing.gs", "--fs", "bearing.sr",
                     "--shaft-hz", "bearing.rate", "--out", str(out)]) == 0
    d = json.loads((out / "detection.json").read_text())
    assert d["record"]["channel"] == "bearing.gs" and d["record"]["rate_Hz"] == RATE
    assert d["shaft_speed_given_rpm"] == pytest.approx(RPM, rel=1e-12)
    assert d["shaft_speed_source"] == "--shaft-hz: the record's field bearing.rate [Hz]"


def test_a_csv_header_with_units_in_brackets_is_listed_and_named(cwru, tmp_path, capsys):
    fe, de = cwru
    path = tmp_path / "r.csv"
    pd.DataFrame({"acc (g)": fe.ravel(), "vel (mm/s)": de.ravel()}).to_csv(path, index=False)
    assert cli.main(["detect", str(path), "--list"]) == 0
    assert "acc (g)                          60000 samples" in capsys.readouterr().out
    with pytest.raises(MeasurementError, match=r"holds 2 channels \(acc \(g\), vel \(mm/s\)\); choose one"):
        read_vibration_record(path, sample_rate_Hz=RATE)
    assert np.array_equal(read_vibration_record(path, "acc (g)", RATE).samples, fe.ravel())
