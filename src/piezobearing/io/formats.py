"""Record files as DAQs export them: CSV, MATLAB .mat (v5, v7.3), UFF58, TDMS, WAV.

:func:`read_table` reads the columns a record needs from any of these formats into a :class:`RawTable`
(no check of the values: :mod:`piezobearing.io.records` does that). Every problem a user can make with a file
raises :class:`MeasurementError` with one line that names the file, the row (as the line number in the file)
or channel, and the fix. Nothing here writes next to the input.

Each format's reader loads its library when a file of that format is read (pandas for CSV and for the
table :func:`read_table` returns, 0.2-0.25 s of CPU to import; pyuff, npTDMS and h5py for theirs): a
detection on a MATLAB v5 record loads none of them.
"""

from __future__ import annotations

import codecs
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np
from scipy.io import wavfile

from .matlab import mat_contents
from .record_formats import RECORD_FORMATS

if TYPE_CHECKING:
    import pandas as pd


class MeasurementError(ValueError):
    """A calibration record that cannot be used as it is."""



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
    import pandas as pd  # the CSV reader (module docstring)

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
        config; in a CSV, the column's header name). Unnamed columns are
        looked up by their own name; a binary file with one data channel gives
        it to ``voltage_V``. In binary formats without
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
        return _read_csv_table(path, columns, optional, unit_hint, channels, key)
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


def _read_csv_table(path: Path, columns, optional, unit_hint: str, channels: dict, key: str) -> RawTable:
    """The record columns of a CSV file, found by their header names: ``channels[column]`` where the config
    names one (``<key>.channels``), else the column's own name; returned under the record's column names."""
    import pandas as pd  # the CSV reader (module docstring)

    hint = _decimal_comma_hint(path)
    if hint:
        raise MeasurementError(f"{path}: {hint}")
    header_of = {c: str(channels.get(c, c)).strip() for c in (*columns, *optional)}

    def record_columns(table: pd.DataFrame) -> pd.DataFrame:
        keep = [*columns, *(c for c in optional if header_of[c] in table.columns)]
        return pd.DataFrame({c: table[header_of[c]].to_numpy() for c in keep})

    fast = _read_numeric(path, tuple(header_of.values()))
    if fast is not None and all(header_of[c] in fast.columns for c in columns):  # every cell a finite number
        return RawTable(record_columns(fast), _csv_place)
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
    missing = [c for c in columns if header_of[c] not in raw.columns]
    seps = [s for s in (";", "\t", "|", " ") if len(raw.columns) == 1 and s in raw.columns[0].strip()]
    header = ",".join(columns)
    if missing and seps:
        raise MeasurementError(
            f"{path}: the columns are separated by {seps[0]!r}, not commas (header: {raw.columns[0]}); "
            f"save it as comma-separated text with a decimal point, header {header}"
        )
    if missing and missing[0] in channels:
        raise MeasurementError(
            f"{path}: column '{header_of[missing[0]]}' ({key}.channels.{missing[0]}) missing (header has: "
            f"{', '.join(raw.columns)}); set {key}.channels.{missing[0]} to the header's name of that column"
        )
    if missing:
        extra = f"[,{','.join(optional)}]" if optional else ""
        raise MeasurementError(
            f"{path}: column '{missing[0]}' missing (header has: {', '.join(raw.columns)}); "
            f"the header must be {header}{extra}{' ' + unit_hint if unit_hint else ''}, or name the columns in "
            f"{key}.channels (e.g. {{{missing[0]}: <its header name>}})"
        )
    return RawTable(record_columns(raw), _csv_place)


@dataclass
class _Channel:
    """One channel of a binary record: its samples and, if the file says, its time axis [s]."""

    data: np.ndarray
    time_s: np.ndarray | None = None


def _pick_channels(path: Path, found: dict, columns, optional, channels: dict, key: str) -> RawTable:
    """Assign the file's channels to the record columns (by the config's names, else by column name)."""
    import pandas as pd  # the table read_table returns (module docstring)

    data_names = [n for n in found if not n.startswith("__")]
    cols: dict[str, np.ndarray] = {}
    time = found.get("__time__")
    for col in (*columns, *optional):
        if col == "time_s" and col not in channels and col not in found:
            continue
        name = channels.get(col, col)
        ch = found.get(str(name))
        if ch is None and col in channels:  # a configured name may be a suffix only one channel ends with
            ends = [n for n in data_names if n.lower().endswith(str(name).lower())]
            if len(ends) == 1:
                ch = found[ends[0]]
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


def mat_arrays(path: Path) -> dict[str, np.ndarray]:
    """The numeric variables and fields of a MATLAB file (v5 by scipy.io, v7.3 by h5py), each by its MATLAB
    path (``X105RPM``, ``bearing.gs``, ``ch(2).data``; :func:`piezobearing.io.matlab.mat_contents`), at least
    2-D, in MATLAB's orientation (an n x k matrix as (n, k)); scalars are 1 x 1."""
    return mat_contents(path).arrays


def _mat_channels(path: Path, channels: dict, wav_full_scale_V, key: str) -> dict:
    """MATLAB variables as channels (v5 by scipy.io, v7.3 by h5py); ``name[k]`` is column k of a matrix."""
    out: dict[str, _Channel] = {}
    rate = None
    for n, a in mat_arrays(path).items():
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
    import pyuff  # this format's reader (module docstring)

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
    from nptdms import TdmsFile  # this format's reader (module docstring)

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

