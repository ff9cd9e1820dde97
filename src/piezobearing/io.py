"""Reading and checking records (calibration: time_s, force_N, voltage_V; running bearing: time_s,
voltage_V[, speed_rpm]) as DAQs export them: CSV, MATLAB .mat (v5, v7.3), UFF58, TDMS, WAV.

Every problem a user can make with a file raises :class:`MeasurementError`
with one line that names the file, the row (as the line number in the file)
or column, and the fix. Nothing here writes next to the input.

Beyond the records, every other file format of the workflow lives here too (the house rule: file formats in
io.py): JSON results, NPZ arrays, CSV tables and time series, the housing and sensor meshes. That makes this module
longer than 600 lines; its sections (records as DAQs export them, result files, arrays and series, meshes,
running-bearing records) are independent.
"""

from __future__ import annotations

import codecs
import functools
import hashlib
import io
import json
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

COLUMNS = ("time_s", "force_N", "voltage_V")
#: Slowest sampling that can still resolve a hand press (about 0.3 s rise) [Hz]; a coarser
#: clock is almost always a time column in milliseconds.
MIN_SAMPLE_RATE_HZ = 20.0
#: Largest relative deviation of a time step from the median step for a uniform clock.
UNIFORM_RTOL = 0.01


class MeasurementError(ValueError):
    """A calibration record that cannot be used as it is."""


@dataclass(frozen=True)
class Measurement:
    """A calibration record on a uniform clock.

    Attributes
    ----------
    time_s, force_N, voltage_V : ndarray
        Samples [s], [N], [V].
    source : str
        Where it came from (a path or "synthetic").
    filled : ndarray of bool or None
        Samples :func:`read_measurement` filled by interpolation across a gap of the recorded clock
        (``resample_to_uniform``; a step longer than ``GAP_FACTOR`` median steps): not measured, so the
        diagnosis leaves them out of its fit and tests (None: every sample measured).
    """

    time_s: np.ndarray
    force_N: np.ndarray
    voltage_V: np.ndarray
    source: str
    filled: np.ndarray | None = None

    @property
    def dt_s(self) -> float:
        return float((self.time_s[-1] - self.time_s[0]) / (len(self.time_s) - 1))

    @property
    def sample_rate_Hz(self) -> float:
        return 1.0 / self.dt_s

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame({"time_s": self.time_s, "force_N": self.force_N, "voltage_V": self.voltage_V})


#: A number written with a decimal comma ("0,25", "-1,5e-3").
_DECIMAL_COMMA = re.compile(r"^[-+]?\d+,\d+([eE][-+]?\d+)?$")
#: Bytes read to check a file's encoding and first lines before parsing it.
_HEAD_BYTES = 1 << 16


def _not_utf8(path: Path, e: UnicodeDecodeError) -> str:
    byte = e.object[e.start : e.start + 1].hex() if isinstance(e.object, bytes) else "?"
    return (
        f"{path}: not UTF-8 text (byte 0x{byte} at offset {e.start}; Latin-1 or Windows-1252?); "
        "save it as UTF-8 (spreadsheet: 'CSV UTF-8'; shell: iconv -f latin1 -t utf-8 IN > OUT)"
    )


def check_readable(path: Path, key: str = "calibration", text: bool = True) -> None:
    """A regular, readable, non-empty file (and with ``text``, UTF-8), or one line saying what it is
    and the fix."""
    if not path.exists():
        raise MeasurementError(f"{path}: file not found; set {key}.measurement to an existing record file")
    if path.is_dir():
        raise MeasurementError(
            f"{path}: is a folder, not a file; set {key}.measurement to the record file inside it"
        )
    if not path.is_file():
        raise MeasurementError(f"{path}: not a regular file; save the record as a file and give its path")
    try:
        with open(path, "rb") as f:
            head = f.read(_HEAD_BYTES)
    except OSError as e:
        raise MeasurementError(
            f"{path}: cannot be read ({e.strerror or type(e).__name__}); give yourself read permission "
            "(chmod u+r) or copy the file somewhere readable"
        ) from None
    if not head.strip():
        raise MeasurementError(f"{path}: the file is empty; export the record again")
    if not text:
        return
    try:
        codecs.getincrementaldecoder("utf-8")().decode(head, final=len(head) < _HEAD_BYTES)
    except UnicodeDecodeError as e:
        raise MeasurementError(_not_utf8(path, e)) from None


def _decimal_comma_hint(path: Path) -> str | None:
    """The fix for a comma-separated file whose numbers also use decimal commas, else None."""
    with open(path, encoding="utf-8-sig", errors="replace") as f:
        lines = [f.readline() for _ in range(3)]
    header, row = lines[0].strip(), lines[1].strip()
    if "," in header and row.count(",") > header.count(",") and re.search(r"\d,\d", row):
        return (
            f"the numbers use a decimal comma (line 2: {row[:40]}); use a dot as the decimal mark "
            "(export with '.' as decimal separator) and commas between columns"
        )
    return None


