"""Calibration records (time_s, force_N, voltage_V) and running-bearing records (time_s, voltage_V[,
speed_rpm]) read from any format of :func:`piezobearing.io.formats.read_table` and checked: finite values,
increasing and uniform time, rate and length, dead, constant or clipped channels.

Every problem a user can make with a file raises :class:`MeasurementError` with one line that names the file,
the row or column, and the fix.

pandas (0.2-0.25 s of CPU to import) loads where a record's table is read or made, not with :class:`Record`,
which every record type (a vibration record's too) derives from.
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .formats import _DECIMAL_COMMA, MeasurementError, read_table
from .results import as_read

if TYPE_CHECKING:
    import pandas as pd

COLUMNS = ("time_s", "force_N", "voltage_V")
#: Slowest sampling that can still resolve a hand press (about 0.3 s rise) [Hz]; a coarser
#: clock is almost always a time column in milliseconds.
MIN_SAMPLE_RATE_HZ = 20.0
#: Largest relative deviation of a time step from the median step for a uniform clock.
UNIFORM_RTOL = 0.01

class Record:
    """What every record :func:`piezobearing.read_record` returns has, whatever its kind.

    :class:`VibrationRecord` (one channel of any recording), :class:`BearingRecord` (this project's running-bearing
    record) and :class:`Measurement` (its calibration record) are records: each has its sampling rate, its
    time axis, its length, its source, and its sampled columns by name in ``data``.

    Attributes
    ----------
    sample_rate_Hz : float
        Sampling rate [Hz].
    time_s : ndarray
        Sample times [s].
    duration_s : float
        Length of the record [s].
    source : str
        Where it came from (a path or "synthetic").
    data : dict of str to ndarray
        The sampled columns by name (a vibration record: its channel's name; a bearing record: ``voltage_V``
        and, with a tachometer, ``speed_rpm``; a calibration record: ``force_N`` and ``voltage_V``).
    """

    __slots__ = ()

    @property
    def duration_s(self) -> float:
        return float(self.time_s.size / self.sample_rate_Hz)


@dataclass(frozen=True)
class Measurement(Record):
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

    @property
    def data(self) -> dict[str, np.ndarray]:
        return {"force_N": self.force_N, "voltage_V": self.voltage_V}

    def to_frame(self) -> pd.DataFrame:
        import pandas as pd  # a table (module docstring)

        return pd.DataFrame({"time_s": self.time_s, "force_N": self.force_N, "voltage_V": self.voltage_V})


def _finite_column(raw: pd.DataFrame, col: str, path: Path, place) -> np.ndarray:
    """A column as floats; the first cell that is not a finite number stops with its place."""
    import pandas as pd  # a table (module docstring)

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


def _time_series(table, path: Path, columns, record: str) -> tuple[dict[str, np.ndarray], np.ndarray, float]:
    """A record's columns checked: at least 3 rows, every cell a finite number, time strictly increasing.

    Returns the columns as floats, the time steps [s] and their median [s]; ``record`` names the kind of
    record in the one-line error.
    """
    raw, place = table.raw, table.place
    if len(raw) < 3:
        raise MeasurementError(
            f"{path}: only {len(raw)} data rows below the header; a {record} needs a time series, one row per sample"
        )
    data = {col: _finite_column(raw, col, path, place) for col in columns}
    _check_increasing(data["time_s"], path, place)
    dt = np.diff(data["time_s"])
    return data, dt, float(np.median(dt))


def _uneven(dt: np.ndarray, step: float, path: Path, place, fix: str | None) -> bool:
    """Whether a time step lies more than ``UNIFORM_RTOL`` off the median ``step`` [s]; with a ``fix``, that
    stops with one line naming the first such row and the fix."""
    off = np.flatnonzero(np.abs(dt - step) > UNIFORM_RTOL * step)
    if off.size and fix is not None:
        i = int(off[0]) + 1
        raise MeasurementError(
            f"{path}: {place(i)}, column time_s: uneven time step ({dt[i - 1]:g} s against the median "
            f"{step:g} s, {off.size} such steps); {fix}"
        )
    return bool(off.size)


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
    data, dt, step = _time_series(table, path, COLUMNS, "calibration record")
    t = data["time_s"]
    if step > 1.0 / MIN_SAMPLE_RATE_HZ:
        raise MeasurementError(
            f"{path}: column time_s: median step {step:g} s ({1 / step:g} Hz) is too coarse for a calibration "
            f"record (at least {MIN_SAMPLE_RATE_HZ:g} Hz); is time in milliseconds? time_s must be in seconds"
        )
    fix = None if resample_to_uniform else "set calibration.resample_to_uniform: true to resample"
    if _uneven(dt, step, path, table.place, fix):
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
class BearingRecord(Record):
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

    @property
    def data(self) -> dict[str, np.ndarray]:
        d = {"voltage_V": self.voltage_V}
        if self.speed_rpm is not None:
            d["speed_rpm"] = self.speed_rpm
        return d

    def to_frame(self) -> pd.DataFrame:
        import pandas as pd  # a table (module docstring)

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
    place = table.place
    data, dt, step = _time_series(table, path, table.raw.columns, "running-bearing record")
    t = data["time_s"]
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
    _uneven(dt, step, path, place, "export the record on the DAQ's sample clock")
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


def average_blocks(rec: BearingRecord, n: int) -> BearingRecord:
    """The record averaged over blocks of ``n`` consecutive samples (the last incomplete block dropped).

    Each sample of a DAQ record stands for the mean over its window [t - dt/2, t + dt/2]; the mean of ``n`` of
    them is the mean over their joined window, stamped at its centre (the block's mean time): a record at
    rate f_s / n with the same box-filter sample a DAQ at that rate gives. A tachometer speed is averaged the
    same way; a block holding a clipped sample is clipped.
    """
    if n <= 1:
        return rec
    m = (rec.time_s.size // n) * n

    def mean(x):
        return None if x is None else np.asarray(x, dtype=float)[:m].reshape(-1, n).mean(axis=1)

    clipped = None if rec.clipped is None else np.asarray(rec.clipped)[:m].reshape(-1, n).any(axis=1)
    return BearingRecord(mean(rec.time_s), mean(rec.voltage_V), mean(rec.speed_rpm), rec.source, rec.warnings, clipped)


def write_bearing_record(rec: BearingRecord, path: str | Path) -> None:
    """Write a running-bearing record as CSV (the synthetic record under results/)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    rec.to_frame().to_csv(path, index=False, float_format="%.10g")
