"""Reading and checking calibration records (CSV: time_s, force_N, voltage_V).

Every problem a user can make with a file raises :class:`MeasurementError`
with one line that names the file, the row (as the line number in the file)
or column, and the fix. Nothing here writes next to the input.
"""

from __future__ import annotations

import codecs
import functools
import hashlib
import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

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
    """

    time_s: np.ndarray
    force_N: np.ndarray
    voltage_V: np.ndarray
    source: str

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


def _check_readable_text(path: Path) -> None:
    """A regular, readable, non-empty UTF-8 file, or one line saying what it is and the fix."""
    if not path.exists():
        raise MeasurementError(f"{path}: file not found; set calibration.measurement to an existing CSV")
    if path.is_dir():
        raise MeasurementError(
            f"{path}: is a folder, not a file; set calibration.measurement to the CSV file inside it"
        )
    if not path.is_file():
        raise MeasurementError(f"{path}: not a regular file; save the record as a CSV file and give its path")
    try:
        with open(path, "rb") as f:
            head = f.read(_HEAD_BYTES)
    except OSError as e:
        raise MeasurementError(
            f"{path}: cannot be read ({e.strerror or type(e).__name__}); give yourself read permission "
            "(chmod u+r) or copy the file somewhere readable"
        ) from None
    if not head.strip():
        raise MeasurementError(
            f"{path}: the file is empty; export the record again, header time_s,force_N,voltage_V"
        )
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


def _read_numeric(path: Path) -> dict | None:
    """The three columns as float arrays when every cell parses as a finite number, else None.

    The fast path: the C reader straight into float64 (about 8 bytes a cell),
    where reading every cell as a string first needs several times the file
    size. Anything unusual returns None and the per-cell checks find it.
    """
    try:
        df = pd.read_csv(
            path,
            usecols=lambda c: str(c).strip() in COLUMNS,
            dtype=float,
            skipinitialspace=True,
            encoding="utf-8-sig",
            engine="c",
        )
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError):
        return None
    df.columns = [str(c).strip() for c in df.columns]
    if sorted(df.columns) != sorted(COLUMNS) or len(df) < 3:
        return None
    data = {c: df[c].to_numpy(dtype=float) for c in COLUMNS}
    del df
    if not all(np.isfinite(v).all() for v in data.values()):
        return None
    return data


def _line(i: int) -> int:
    """File line number of data row i (line 1 is the header)."""
    return int(i) + 2


def read_measurement(path: str | Path, resample_to_uniform: bool = False) -> Measurement:
    """Read and check a calibration CSV.

    Checks, in order: the file exists; the columns time_s, force_N, voltage_V
    are present; every cell is a finite number; at least 3 rows; time
    strictly increasing; time steps uniform within 1% of the median step
    (or, with ``resample_to_uniform``, linear resampling onto the median step).
    """
    path = Path(path)
    _check_readable_text(path)
    hint = _decimal_comma_hint(path)
    if hint:
        raise MeasurementError(f"{path}: {hint}")
    fast = _read_numeric(path)
    if fast is not None:  # every cell a finite number: no per-cell checks needed
        return _checked(path, fast, resample_to_uniform)
    try:
        # keep_default_na=False: a cell reading 'nan' or 'NA' is reported as written, not as empty
        raw = pd.read_csv(path, dtype=str, skipinitialspace=True, keep_default_na=False, encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise MeasurementError(_not_utf8(path, e)) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        hint = _decimal_comma_hint(path)
        raise MeasurementError(
            f"{path}: not a readable CSV ({first}); "
            + (hint or "save it as comma-separated text, header time_s,force_N,voltage_V")
        ) from None
    raw.columns = [str(c).strip() for c in raw.columns]
    missing = [c for c in COLUMNS if c not in raw.columns]
    seps = [s for s in (";", "\t", "|", " ") if len(raw.columns) == 1 and s in raw.columns[0].strip()]
    if missing and seps:
        raise MeasurementError(
            f"{path}: the columns are separated by {seps[0]!r}, not commas (header: {raw.columns[0]}); "
            f"save it as comma-separated text with a decimal point, header {','.join(COLUMNS)}"
        )
    if missing:
        raise MeasurementError(
            f"{path}: column '{missing[0]}' missing (header has: {', '.join(raw.columns)}); "
            f"the header must be {','.join(COLUMNS)} with values in s, N, V"
        )
    if len(raw) < 3:
        raise MeasurementError(
            f"{path}: only {len(raw)} data rows below the header; a calibration record needs a time series, "
            "one row per sample"
        )
    data = {}
    for col in COLUMNS:
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
                f"{path}: line {_line(i)}, column {col}: {what} is not a finite number "
                f"({bad.size} such cells); {fix}"
            )
        data[col] = num
    return _checked(path, data, resample_to_uniform)


def _checked(path: Path, data: dict, resample_to_uniform: bool) -> Measurement:
    """The clock checks on parsed columns (see :func:`read_measurement`)."""
    t = data["time_s"]
    dt = np.diff(t)
    back = np.flatnonzero(dt <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise MeasurementError(
            f"{path}: line {_line(i)}, column time_s: time does not increase ({t[i - 1]:g} s then {t[i]:g} s); "
            "sort the rows by time and remove duplicates"
        )
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
                f"{path}: line {_line(i)}, column time_s: uneven time step ({dt[i - 1]:g} s against the median "
                f"{step:g} s, {off.size} such steps); set calibration.resample_to_uniform: true to resample"
            )
        n = int(np.floor((t[-1] - t[0]) / step)) + 1
        tu = t[0] + step * np.arange(n)
        data = {"time_s": tu, **{c: np.interp(tu, t, data[c]) for c in COLUMNS[1:]}}
    return Measurement(data["time_s"], data["force_N"], data["voltage_V"], str(path))


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


def write_measurement(m: Measurement, path: str | Path) -> None:
    """Write a record as CSV (used for the synthetic record under results/)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    m.to_frame().to_csv(path, index=False, float_format="%.9g")


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
