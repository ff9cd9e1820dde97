"""Stage functions of the calibration chain (Sec. II, III-B/C; Fig. 5, 6, 8a): each reads its files, calls one
function of :mod:`piezobearing.chain.calibration` (which the calibration_circuit study calls too) and writes what
it returns."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from .. import io
from ..chain import calibration as outputs
from ..chain.calibration import nominal_circuit  # noqa: F401 (the stages' name for it: tests, diagnostics)
from ..diagnosis.calibration import record
from ..diagnosis.calibration.record import read_record
from ..io import Measurement, check_readable, read_json, write_csv, write_json, write_measurement
from ..io import formats as io_formats
from ..io import records as io_records
from ..sensor import calibration as sensor_calibration
from ..workflow.checks import remembered


def synthesize_calibration(config: dict, out_csv: str) -> None:
    """Write the synthetic calibration record (results/calibration/measurement.csv)."""
    write_measurement(outputs.synthesize_calibration(config), out_csv)


def load_record(path: str, config: dict) -> tuple[Measurement, list[sensor_calibration.Impulse]]:
    """Read and check a calibration record and detect its impulses (the calibration subject's reader,
    :func:`piezobearing.diagnosis.calibration.record.read_record`)."""
    return read_record(path, config)


def _checks_digest(path: str, config: dict) -> str:
    """What a record's check depends on: its content, the settings the checks read, the checking code."""
    h = hashlib.sha256(io.file_digest(path).encode())
    h.update(
        json.dumps({k: config[k] for k in ("calibration", "sensor")}, sort_keys=True, default=str).encode()
    )
    for mod in (io_formats, io_records, record, sensor_calibration):
        h.update(Path(mod.__file__).read_bytes())
    h.update(Path(__file__).read_bytes())
    return h.hexdigest()


def check_record_once(path: str, config: dict, cache_dir: str) -> dict:
    """:func:`load_record`'s checks, done once per record content and settings.

    The workflow checks the user's record at every start (even ``-n``); a
    record that passed is remembered in ``cache_dir``/<digest>.json, keyed by
    the SHA-256 of the file's content, the calibration and sensor settings
    and the checking code, so an unchanged 200 MB record costs one hash per
    start, not a parse. Failures are not cached. Returns the summary.
    """
    check_readable(Path(path), text=False)  # a folder or unreadable file: one line before hashing
    key = _checks_digest(path, config)

    def check() -> dict:
        m, imps = load_record(path, config)
        return {
            "measurement": str(path),
            "rows": int(m.time_s.size),
            "sample_rate_Hz": m.sample_rate_Hz,
            "impulses": len(imps),
        }

    return remembered(Path(cache_dir) / f"{key}.json", check)[0]


def extract_sensitivity(measurement_csv: str, out_json: str, config: dict) -> None:
    """Peak voltage over peak force per impulse → results/calibration/sensitivity.json."""
    write_json(outputs.extract_sensitivity(*load_record(measurement_csv, config), config), out_json)


def fit_resistance(measurement_csv: str, out_json: str, out_csv: str, config: dict) -> None:
    """Fit R of Eq. 6 → resistance.json and the simulated voltage (fit.csv)."""
    record, table = outputs.fit_resistance(load_record(measurement_csv, config)[0], config)
    write_json(record, out_json)
    write_csv(table, out_csv, "%.9g")


def lowfreq(resistance_json: str, out_json: str, out_csv: str, config: dict) -> None:
    """Sensitivity against frequency from the fitted model → results/sensor/lowfreq.{json,csv}."""
    record, table = outputs.lowfreq(read_json(resistance_json)["resistance_ohm"], config)
    write_json(record, out_json)
    write_csv(table, out_csv, "%.9g")
