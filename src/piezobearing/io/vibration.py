"""A vibration record as a DAQ writes it, for fault detection: one channel, its sampling rate and, where the
file holds one, the shaft speed.

Formats (:data:`piezobearing.io.record_formats.RECORD_FORMATS`): MATLAB v5 and v7.3 as published, with one variable
per channel (CWRU's ``X105_DE_time``, ``X105_FE_time``, a 1 x 1 ``X105RPM``) or with structs, nested structs,
struct arrays and cell arrays (:mod:`piezobearing.io.matlab`: a channel by its MATLAB path, ``bearing.gs``,
``ch(2).data``, or by the text of its struct's ``name`` field); CSV with a header (a ``time_s`` column, or
none and the rate given); WAV; UFF58; TDMS. The channel is chosen by its name or path, or by a suffix that
only one of them ends with (``_DE_time``, ``FE_time``, ``.gs``); a file with one channel needs neither.

The rate comes from the file's time axis where it has one, else from the caller: a number (``--fs 12000``)
or the path of a scalar field of the file that holds it (``--fs bearing.sr``, an integer or text field too).
A scalar variable whose name ends in ``RPM`` is the shaft speed the file gives. :func:`read_record_contents`
lists what a file holds (``piezobearing detect FILE --list``). Every problem stops with one line naming the
file, what is missing, what the file holds (every channel and scalar field with its path) and how to give it.

pandas (0.2-0.25 s of CPU to import) loads only for a CSV record or a channel of text cells; each binary
format's library loads with its reader (:mod:`piezobearing.io.formats`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .formats import _BINARY_READERS, MeasurementError, check_readable, mat_arrays
from .matlab import mat_contents
from .record_formats import RECORD_FORMATS
from .records import Record

#: Shortest record the detector can use [s] (a few revolutions of a slow shaft).
MIN_DURATION_S = 0.5
#: Largest relative difference between a rate given and the file's own time axis.
RATE_RTOL = 0.01
#: Names of a top-level MATLAB scalar that states the file's sampling rate [Hz].
RATE_VARIABLES = ("sample_rate_Hz", "fs", "Fs")
#: Characters of a text field shown in a listing.
_TEXT_SHOWN = 24


@dataclass(frozen=True)
class RecordContents:
    """What a record file holds, before a channel is chosen.

    Attributes
    ----------
    path : Path
        The file.
    channels : dict
        Channel name or MATLAB path (a matrix's column k as ``path[k]``) -> its samples.
    scalars : dict
        Path -> value of every numeric scalar (MATLAB: variables and fields of any numeric class).
    texts : dict
        Path -> text (MATLAB ``char`` variables and fields).
    names : dict
        A channel's name from its struct's name field -> its path ("" where two channels share it).
    sample_rate_Hz : float or None
        The rate the file states: its time axis, or a top-level scalar of :data:`RATE_VARIABLES` [Hz].
    kind : str
        The format, as :data:`RECORD_FORMATS` names it (MATLAB with its version).
    """

    path: Path
    channels: dict[str, np.ndarray]
    scalars: dict[str, float] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)
    names: dict[str, str] = field(default_factory=dict)
    sample_rate_Hz: float | None = None
    kind: str = ""

    def _labelled(self) -> list[tuple[str, str]]:
        """Every channel's path and label: the path, with its name where its struct gives one."""
        by_path = {p: n for n, p in self.names.items() if p}
        return [(c, f"{c} ('{by_path[c]}')" if c in by_path else c) for c in self.channels]

    def channel_list(self) -> list[str]:
        """Every channel: its path, with its name where its struct gives one."""
        return [label for _, label in self._labelled()]

    def held(self) -> str:
        """One line: every channel with its length, every scalar field with its value, every text field."""
        chans = ", ".join(f"{label} [{self.channels[c].size}]" for c, label in self._labelled())
        parts = [f"channels {chans}" if chans else "no channels"]
        if self.scalars:
            parts.append("scalar fields " + ", ".join(f"{p} = {v:g}" for p, v in self.scalars.items()))
        if self.texts:
            parts.append("text fields " + ", ".join(f"{p} = '{_shown(t)}'" for p, t in self.texts.items()))
        return "; ".join(parts)

    def listing(self) -> str:
        """What ``piezobearing detect FILE --list`` prints: a line per channel, scalar and text field."""
        lines = [f"{self.path}: {self.kind}" + (f", {self.sample_rate_Hz:g} Hz stated by the file" if self.sample_rate_Hz else "")]
        lines.append(f"channels ({len(self.channels)}):" if self.channels else "channels: none")
        lines += [f"  {label:<32} {self.channels[c].size} samples" for c, label in self._labelled()]
        if self.scalars:
            lines.append(f"scalar fields ({len(self.scalars)}):")
            lines += [f"  {p:<32} {v:g}" for p, v in self.scalars.items()]
        if self.texts:
            lines.append(f"text fields ({len(self.texts)}):")
            lines += [f"  {p:<32} '{_shown(t)}'" for p, t in self.texts.items()]
        return "\n".join(lines)

    def field_value(self, name: str, what: str) -> float:
        """The number a scalar field (or a text field that reads as one) holds; ``what`` says what it is for
        (``the sampling rate (--fs)``) in the one-line error."""
        if name in self.scalars:
            return self.scalars[name]
        if name in self.texts:
            text = self.texts[name].strip()
            try:
                return float(text)
            except ValueError:
                raise MeasurementError(f"{self.path}: field '{name}' ({what}) holds the text '{_shown(text)}', "
                                       "not a number; name a numeric field or give the value") from None
        if name in self.channels:
            raise MeasurementError(f"{self.path}: field '{name}' ({what}) holds {self.channels[name].size} values, "
                                   f"not one; name a scalar field ({self._scalar_names()}) or give the value")
        raise MeasurementError(f"{self.path}: field '{name}' ({what}) not found (the file holds {self.held()}); "
                               "give one of those scalar fields, or the value")

    def _scalar_names(self) -> str:
        return ", ".join([*self.scalars, *self.texts]) or "the file has none"


def _shown(text: str) -> str:
    one = " ".join(text.split())
    return one if len(one) <= _TEXT_SHOWN else one[: _TEXT_SHOWN - 3] + "..."


@dataclass(frozen=True)
class VibrationRecord(Record):
    """One channel of a record on a uniform clock.

    Attributes
    ----------
    samples : ndarray
        The channel's samples (the file's unit: g, m/s^2, V).
    sample_rate_Hz : float
        Sampling rate [Hz].
    channel : str
        The channel's name in the file (its MATLAB path).
    speed_rpm : float or None
        The shaft speed the file holds (a scalar ``*RPM`` variable) [rpm], else None.
    source : str
        The file.
    channels : tuple of str
        Every channel the file holds.
    rate_source : str
        Where the rate came from (the file's time axis, a field of the file, the rate given).
    contents : RecordContents or None
        What the file holds (its scalar and text fields: a speed or a time held in a field).
    """

    samples: np.ndarray
    sample_rate_Hz: float
    channel: str
    speed_rpm: float | None
    source: str
    channels: tuple[str, ...]
    rate_source: str = ""
    contents: RecordContents | None = None

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.samples.size) / self.sample_rate_Hz

    @property
    def data(self) -> dict[str, np.ndarray]:
        return {self.channel: self.samples}

    def field_value(self, name: str, what: str) -> float:
        """:meth:`RecordContents.field_value` of the record's file."""
        if self.contents is None or (not self.contents.scalars and not self.contents.texts
                                     and name not in self.contents.channels):
            kind = Path(self.source).suffix or "this"
            raise MeasurementError(f"{self.source}: '{name}' ({what}) names a field, but a {kind} file holds no "
                                   "fields; give the value as a number")
        return self.contents.field_value(name, what)