def _read_numeric(path: Path, wanted: tuple[str, ...]) -> pd.DataFrame | None:
    """The ``wanted`` columns that the file has, as floats, when every cell parses as a finite number,
    else None.

    The fast path: the C reader straight into float64 (about 8 bytes a cell),
    where reading every cell as a string first needs several times the file
    size. Anything unusual returns None and the per-cell checks find it.
    """
    try:
        df = pd.read_csv(
            path,
            usecols=lambda c: str(c).strip() in wanted,
            dtype=float,
            skipinitialspace=True,
            encoding="utf-8-sig",
            engine="c",
        )
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError):
        return None
    df.columns = [str(c).strip() for c in df.columns]
    if len(df) < 3 or not all(np.isfinite(df[c].to_numpy()).all() for c in df.columns):
        return None
    return df


def _line(i: int) -> int:
    """File line number of data row i (line 1 is the header)."""
    return int(i) + 2


# --------------------------------------------------------------------------- records as DAQs export them

#: File extensions the record reader understands, and what they are.
RECORD_FORMATS = {
    ".csv": "comma-separated text with a header",
    ".mat": "MATLAB v5 (scipy.io) or v7.3 (HDF5, h5py)",
    ".uff": "universal file, dataset 58 (pyuff)",
    ".unv": "universal file, dataset 58 (pyuff)",
    ".tdms": "NI TDMS (npTDMS)",
    ".wav": "WAV (scipy.io.wavfile)",
}


@dataclass(frozen=True, eq=False)
class RawTable:
    """The columns a record file holds, before any check of their values.

    Attributes
    ----------
    raw : DataFrame
        One column per requested record column found in the file (CSV: the
        cells as text, as written; other formats: numbers).
    place : callable
        ``place(i)`` names data row i for a message: ``line 43`` in a CSV
        (line 1 is the header), ``sample 42`` (1-based) in other formats.
    """

    raw: pd.DataFrame
    place: Callable[[int], str]


def _sample(i: int) -> str:
    return f"sample {int(i) + 1}"


def _csv_place(i: int) -> str:
    return f"line {_line(i)}"


def read_table(
    path: str | Path,
    columns: tuple[str, ...],
    optional: tuple[str, ...] = (),
    channels: dict | None = None,
    key: str = "calibration",
    wav_full_scale_V: float | None = None,
    unit_hint: str = "",
) -> RawTable:
    """Read the record columns of a DAQ export, dispatching on the file's extension.

    Parameters
    ----------
    path : path
        ``.csv`` (header with the column names), ``.mat`` (MATLAB v5 or v7.3:
        one variable per channel), ``.uff``/``.unv`` (datasets 58, one per
        channel, named by their ID line 1 or their 0-based position),
        ``.tdms`` (channels ``group/channel`` or ``channel``), ``.wav``
        (channels by 0-based index).
    columns, optional : tuple of str
        Record columns required and optional (``time_s``, ``voltage_V``, ...).
    channels : dict
        Record column -> channel name in the file (``<key>.channels`` in the
        config). Unnamed columns are looked up by their own name; a file with
        one data channel gives it to ``voltage_V``. In binary formats without
        a time channel, time comes from the sampling (TDMS ``wf_increment``,
        UFF58 abscissa, WAV rate, a scalar ``sample_rate_Hz`` in a .mat file).
    key : str
        Config section named in messages (``calibration``, ``bearing``).
    wav_full_scale_V : float
        Voltage of a full-scale sample of an integer WAV [V].

    Raises
    ------
    MeasurementError
        One line naming the file, the channel and the fix.
    """
    path = Path(path)
    if not path.exists():
        raise MeasurementError(f"{path}: file not found; set {key}.measurement to an existing record file")
    ext = path.suffix.lower()
    check_readable(path, key, text=ext == ".csv")
    if ext not in RECORD_FORMATS:
        kinds = ", ".join(f"{e} ({d})" for e, d in RECORD_FORMATS.items())
        raise MeasurementError(
            f"{path}: unknown record format '{ext or '(no extension)'}'; export the record as one of: {kinds}"
        )
    channels = {k: v for k, v in (channels or {}).items() if v not in (None, "")}
    if ext == ".csv":
        return _read_csv_table(path, columns, optional, unit_hint)
    try:
        found = _BINARY_READERS[ext](path, channels, wav_full_scale_V, key)
    except MeasurementError:
        raise
    except Exception as e:  # noqa: BLE001 - a library's own error on a damaged file: one line, no traceback
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise MeasurementError(
            f"{path}: not a readable {RECORD_FORMATS[ext]} file ({first}); export it again from the DAQ software"
        ) from None
    return _pick_channels(path, found, columns, optional, channels, key)


