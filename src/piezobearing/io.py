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


# --------------------------------------------------------------------------- arrays, tables, series


def write_npz(path: str | Path, **arrays) -> None:
    """Arrays as a compressed NPZ, creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)


def read_npz(path: str | Path) -> dict:
    """Every array of an NPZ, by name."""
    d = np.load(path)
    return {k: d[k] for k in d.files}


def write_csv(df: pd.DataFrame, path: str | Path, float_format: str | None = "%.10g") -> None:
    """A table as CSV without the index, creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(path, index=False, float_format=float_format)


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
    df = pd.read_csv(path)
    for c in ("time_s", column):
        if c not in df.columns:
            raise SignalFileError(f"{path}: column '{c}' missing (header: {', '.join(df.columns)}); "
                                  f"write time_s,{column}")
    t = df["time_s"].to_numpy(dtype=float)
    x = df[column].to_numpy(dtype=float)
    bad = np.flatnonzero(~(np.isfinite(t) & np.isfinite(x)))
    if bad.size:
        raise SignalFileError(f"{path}: line {int(bad[0]) + 2}: not a finite number ({bad.size} rows); "
                              "fix the stage that writes it")
    if t.size < 8:
        raise SignalFileError(f"{path}: only {t.size} rows; a signal needs a time series")
    dt = float((t[-1] - t[0]) / (t.size - 1))
    off = np.flatnonzero(np.abs(np.diff(t) - dt) > SERIES_UNIFORM_RTOL * dt)
    if dt <= 0 or off.size:
        i = int(off[0]) + 1 if off.size else 1
        raise SignalFileError(f"{path}: line {i + 2}, column time_s: uneven or decreasing time step; "
                              "the signal stages need a uniform clock")
    return t, x, dt


def read_kinematics(path: str | Path) -> dict:
    """The bearing's kinematic frequencies [Hz] (shaft, FTF, BPFO, BPFI, BSF) from kinematics.json."""
    k = read_json(path)
    need = ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")
    miss = [n for n in need if n not in k]
    if miss:
        raise SignalFileError(f"{path}: key '{miss[0]}' missing; kinematics.json needs {', '.join(need)}")
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
    if not np.isclose(m.points[:, 2].max(), z[-1], rtol=1e-9) or not set(groups) <= {1, 2, 3}:
        raise error(f"{p}: mesh does not match the configured stack geometry; rerun rule sensor_mesh")
    return StackMesh(np.asarray(m.points, float), np.asarray(cells, int), groups, geometry, level)
