"""A vibration record as a DAQ writes it, for fault detection: one channel, its sampling rate and, where the
file holds one, the shaft speed.

Formats (:data:`piezobearing.io.formats.RECORD_FORMATS`): MATLAB v5 and v7.3 with one variable per channel
and no time vector (CWRU's ``X105_DE_time``, ``X105_FE_time``, a 1 x 1 ``X105RPM``); CSV with a header
(a ``time_s`` column, or none and the rate given); WAV; UFF58; TDMS. The channel is chosen by its name or by
a suffix that only one channel name ends with (``_DE_time``, ``FE_time``); a file with one channel needs
neither. The rate comes from the file's time axis where it has one, else from the caller (``--fs`` or the
rig file's ``sample_rate_Hz``); a scalar variable whose name ends in ``RPM`` is the shaft speed the file
gives. Every problem stops with one line naming the file, what is missing and how to give it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .formats import _BINARY_READERS, RECORD_FORMATS, MeasurementError, check_readable, mat_arrays

#: Shortest record the detector can use [s] (a few revolutions of a slow shaft).
MIN_DURATION_S = 0.5
#: Largest relative difference between a rate given and the file's own time axis.
RATE_RTOL = 0.01


@dataclass(frozen=True)
class VibrationRecord:
    """One channel of a record on a uniform clock.

    Attributes
    ----------
    samples : ndarray
        The channel's samples (the file's unit: g, m/s^2, V).
    rate_Hz : float
        Sampling rate [Hz].
    channel : str
        The channel's name in the file.
    speed_rpm : float or None
        The shaft speed the file holds (a scalar ``*RPM`` variable) [rpm], else None.
    source : str
        The file.
    channels : tuple of str
        Every channel the file holds.
    """

    samples: np.ndarray
    rate_Hz: float
    channel: str
    speed_rpm: float | None
    source: str
    channels: tuple[str, ...]

    @property
    def duration_s(self) -> float:
        return self.samples.size / self.rate_Hz


def pick_channel(path: Path, names: list[str], channel: str | None) -> str:
    """The channel named ``channel`` (exactly, or the only name ending with it), or the only channel."""
    listed = ", ".join(names) or "no channels"
    if channel is None or channel == "":
        if len(names) == 1:
            return names[0]
        raise MeasurementError(
            f"{path}: holds {len(names)} channels ({listed}); choose one with --channel NAME "
            "(or channel: in the rig file; a unique suffix such as _DE_time is enough)"
        )
    if channel in names:
        return channel
    ends = [n for n in names if n.lower().endswith(channel.lower())]
    if len(ends) == 1:
        return ends[0]
    if len(ends) > 1:
        raise MeasurementError(
            f"{path}: {len(ends)} channel names end with '{channel}' ({', '.join(ends)}); give the full name"
        )
    raise MeasurementError(f"{path}: channel '{channel}' not found (the file holds: {listed}); give one of those")


def scalar_rpm(arrays: dict[str, np.ndarray]) -> tuple[float, str] | None:
    """The shaft speed a MATLAB file states: its scalar variable whose name ends in ``RPM`` (any case), as
    (speed [rpm], the variable's name); None where it has none (the first such variable where it has several)."""
    for name, a in arrays.items():
        if a.size == 1 and name.lower().endswith("rpm"):
            return float(a.ravel()[0]), name
    return None


def record_rpm(path: str | Path) -> tuple[float, str] | None:
    """The shaft speed a record file states (:func:`scalar_rpm` of a ``.mat`` file), as (speed [rpm], the
    variable's name); None for a file without one or of another format."""
    path = Path(path)
    if path.suffix.lower() != ".mat" or not path.exists():
        return None
    try:
        arrays = mat_arrays(path)
    except Exception:  # noqa: BLE001 - an unreadable file: the record's reader says why, with its fix
        return None
    return scalar_rpm(arrays)


def _mat_record(path: Path) -> tuple[dict[str, np.ndarray], float | None, float | None]:
    arrays = mat_arrays(path)
    channels, rate = {}, None
    stated = scalar_rpm(arrays)
    rpm = None if stated is None else stated[0]
    for name, a in arrays.items():
        if a.size == 1:
            if name.lower().endswith("rpm"):
                continue
            elif name in ("sample_rate_Hz", "fs", "Fs"):
                rate = float(a.ravel()[0])
            continue
        if 1 in a.shape:
            channels[name] = a.ravel()
        else:
            m = a if a.shape[0] >= a.shape[1] else a.T
            for k in range(m.shape[1]):
                channels[f"{name}[{k}]"] = m[:, k]
    return channels, rate, rpm


def _csv_record(path: Path) -> tuple[dict[str, np.ndarray], float | None]:
    try:
        table = pd.read_csv(path, skipinitialspace=True, encoding="utf-8-sig")
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise MeasurementError(f"{path}: not a readable CSV ({first}); save it as comma-separated text with a "
                               "header naming the channels") from None
    table.columns = [str(c).strip() for c in table.columns]
    rate = None
    if "time_s" in table.columns:
        rate = _rate_of(path, table["time_s"].to_numpy(dtype=float))
    channels = {c: table[c].to_numpy() for c in table.columns if c != "time_s"}
    return channels, rate


def _rate_of(path: Path, time_s: np.ndarray) -> float:
    step = np.diff(time_s)
    if time_s.size < 3 or not np.all(np.isfinite(time_s)) or np.any(step <= 0):
        raise MeasurementError(f"{path}: the time axis is not increasing finite seconds; fix it or leave it out "
                               "and give the rate (--fs HZ)")
    median = float(np.median(step))
    if np.any(np.abs(step - median) > RATE_RTOL * median):
        raise MeasurementError(f"{path}: the time axis is not uniform (steps beyond 1 % of the median "
                               f"{median:g} s); export the record on the DAQ's sample clock")
    return (time_s.size - 1) / float(time_s[-1] - time_s[0])  # the mean step: exact for a written clock


def read_vibration_record(path: str | Path, channel: str | None = None, rate_Hz: float | None = None,
                          key: str = "record") -> VibrationRecord:
    """Read one channel of a record as a DAQ writes it (see the module docstring).

    Parameters
    ----------
    path : path
        The record file.
    channel : str, optional
        The channel's name or a unique suffix of it; None for a file with one channel.
    rate_Hz : float, optional
        The sampling rate [Hz] where the file has no time axis (checked against it where it has one).
    key : str
        What names the record in messages.

    Raises
    ------
    MeasurementError
        One line naming the file, what is missing and how to give it.
    """
    path = Path(path)
    if not path.exists():
        raise MeasurementError(f"{path}: file not found; give the path of the record file")
    ext = path.suffix.lower()
    if ext not in RECORD_FORMATS:
        kinds = ", ".join(f"{e} ({d})" for e, d in RECORD_FORMATS.items())
        raise MeasurementError(f"{path}: unknown record format '{ext or '(no extension)'}'; export it as one of: {kinds}")
    check_readable(path, key, text=ext == ".csv")
    rpm, file_rate = None, None
    try:
        if ext == ".mat":
            found, file_rate, rpm = _mat_record(path)
        elif ext == ".csv":
            found, file_rate = _csv_record(path)
        else:
            raw = _BINARY_READERS[ext](path, {}, 1.0, key)  # WAV: integer samples in full-scale units
            found = {n: c.data for n, c in raw.items() if not n.startswith("__")}
            times = [c.time_s for n, c in raw.items() if c.time_s is not None]
            file_rate = _rate_of(path, np.asarray(times[0], dtype=float)) if times else None
            if ext in (".uff", ".unv"):  # each dataset by its ID line and by its position: name it once
                named = {id(v) for n, v in found.items() if not n.isdigit()}
                found = {n: v for n, v in found.items() if not n.isdigit() or id(v) not in named}
    except MeasurementError:
        raise
    except Exception as e:  # noqa: BLE001 - a library's own error on a damaged file: one line, no traceback
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise MeasurementError(f"{path}: not a readable {RECORD_FORMATS[ext]} file ({first}); export it again") from None
    name = pick_channel(path, list(found), channel)
    samples = pd.to_numeric(pd.Series(np.asarray(found[name]).ravel()), errors="coerce").to_numpy(dtype=float)
    bad = np.flatnonzero(~np.isfinite(samples))
    if bad.size:
        raise MeasurementError(f"{path}: channel {name}, sample {int(bad[0]) + 1}: not a finite number ({bad.size} "
                               "such samples); fix or cut them out of the record")
    if file_rate is not None and rate_Hz is not None and abs(file_rate - rate_Hz) > RATE_RTOL * file_rate:
        raise MeasurementError(f"{path}: the file's time axis says {file_rate:.6g} Hz, the rate given is "
                               f"{rate_Hz:.6g} Hz; give the file's rate or leave --fs out")
    rate = file_rate if file_rate is not None else rate_Hz
    if rate is None:
        raise MeasurementError(f"{path}: no time axis in the file and no sampling rate given; give --fs HZ "
                               "(or sample_rate_Hz: in the rig file)")
    if not rate > 0:
        raise MeasurementError(f"{path}: sampling rate {rate:g} Hz; give the rate in Hz (> 0)")
    if samples.size < MIN_DURATION_S * rate:
        raise MeasurementError(f"{path}: channel {name} holds {samples.size} samples ({samples.size / rate:.3g} s at "
                               f"{rate:g} Hz); fault detection needs at least {MIN_DURATION_S:g} s: record longer")
    if np.all(samples == samples[0]):
        raise MeasurementError(f"{path}: channel {name} is constant ({samples[0]:g}); a dead channel: check the "
                               "sensor and the DAQ channel")
    return VibrationRecord(samples, float(rate), name, rpm, str(path), tuple(found))