def pick_channel(contents: RecordContents, channel: str | None) -> str:
    """The channel named ``channel`` (its path, its name, or the only path ending with it), or the only
    channel; returns its path."""
    path, names = contents.path, list(contents.channels)
    if channel is None or channel == "":
        if len(names) == 1:
            return names[0]
        raise MeasurementError(
            f"{path}: holds {len(names)} channels ({', '.join(contents.channel_list()) or 'none'})"
            + (f" and scalar fields ({', '.join(f'{p} = {v:g}' for p, v in contents.scalars.items())})"
               if contents.scalars else "")
            + "; choose one with --channel NAME (or channel: in the rig file; a unique suffix such as _DE_time "
            "is enough; --list lists them)"
        )
    if channel in names:
        return channel
    if contents.names.get(channel):
        return contents.names[channel]
    if channel in contents.names:
        raise MeasurementError(f"{path}: several channels are named '{channel}'; give its path "
                               f"({', '.join(contents.channel_list())})")
    ends = [n for n in names if n.lower().endswith(channel.lower())]
    if len(ends) == 1:
        return ends[0]
    if len(ends) > 1:
        raise MeasurementError(
            f"{path}: {len(ends)} channel names end with '{channel}' ({', '.join(ends)}); give the full name"
        )
    raise MeasurementError(f"{path}: channel '{channel}' not found (the file holds {contents.held()}); give one "
                           "of those channels by its path")


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


def _mat_record(path: Path) -> RecordContents:
    held = mat_contents(path)
    channels, rate = {}, None
    for name, a in held.arrays.items():
        if a.size == 1:
            if name in RATE_VARIABLES:
                rate = float(a.ravel()[0])
            continue
        if 1 in a.shape:
            channels[name] = a.ravel()
        else:
            m = a if a.shape[0] >= a.shape[1] else a.T
            for k in range(m.shape[1]):
                channels[f"{name}[{k}]"] = m[:, k]
    return RecordContents(path, channels, held.scalars(), dict(held.texts), dict(held.names), rate,
                          f"MATLAB {held.version}")


