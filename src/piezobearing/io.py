"""Reading and checking calibration records (CSV: time_s, force_N, voltage_V).

Every problem a user can make with a file raises :class:`MeasurementError`
with one line that names the file, the row (as the line number in the file)
or column, and the fix. Nothing here writes next to the input.
"""

from __future__ import annotations

import json
import math
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
    if not path.exists():
        raise MeasurementError(f"{path}: file not found; set calibration.measurement to an existing CSV")
    try:
        # keep_default_na=False: a cell reading 'nan' or 'NA' is reported as written, not as empty
        raw = pd.read_csv(path, dtype=str, skipinitialspace=True, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise MeasurementError(
            f"{path}: not a readable CSV ({first}); save it as comma-separated text"
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
            raise MeasurementError(
                f"{path}: line {_line(i)}, column {col}: {what} is not a finite number "
                f"({bad.size} such cells); fix or remove those rows"
            )
        data[col] = num
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
