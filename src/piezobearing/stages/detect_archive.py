"""Stages of ``piezobearing detect`` over an archive of recordings as Snakemake rules (``detect_record``, one
job per record, and ``detect_archive``, the table and the trend; workflow/rules/detect_archive.smk, outside
``rule all``).

The archive is ``detect_archive.folder``: its files matching ``detect_archive.glob``, each with its own rig
file beside it (same name, ``.yaml``) or ``detect_archive.rig``. Each record's job writes its report into
``RESULTS/detect_archive/<name>/`` and its row of the table (``row.json``); a record that cannot be read gets
its row with the one-line error, so one bad file stops no job. The table and trend are those of
:func:`piezobearing.stages.recording.write_batch`.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from ..io import read_json, write_json
from .recording import detect_one, write_batch


def detect_record(record: str, row_json: str, config: dict) -> None:
    """Rule detect_record: one record's detection into the folder of ``row_json``, and its table row."""
    archive = config["detect_archive"]
    out = Path(row_json).parent
    job = {"record": record, "order": 0, "out": str(out.parent),  # the order: the table's, of every record
           "rig": archive["rig"], "bearing": None, "rpm": None, "fs": None, "channel": None, "shaft_Hz": None,
           "time_field": archive["time_field"], "time_pattern": archive["time_from_name"]}
    row = detect_one(job)
    if isinstance(row["time"], datetime):
        row["time"] = row["time"].isoformat()
    write_json(row | {"config": {"detect_archive": archive}}, row_json)


def archive_table(row_jsons: list[str], csv: str, config: dict) -> None:
    """Rule detect_archive: the rows of every record into ``detections.csv`` and ``trend.png`` beside it."""
    archive = config["detect_archive"]
    rows = []
    for path in row_jsons:
        row = {k: v for k, v in read_json(path).items() if k != "config"}
        if isinstance(row["time"], str):
            row["time"] = datetime.fromisoformat(row["time"])
        rows.append(row)
    for i, row in enumerate(sorted(rows, key=lambda r: Path(r["file"]).name)):
        row["order"] = i + 1
    write_batch(rows, Path(csv).parent, archive["time_field"], archive["time_from_name"])