def _csv_record(path: Path) -> tuple[dict[str, np.ndarray], float | None]:
    import pandas as pd  # the CSV reader (module docstring)

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


def numeric_samples(values) -> np.ndarray:
    """A channel's samples as floats (flattened), a cell that is not a number as NaN: numbers as they are, text
    cells (a CSV column with words in it) parsed by pandas."""
    a = np.asarray(values).ravel()
    if a.dtype.kind in "biuf":
        return a.astype(float)
    import pandas as pd  # text cells only (module docstring)

    return pd.to_numeric(pd.Series(a), errors="coerce").to_numpy(dtype=float)


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


def read_record_contents(path: str | Path, key: str = "record") -> RecordContents:
    """Every channel, scalar and text field a record file holds (no check of the samples).

    Raises
    ------
    MeasurementError
        One line naming the file and the fix, for a file missing, of an unknown format, or unreadable.
    """
    path = Path(path)
    if not path.exists():
        raise MeasurementError(f"{path}: file not found; give the path of the record file")
    ext = path.suffix.lower()
    if ext not in RECORD_FORMATS:
        kinds = ", ".join(f"{e} ({d})" for e, d in RECORD_FORMATS.items())
        raise MeasurementError(f"{path}: unknown record format '{ext or '(no extension)'}'; export it as one of: {kinds}")
    check_readable(path, key, text=ext == ".csv")
    try:
        if ext == ".mat":
            return _mat_record(path)
        if ext == ".csv":
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
    return RecordContents(path, found, sample_rate_Hz=file_rate, kind=RECORD_FORMATS[ext])


def read_vibration_record(path: str | Path, channel: str | None = None, sample_rate_Hz: float | str | None = None,
                          key: str = "record") -> VibrationRecord:
    """Read one channel of a record as a DAQ writes it (see the module docstring).

    Parameters
    ----------
    path : path
        The record file.
    channel : str, optional
        The channel's name or path, or a unique suffix of it; None for a file with one channel.
    sample_rate_Hz : float or str, optional
        The sampling rate [Hz] where the file has no time axis (checked against it where it has one), or the
        path of the file's scalar field that holds it (``"bearing.sr"``).
    key : str
        What names the record in messages.

    Raises
    ------
    MeasurementError
        One line naming the file, what is missing and how to give it.
    """
    contents = read_record_contents(path, key)
    path = contents.path
    file_rate = contents.sample_rate_Hz
    given, given_source = sample_rate_Hz, "the rate given"
    if isinstance(sample_rate_Hz, str):
        given = contents.field_value(sample_rate_Hz, "the sampling rate, --fs or sample_rate_Hz")
        given_source = f"field {sample_rate_Hz}"
    name = pick_channel(contents, channel)
    samples = numeric_samples(contents.channels[name])
    bad = np.flatnonzero(~np.isfinite(samples))
    if bad.size:
        raise MeasurementError(f"{path}: channel {name}, sample {int(bad[0]) + 1}: not a finite number ({bad.size} "
                               "such samples); fix or cut them out of the record")
    if file_rate is not None and given is not None and abs(file_rate - given) > RATE_RTOL * file_rate:
        raise MeasurementError(f"{path}: the file's time axis says {file_rate:.6g} Hz, {given_source} is "
                               f"{given:.6g} Hz; give the file's rate or leave --fs out")
    rate = file_rate if file_rate is not None else given
    source = "the file's time axis" if file_rate is not None else given_source
    if rate is None:
        raise MeasurementError(f"{path}: no time axis in the file and no sampling rate given; give --fs HZ "
                               "(or sample_rate_Hz: in the rig file; either can name a field of the file, "
                               "--fs bearing.sr)")
    if not rate > 0 or not math.isfinite(rate):
        raise MeasurementError(f"{path}: sampling rate {rate:g} Hz ({source}); give the rate in Hz (> 0)")
    if samples.size < MIN_DURATION_S * rate:
        raise MeasurementError(f"{path}: channel {name} holds {samples.size} samples ({samples.size / rate:.3g} s at "
                               f"{rate:g} Hz); fault detection needs at least {MIN_DURATION_S:g} s: record longer")
    if np.all(samples == samples[0]):
        raise MeasurementError(f"{path}: channel {name} is constant ({samples[0]:g}); a dead channel: check the "
                               "sensor and the DAQ channel")
    stated = scalar_rpm({p: np.atleast_2d(v) for p, v in contents.scalars.items()})
    rpm = None if stated is None else stated[0]
    return VibrationRecord(samples, float(rate), name, rpm, str(path), tuple(contents.channels), source, contents)
