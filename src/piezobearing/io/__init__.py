"""The workflow's file formats, by concern.

- :mod:`piezobearing.io.formats`: record files as DAQs export them (CSV, MATLAB .mat v5/v7.3, UFF58, TDMS,
  WAV) read into their raw columns (:mod:`piezobearing.io.matlab`: MATLAB files as published);
- :mod:`piezobearing.io.records`: calibration and running-bearing records read and checked;
- :mod:`piezobearing.io.results`: result files (JSON, NPZ, CSV tables and time series);
- :mod:`piezobearing.io.vibration`: one channel of a vibration record for fault detection (rate, channel
  and shaft speed as DAQs write them).

Every name a caller uses is importable from ``piezobearing.io`` itself, and is loaded on first use (a module
``__getattr__``, as the package's face): a job that only writes results loads no record reader (h5py, scipy.io,
pyuff, npTDMS).
"""

import importlib

#: Each name and the module that defines it (the workflow's code hash follows an import of a name to its module).
_EXPORTS = {
    "MeasurementError": "piezobearing.io.formats",
    "RECORD_FORMATS": "piezobearing.io.record_formats",
    "RawTable": "piezobearing.io.formats",
    "check_readable": "piezobearing.io.formats",
    "read_table": "piezobearing.io.formats",
    "BEARING_COLUMNS": "piezobearing.io.records",
    "BEARING_OPTIONAL": "piezobearing.io.records",
    "BearingRecord": "piezobearing.io.records",
    "CLIPPED_FRACTION": "piezobearing.io.records",
    "CLIPPED_MIN_SAMPLES": "piezobearing.io.records",
    "CLIP_RUN": "piezobearing.io.records",
    "COLUMNS": "piezobearing.io.records",
    "GAP_FACTOR": "piezobearing.io.records",
    "MEASUREMENT_CSV_FORMAT": "piezobearing.io.records",
    "MIN_BEARING_DURATION_S": "piezobearing.io.records",
    "MIN_BEARING_RATE_HZ": "piezobearing.io.records",
    "MIN_SAMPLE_RATE_HZ": "piezobearing.io.records",
    "Measurement": "piezobearing.io.records",
    "Record": "piezobearing.io.records",
    "UNIFORM_RTOL": "piezobearing.io.records",
    "average_blocks": "piezobearing.io.records",
    "check_channels": "piezobearing.io.records",
    "clipping_runs": "piezobearing.io.records",
    "file_digest": "piezobearing.io.records",
    "gap_filled": "piezobearing.io.records",
    "measurement_as_read": "piezobearing.io.records",
    "read_bearing_record": "piezobearing.io.records",
    "read_measurement": "piezobearing.io.records",
    "write_bearing_record": "piezobearing.io.records",
    "write_measurement": "piezobearing.io.records",
    "CSV_FORMAT": "piezobearing.io.results",
    "FORCE_CSV_FORMAT": "piezobearing.io.results",
    "ResultFileError": "piezobearing.io.results",
    "SERIES_UNIFORM_RTOL": "piezobearing.io.results",
    "SignalFileError": "piezobearing.io.results",
    "as_read": "piezobearing.io.results",
    "json_as_read": "piezobearing.io.results",
    "kinematics_of": "piezobearing.io.results",
    "read_harmonic": "piezobearing.io.results",
    "read_json": "piezobearing.io.results",
    "read_kinematics": "piezobearing.io.results",
    "read_npz": "piezobearing.io.results",
    "read_series": "piezobearing.io.results",
    "table_series": "piezobearing.io.results",
    "write_csv": "piezobearing.io.results",
    "write_json": "piezobearing.io.results",
    "write_npz": "piezobearing.io.results",
    "VibrationRecord": "piezobearing.io.vibration",
    "read_vibration_record": "piezobearing.io.vibration",
    "record_rpm": "piezobearing.io.vibration",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