def _read_csv_table(path: Path, columns, optional, unit_hint: str) -> RawTable:
    hint = _decimal_comma_hint(path)
    if hint:
        raise MeasurementError(f"{path}: {hint}")
    fast = _read_numeric(path, (*columns, *optional))
    if fast is not None and all(c in fast.columns for c in columns):  # every cell a finite number
        return RawTable(fast[[*columns, *(c for c in optional if c in fast.columns)]], _csv_place)
    del fast
    try:
        # keep_default_na=False: a cell reading 'nan' or 'NA' is reported as written, not as empty
        raw = pd.read_csv(path, dtype=str, skipinitialspace=True, keep_default_na=False, encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise MeasurementError(_not_utf8(path, e)) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise MeasurementError(
            f"{path}: not a readable CSV ({first}); save it as comma-separated text, header {','.join(columns)}"
        ) from None
    raw.columns = [str(c).strip() for c in raw.columns]
    missing = [c for c in columns if c not in raw.columns]
    seps = [s for s in (";", "\t", "|", " ") if len(raw.columns) == 1 and s in raw.columns[0].strip()]
    header = ",".join(columns)
    if missing and seps:
        raise MeasurementError(
            f"{path}: the columns are separated by {seps[0]!r}, not commas (header: {raw.columns[0]}); "
            f"save it as comma-separated text with a decimal point, header {header}"
        )
    if missing:
        extra = f"[,{','.join(optional)}]" if optional else ""
        raise MeasurementError(
            f"{path}: column '{missing[0]}' missing (header has: {', '.join(raw.columns)}); "
            f"the header must be {header}{extra}{' ' + unit_hint if unit_hint else ''}"
        )
    keep = [*columns, *(c for c in optional if c in raw.columns)]
    return RawTable(raw[keep], _csv_place)


@dataclass
class _Channel:
    """One channel of a binary record: its samples and, if the file says, its time axis [s]."""

    data: np.ndarray
    time_s: np.ndarray | None = None


def _pick_channels(path: Path, found: dict, columns, optional, channels: dict, key: str) -> RawTable:
    """Assign the file's channels to the record columns (by the config's names, else by column name)."""
    data_names = [n for n in found if not n.startswith("__")]
    cols: dict[str, np.ndarray] = {}
    time = found.get("__time__")
    for col in (*columns, *optional):
        if col == "time_s" and col not in channels and col not in found:
            continue
        name = channels.get(col, col)
        ch = found.get(str(name))
        if ch is None and col == "voltage_V" and "voltage_V" not in channels:
            others = [n for n in data_names if n not in channels.values() and n != "time_s"]
            if len(others) == 1:
                ch = found[others[0]]
        if ch is None:
            if col in optional:
                continue
            what = f"channel '{name}'" + ("" if name == col else f" (for {col})")
            raise MeasurementError(
                f"{path}: {what} not found (the file holds: {', '.join(data_names) or 'no channels'}); "
                f"name the channel of {col} in {key}.channels.{col}"
            )
        cols[col] = np.asarray(ch.data, dtype=float).ravel()
        if time is None and ch.time_s is not None:
            time = _Channel(ch.time_s)
    if "time_s" not in cols:
        if time is None:
            raise MeasurementError(
                f"{path}: no time axis (no channel 'time_s', no sampling interval in the file); "
                f"name the time channel in {key}.channels.time_s"
            )
        cols["time_s"] = np.asarray(time.data, dtype=float).ravel()
    n = {c: v.size for c, v in cols.items()}
    if len(set(n.values())) > 1:
        desc = ", ".join(f"{c} {k}" for c, k in n.items())
        raise MeasurementError(
            f"{path}: the channels have different lengths ({desc} samples); export them on one clock"
        )
    order = [c for c in (*columns, *optional) if c in cols]
    return RawTable(pd.DataFrame({c: cols[c] for c in order}), _sample)


def _mat_channels(path: Path, channels: dict, wav_full_scale_V, key: str) -> dict:
    """MATLAB variables as channels (v5 by scipy.io, v7.3 by h5py); ``name[k]`` is column k of a matrix."""
    import h5py

    if h5py.is_hdf5(path):
        with h5py.File(path, "r") as f:
            # MATLAB stores arrays column-major: an n x k matrix reads as (k, n)
            arrays = {
                n: np.asarray(v[()]).T
                for n, v in f.items()
                if isinstance(v, h5py.Dataset) and np.issubdtype(v.dtype, np.number)
            }
    else:
        from scipy.io import loadmat

        arrays = {
            n: np.asarray(v)
            for n, v in loadmat(path, squeeze_me=False).items()
            if not n.startswith("__") and isinstance(v, np.ndarray) and np.issubdtype(v.dtype, np.number)
        }
    out: dict[str, _Channel] = {}
    rate = None
    for n, a in arrays.items():
        a = np.atleast_2d(a)
        if a.size == 1:
            if n == "sample_rate_Hz":
                rate = float(a.ravel()[0])
            continue
        if 1 in a.shape:
            out[n] = _Channel(a.ravel())
        else:
            m = a if a.shape[0] >= a.shape[1] else a.T
            for k in range(m.shape[1]):
                out[f"{n}[{k}]"] = _Channel(m[:, k])
    if rate is not None and out:
        n0 = next(iter(out.values())).data.size
        out["__time__"] = _Channel(np.arange(n0) / rate)
    return out


def _uff_channels(path: Path, channels: dict, wav_full_scale_V, key: str) -> dict:
    """Datasets 58 of a universal file, each by its ID line 1 and by its position among them."""
    import pyuff

    sets = pyuff.UFF(str(path)).read_sets()
    sets = [s for s in ([sets] if isinstance(sets, dict) else sets) if s.get("type") == 58]
    if not sets:
        raise MeasurementError(f"{path}: no dataset 58 (function at nodal DOF) in the file; export time records as UFF58")
    out: dict[str, _Channel] = {}
    for i, s in enumerate(sets):
        ch = _Channel(np.real(np.asarray(s["data"])), np.asarray(s["x"], dtype=float))
        out[str(i)] = ch
        name = str(s.get("id1", "")).strip()
        if name and name not in out:
            out[name] = ch
    return out


def _tdms_channels(path: Path, channels: dict, wav_full_scale_V, key: str) -> dict:
    """TDMS channels as ``group/channel`` and, where unique, ``channel``; time from ``wf_increment``."""
    from nptdms import TdmsFile

    out: dict[str, _Channel] = {}
    count: dict[str, int] = {}
    f = TdmsFile.read(path)
    for g in f.groups():
        for c in g.channels():
            t = None
            if "wf_increment" in c.properties:
                t = c.time_track()
            ch = _Channel(np.asarray(c[:]), t)
            out[f"{g.name}/{c.name}"] = ch
            count[c.name] = count.get(c.name, 0) + 1
            out.setdefault(c.name, ch)
    for name, k in count.items():
        if k > 1:
            del out[name]  # ambiguous: only group/channel names it
    return out


def _wav_channels(path: Path, channels: dict, wav_full_scale_V, key: str) -> dict:
    """WAV channels by 0-based index; integer samples scaled so that full scale is ``wav_full_scale_V``."""
    from scipy.io import wavfile

    rate, data = wavfile.read(path)
    data = np.asarray(data)
    if np.issubdtype(data.dtype, np.integer):
        if wav_full_scale_V is None:
            raise MeasurementError(
                f"{path}: integer WAV samples ({data.dtype}) carry no unit; set {key}.wav_full_scale_V to the "
                "voltage of a full-scale sample, or export 32-bit float samples in volts"
            )
        info = np.iinfo(data.dtype)
        mid = 0.5 * (float(info.max) + float(info.min) + 1)
        data = (data.astype(float) - mid) / (float(info.max) + 1 - mid) * wav_full_scale_V
    data = data.reshape(len(data), -1)
    t = np.arange(len(data)) / float(rate)
    return {str(k): _Channel(data[:, k], t) for k in range(data.shape[1])}


_BINARY_READERS = {
    ".mat": _mat_channels,
    ".uff": _uff_channels,
    ".unv": _uff_channels,
    ".tdms": _tdms_channels,
    ".wav": _wav_channels,
}


def _finite_column(raw: pd.DataFrame, col: str, path: Path, place) -> np.ndarray:
    """A column as floats; the first cell that is not a finite number stops with its place."""
    num = pd.to_numeric(raw[col], errors="coerce").to_numpy(dtype=float)
    bad = np.flatnonzero(~np.isfinite(num))
    if bad.size:
        i = int(bad[0])
        cell = raw[col].iloc[i]
        what = "empty" if pd.isna(cell) or str(cell).strip() == "" else f"'{cell}'"
        fix = (
            "use a dot as the decimal mark (or export the file with '.' as decimal separator)"
            if _DECIMAL_COMMA.match(str(cell).strip())
            else "fix or remove those rows"
        )
        raise MeasurementError(
            f"{path}: {place(i)}, column {col}: {what} is not a finite number ({bad.size} such cells); {fix}"
        )
    return num


def _check_increasing(t: np.ndarray, path: Path, place) -> None:
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise MeasurementError(
            f"{path}: {place(i)}, column time_s: time does not increase ({t[i - 1]:g} s then {t[i]:g} s); "
            "sort the rows by time and remove duplicates"
        )


def read_measurement(
    path: str | Path,
    resample_to_uniform: bool = False,
    channels: dict | None = None,
    wav_full_scale_V: float | None = None,
) -> Measurement:
    """Read and check a calibration record (CSV, .mat, UFF58, TDMS or WAV; see :func:`read_table`).

    Checks, in order: the file exists; the columns time_s, force_N, voltage_V
    are present; every cell is a finite number; at least 3 rows; time
    strictly increasing; time steps uniform within 1% of the median step
    (or, with ``resample_to_uniform``, linear resampling onto the median step;
    the samples that fall inside a gap, a recorded step over ``GAP_FACTOR``
    median steps, are marked in ``Measurement.filled``).
    ``channels`` names the channels of a file that holds several
    (``calibration.channels``).
    """
    path = Path(path)
    table = read_table(
        path, COLUMNS, channels=channels, key="calibration", wav_full_scale_V=wav_full_scale_V,
        unit_hint="with values in s, N, V",
    )
    raw, place = table.raw, table.place
    if len(raw) < 3:
        raise MeasurementError(
            f"{path}: only {len(raw)} data rows below the header; a calibration record needs a time series, "
            "one row per sample"
        )
    data = {col: _finite_column(raw, col, path, place) for col in COLUMNS}
    t = data["time_s"]
    dt = np.diff(t)
    _check_increasing(t, path, place)
    step = float(np.median(dt))
    if step > 1.0 / MIN_SAMPLE_RATE_HZ:
        raise MeasurementError(
            f"{path}: column time_s: median step {step:g} s ({1 / step:g} Hz) is too coarse for a calibration "
            f"record (at least {MIN_SAMPLE_RATE_HZ:g} Hz); is time in milliseconds? time_s must be in seconds"
        )
    off = np.flatnonzero(np.abs(dt - step) > UNIFORM_RTOL * step)
    if off.size:
        if not resample_to_uniform:
            i = int(off[0]) + 1
            raise MeasurementError(
                f"{path}: {place(i)}, column time_s: uneven time step ({dt[i - 1]:g} s against the median "
                f"{step:g} s, {off.size} such steps); set calibration.resample_to_uniform: true to resample"
            )
        n = int(np.floor((t[-1] - t[0]) / step + 1e-6)) + 1  # the last sample too (12 s / 2 ms = 5999.99..)
        tu = t[0] + step * np.arange(n)
        filled = gap_filled(t, tu, step)
        data = {"time_s": tu, **{c: np.interp(tu, t, data[c]) for c in COLUMNS[1:]}}
        return Measurement(
            data["time_s"], data["force_N"], data["voltage_V"], str(path), filled if filled.any() else None
        )
    return Measurement(data["time_s"], data["force_N"], data["voltage_V"], str(path))


def gap_filled(t: np.ndarray, tu: np.ndarray, step: float) -> np.ndarray:
    """Which samples of the uniform clock ``tu`` lie strictly inside a gap of the recorded clock ``t``.

    A gap is a recorded step longer than ``GAP_FACTOR`` median steps (``step``): samples were lost
    there, and a sample of ``tu`` inside it is the interpolation's, not a measurement (jitter within
    that factor only moves measured samples onto the grid).
    """
    i = np.clip(np.searchsorted(t, tu, side="right") - 1, 0, t.size - 2)  # the recorded step holding tu
    gap = np.diff(t)[i] > GAP_FACTOR * step
    # a grid sample within half a step of a recorded one stands for it; the rest were lost
    return gap & (tu > t[i] + 0.5 * step) & (tu < t[i + 1] - 0.5 * step)


#: Samples at exactly the channel's extreme value beyond which the channel counts as clipped
#: (at least this many, and at least CLIPPED_FRACTION of the record).
CLIPPED_MIN_SAMPLES = 5
CLIPPED_FRACTION = 1.0e-3


def check_channels(m: Measurement) -> None:
    """Refuse a dead, constant or clipped channel (one line naming the column and the fix).

    A dead voltage channel (every sample 0 V) or a constant one would be
    fitted as a sensitivity of 0 V/N with a confident interval; a clipped one
    (many samples at exactly its largest or smallest value: the DAQ's range)
    cuts the impulse peaks and biases the sensitivity low.
    """
    for col, v in (("voltage_V", m.voltage_V), ("force_N", m.force_N)):
        lo, hi = float(v.min()), float(v.max())
        if hi == 0.0 and lo == 0.0:
            raise MeasurementError(
                f"{m.source}: column {col}: every sample is 0 (a dead channel); check the sensor cable and the "
                "DAQ channel, and record again"
            )
        if hi == lo:
            raise MeasurementError(
                f"{m.source}: column {col}: constant at {hi:g} in every sample (no signal); check the sensor "
                "cable and the DAQ channel, and record again"
            )
        limit = max(CLIPPED_MIN_SAMPLES, CLIPPED_FRACTION * v.size)
        for side, value in (("largest", hi), ("smallest", lo)):
            n = int(np.count_nonzero(v == value))
            if n >= limit:
                raise MeasurementError(
                    f"{m.source}: column {col}: clipped ({n} samples sit at exactly the {side} value {value:g}, "
                    "the DAQ's range); widen the input range or lower the gain and record again"
                )


@functools.lru_cache(maxsize=16)
def _digest(path: str, size: int, mtime_ns: int, inode: int) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's content (hex); computed once per process for an unchanged file."""
    st = Path(path).stat()
    return _digest(str(Path(path).resolve()), st.st_size, st.st_mtime_ns, st.st_ino)


#: Digits of a record written by :func:`write_measurement`.
MEASUREMENT_CSV_FORMAT = "%.9g"


def write_measurement(m: Measurement, path: str | Path) -> None:
    """Write a record as CSV (used for the synthetic record under results/)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    m.to_frame().to_csv(path, index=False, float_format=MEASUREMENT_CSV_FORMAT)


def measurement_as_read(m: Measurement, source: str) -> Measurement:
    """The record as :func:`read_measurement` reads back the file :func:`write_measurement` makes of it (in
    memory, :func:`as_read`; a uniform record, as the synthetic one is), named ``source``."""
    df = as_read(m.to_frame(), MEASUREMENT_CSV_FORMAT)
    return Measurement(*(df[c].to_numpy(dtype=float) for c in COLUMNS), source)


# --------------------------------------------------------------------------- result files


class ResultFileError(ValueError):
    """A result file of an earlier stage that is missing or incomplete."""


def _jsonable(obj):
    """numpy scalars and arrays to plain values; non-finite floats to null (strict JSON)."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if hasattr(obj, "tolist"):
        return _jsonable(obj.tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(obj: dict, path: str | Path) -> None:
    """Write a result as strict JSON (NaN and inf become null), creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(_jsonable(obj), indent=2, allow_nan=False) + "\n")


def read_json(path: str | Path, keys=(), error: type[Exception] = ResultFileError) -> dict:
    """Read a result; raise ``error`` naming the file when it is missing, invalid or lacks one of ``keys``."""
    p = Path(path)
    if not p.exists():
        raise error(f"{p}: file not found; run the rule that writes it")
    try:
        d = json.loads(p.read_text())
    except json.JSONDecodeError as e:
        raise error(f"{p}: not valid JSON ({e}); rerun the rule that writes it") from e
    for k in keys:
        if k not in d:
            raise error(f"{p}: key '{k}' missing; rerun the rule that writes it")
    return d


# --------------------------------------------------------------------------- arrays, tables, series


def write_npz(path: str | Path, **arrays) -> None:
    """Arrays as a compressed NPZ, creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)


def read_npz(path: str | Path) -> dict:
    """Every array of an NPZ, by name."""
    d = np.load(path)
    return {k: d[k] for k in d.files}


#: Digits of the tables the stages hand on: CSV at 10 significant digits, the sensor force and the LPM's
#: contact loads at 9 (stages.bearing).
CSV_FORMAT = "%.10g"
FORCE_CSV_FORMAT = "%.9g"


def write_csv(df: pd.DataFrame, path: str | Path, float_format: str | None = CSV_FORMAT) -> None:
    """A table as CSV without the index, creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(path, index=False, float_format=float_format)


def as_read(df: pd.DataFrame, float_format: str | None = CSV_FORMAT) -> pd.DataFrame:
    """The table as the next stage reads it back from the file :func:`write_csv` makes of it (formatted and
    parsed in memory, no file): what a study hands from one rule's function to the next, so that its values
    are the workflow's to the bit."""
    buf = io.StringIO()
    df.to_csv(buf, index=False, float_format=float_format)
    buf.seek(0)
    return pd.read_csv(buf)


def json_as_read(obj: dict) -> dict:
    """The record as :func:`read_json` reads back the file :func:`write_json` makes of it (in memory)."""
    return json.loads(json.dumps(_jsonable(obj), allow_nan=False))


class SignalFileError(ValueError):
    """A time series or result file of the signal stages that cannot be used as it is."""


#: Largest relative deviation of a time step from the mean step of a time series.
SERIES_UNIFORM_RTOL = 1e-3


def read_series(path: str | Path, column: str) -> tuple[np.ndarray, np.ndarray, float]:
    """Read ``time_s`` and ``column`` of a CSV on a uniform clock.

    Returns time [s], the column's values and the step dt = (t_end - t_0)/(n - 1) [s].
    """
    path = Path(path)
    if not path.exists():
        raise SignalFileError(f"{path}: file not found; run the stage that writes it")
    return table_series(pd.read_csv(path), column, path)


def table_series(df: pd.DataFrame, column: str, source) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`read_series` on a table already read (``source`` names it in errors)."""
    for c in ("time_s", column):
        if c not in df.columns:
            raise SignalFileError(f"{source}: column '{c}' missing (header: {', '.join(df.columns)}); "
                                  f"write time_s,{column}")
    t = df["time_s"].to_numpy(dtype=float)
    x = df[column].to_numpy(dtype=float)
    bad = np.flatnonzero(~(np.isfinite(t) & np.isfinite(x)))
    if bad.size:
        raise SignalFileError(f"{source}: line {int(bad[0]) + 2}: not a finite number ({bad.size} rows); "
                              "fix the stage that writes it")
    if t.size < 8:
        raise SignalFileError(f"{source}: only {t.size} rows; a signal needs a time series")
    dt = float((t[-1] - t[0]) / (t.size - 1))
    off = np.flatnonzero(np.abs(np.diff(t) - dt) > SERIES_UNIFORM_RTOL * dt)
    if dt <= 0 or off.size:
        i = int(off[0]) + 1 if off.size else 1
        raise SignalFileError(f"{source}: line {i + 2}, column time_s: uneven or decreasing time step; "
                              "the signal stages need a uniform clock")
    return t, x, dt


def read_kinematics(path: str | Path) -> dict:
    """The bearing's kinematic frequencies [Hz] (shaft, FTF, BPFO, BPFI, BSF) from kinematics.json."""
    return kinematics_of(read_json(path), path)


def kinematics_of(k: dict, source) -> dict:
    """:func:`read_kinematics` on the record already read (``source`` names it in errors)."""
    need = ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")
    miss = [n for n in need if n not in k]
    if miss:
        raise SignalFileError(f"{source}: key '{miss[0]}' missing; kinematics.json needs {', '.join(need)}")
    return {n: float(k[n]) for n in need}


def read_harmonic(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] and |V/F| [V/N] of the sensor FEM's harmonic response (harmonic.csv)."""
    df = pd.read_csv(path)
    for c in ("frequency_Hz", "voltage_per_force_V_per_N"):
        if c not in df.columns:
            raise SignalFileError(f"{path}: column '{c}' missing; the sensor FEM writes frequency_Hz, "
                                  "voltage_per_force_V_per_N, phase")
    return df["frequency_Hz"].to_numpy(dtype=float), np.abs(df["voltage_per_force_V_per_N"].to_numpy(dtype=float))


# --------------------------------------------------------------------------- meshes


def write_housing_mesh(m, path: str | Path) -> None:
    """A :class:`~piezobearing.bearing.housing_mesh.HousingMesh` and its node sets as NPZ (with its geometry)."""
    from dataclasses import asdict

    write_npz(
        path,
        coors=m.coors,
        conn=m.conn,
        group=m.group,
        raceway_psi=m.raceway_psi,
        raceway_x=m.raceway_x,
        raceway_nodes=m.raceway_nodes,
        ring_outer_psi=m.ring_outer_psi,
        ring_outer_nodes=m.ring_outer_nodes,
        base_nodes=m.base_nodes,
        faulty=m.faulty,
        level=m.level,
        geometry=json.dumps(asdict(m.geometry)),
    )


def read_housing_mesh(path: str | Path):
    """A housing mesh written by :func:`write_housing_mesh`."""
    from .bearing.housing_mesh import HousingGeometry, HousingMesh

    d = np.load(path)
    geo = HousingGeometry(**json.loads(str(d["geometry"])))
    keys = (
        "coors conn group raceway_psi raceway_x raceway_nodes ring_outer_psi ring_outer_nodes base_nodes"
    ).split()
    return HousingMesh(
        **{k: d[k] for k in keys}, geometry=geo, faulty=bool(d["faulty"]), level=float(d["level"])
    )


def write_housing_vtk(m, path: str | Path) -> None:
    """A housing mesh as VTK (hexahedra with the cell array ``group``), to view."""
    import meshio

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, meshio.Mesh(m.coors, [("hexahedron", m.conn)], cell_data={"group": [m.group]}))


