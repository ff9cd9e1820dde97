"""Result files of the workflow's stages: strict JSON, NPZ arrays, CSV tables and time series, and the
kinematics and harmonic-response tables the signal stages read.

pandas (0.2-0.25 s of CPU to import) loads where a CSV is read: a job or command that writes only JSON, as
``piezobearing detect`` does, goes without it.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import pandas as pd


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
    import pandas as pd  # a CSV read (module docstring)

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
    import pandas as pd  # a CSV read (module docstring)

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
    import pandas as pd  # a CSV read (module docstring)

    df = pd.read_csv(path)
    for c in ("frequency_Hz", "voltage_per_force_V_per_N"):
        if c not in df.columns:
            raise SignalFileError(f"{path}: column '{c}' missing; the sensor FEM writes frequency_Hz, "
                                  "voltage_per_force_V_per_N, phase")
    return df["frequency_Hz"].to_numpy(dtype=float), np.abs(df["voltage_per_force_V_per_N"].to_numpy(dtype=float))