def write_stack_mesh(mesh, path: str | Path) -> None:
    """The sensor's quarter mesh as binary legacy VTK with the cell groups (1 bottom disk, 2 PZT, 3 top disk)."""
    import meshio

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    m = meshio.Mesh(
        mesh.coors, [("hexahedron", mesh.cells)], cell_data={"group": [mesh.groups.astype(np.int32)]}
    )
    meshio.write(str(path), m, file_format="vtk", binary=True)


def read_stack_mesh(path: str | Path, geometry, level: float, error: type[Exception] = ResultFileError):
    """Read a mesh written by :func:`write_stack_mesh` and check it against ``geometry`` (a StackGeometry)."""
    import meshio

    from .sensor.mesh import StackMesh

    p = Path(path)
    if not p.exists():
        raise error(f"{p}: mesh file not found; run rule sensor_mesh")
    m = meshio.read(str(p))
    cells = m.cells_dict.get("hexahedron")
    if cells is None or "group" not in m.cell_data_dict:
        raise error(f"{p}: no hexahedra with a 'group' cell array; rerun rule sensor_mesh")
    groups = np.asarray(m.cell_data_dict["group"]["hexahedron"], dtype=int)
    z = geometry.z_interfaces_m
    if not np.isclose(m.points[:, 2].max(), z[-1], rtol=1e-9) or not set(groups) <= {1, 2, 3, 4}:
        raise error(f"{p}: mesh does not match the configured stack geometry; rerun rule sensor_mesh")
    return StackMesh(np.asarray(m.points, float), np.asarray(cells, int), groups, geometry, level)

# --------------------------------------------------------------------------- running-bearing records

BEARING_COLUMNS = ("time_s", "voltage_V")
BEARING_OPTIONAL = ("speed_rpm",)
#: Slowest sampling of a running-bearing record: the roller passages (BPFO ~ 70 Hz at 1000 rpm) and
#: their first harmonics must lie well below Nyquist [Hz].
MIN_BEARING_RATE_HZ = 2000.0
#: Shortest running-bearing record: ~35 roller passages at 1000 rpm, a 2 Hz resolution [s].
MIN_BEARING_DURATION_S = 0.5
#: A step longer than this many median steps is a gap (lost samples), not jitter.
GAP_FACTOR = 1.5
#: Consecutive samples at the record's extreme value that count as clipping.
CLIP_RUN = 3


@dataclass(frozen=True)
class BearingRecord:
    """A running-bearing record on a uniform clock: the sensor voltage and, optionally, a tachometer.

    Attributes
    ----------
    time_s, voltage_V : ndarray
        Samples [s], [V].
    speed_rpm : ndarray or None
        Shaft speed from a tachometer [rpm].
    source : str
        Where it came from (a path or "synthetic").
    warnings : tuple of str
        Problems that do not stop the diagnosis (clipping), one line each, naming the place.
    clipped : ndarray of bool or None
        Samples at a clipping level.
    """

    time_s: np.ndarray
    voltage_V: np.ndarray
    speed_rpm: np.ndarray | None
    source: str
    warnings: tuple[str, ...] = ()
    clipped: np.ndarray | None = None

    @property
    def dt_s(self) -> float:
        return float((self.time_s[-1] - self.time_s[0]) / (len(self.time_s) - 1))

    @property
    def sample_rate_Hz(self) -> float:
        return 1.0 / self.dt_s

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0] + self.dt_s)

    def to_frame(self) -> pd.DataFrame:
        d = {"time_s": self.time_s, "voltage_V": self.voltage_V}
        if self.speed_rpm is not None:
            d["speed_rpm"] = self.speed_rpm
        return pd.DataFrame(d)


def clipping_runs(x: np.ndarray, min_run: int = CLIP_RUN) -> list[tuple[int, int]]:
    """[start, stop) of runs of at least ``min_run`` samples sitting exactly at the record's max or min.

    A DAQ input driven past its range returns its full-scale code for as long
    as the overload lasts; a live signal repeats its extreme value only by
    such saturation (or by a coarse ADC, which the run length guards against).
    """
    runs = []
    for level in (np.max(x), np.min(x)):
        at = np.concatenate([[0], (x == level).astype(np.int8), [0]])
        d = np.diff(at)
        for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True):
            if b - a >= min_run:
                runs.append((int(a), int(b)))
    return sorted(runs)


def read_bearing_record(
    path: str | Path,
    channels: dict | None = None,
    wav_full_scale_V: float | None = None,
    key: str = "bearing",
) -> BearingRecord:
    """Read and check a running-bearing record: ``time_s, voltage_V[, speed_rpm]`` (s, V, rpm).

    Any format of :func:`read_table`. Checks, in order: the file and its
    columns; every value a finite number; time strictly increasing, in
    seconds; no gaps (a step over 1.5 median steps); steps uniform within
    1%; at least 2 kHz and 0.5 s; a tachometer speed positive. Clipping
    (runs of samples at the record's extreme value) is reported in
    ``warnings`` and ``clipped``, not refused.
    """
    path = Path(path)
    table = read_table(
        path, BEARING_COLUMNS, BEARING_OPTIONAL, channels, key, wav_full_scale_V, "with values in s, V, rpm"
    )
    raw, place = table.raw, table.place
    if len(raw) < 3:
        raise MeasurementError(
            f"{path}: only {len(raw)} data rows; a running-bearing record needs a time series, one row per sample"
        )
    data = {c: _finite_column(raw, c, path, place) for c in raw.columns}
    t = data["time_s"]
    _check_increasing(t, path, place)
    dt = np.diff(t)
    step = float(np.median(dt))
    if step > 1.0 / MIN_BEARING_RATE_HZ:
        hint = "; is time in milliseconds? time_s must be in seconds" if 1e3 / step >= MIN_BEARING_RATE_HZ else ""
        raise MeasurementError(
            f"{path}: column time_s: sampling at {1 / step:.6g} Hz; a running-bearing record needs at least "
            f"{MIN_BEARING_RATE_HZ:g} Hz (the roller passages' harmonics must lie below Nyquist){hint}; "
            "record at a higher rate"
        )
    gaps = np.flatnonzero(dt > GAP_FACTOR * step)
    if gaps.size:
        i = int(gaps[0]) + 1
        lost = int(round(dt[i - 1] / step)) - 1
        raise MeasurementError(
            f"{path}: {place(i)}, column time_s: gap of {dt[i - 1]:g} s (about {lost} samples lost) at "
            f"t = {t[i - 1]:g} s ({gaps.size} gap(s) in the record); the model needs one uninterrupted record: "
            "diagnose the longest piece without a gap"
        )
    off = np.flatnonzero(np.abs(dt - step) > UNIFORM_RTOL * step)
    if off.size:
        i = int(off[0]) + 1
        raise MeasurementError(
            f"{path}: {place(i)}, column time_s: uneven time step ({dt[i - 1]:g} s against the median "
            f"{step:g} s, {off.size} such steps); export the record on the DAQ's sample clock"
        )
    duration = float(t[-1] - t[0] + step)
    if duration < MIN_BEARING_DURATION_S:
        raise MeasurementError(
            f"{path}: column time_s: {duration:.3g} s recorded; a running-bearing record needs at least "
            f"{MIN_BEARING_DURATION_S:g} s (about 35 roller passages at 1000 rpm); record longer"
        )
    speed = data.get("speed_rpm")
    if speed is not None:
        neg = np.flatnonzero(speed <= 0)
        if neg.size:
            i = int(neg[0])
            raise MeasurementError(
                f"{path}: {place(i)}, column speed_rpm: {speed[i]:g} rpm; the tachometer speed must be "
                "positive (in revolutions per minute); fix the column or leave it out"
            )
    v = data["voltage_V"]
    runs = clipping_runs(v)
    warnings: list[str] = []
    clipped = np.zeros(v.size, dtype=bool)
    for a, b in runs:
        clipped[a:b] = True
    if runs:
        a, b = runs[0]
        warnings.append(
            f"{path}: {place(a)}, column voltage_V: clipped at {v[a]:g} V for {b - a} samples "
            f"({clipped.sum()} samples in {len(runs)} runs, {100 * clipped.mean():.2g}% of the record); "
            "the model cannot follow them there (expect residual at those samples); lower the DAQ gain or widen its range"
        )
    return BearingRecord(t, v, speed, str(path), tuple(warnings), clipped)


def write_bearing_record(rec: BearingRecord, path: str | Path) -> None:
    """Write a running-bearing record as CSV (the synthetic record under results/)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    rec.to_frame().to_csv(path, index=False, float_format="%.10g")
