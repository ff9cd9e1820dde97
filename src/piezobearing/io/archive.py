"""An archive of recordings on disk: its records (a folder's files of a record format, by a glob) and each
record's rig file (its own beside it, same name with ``.yaml``, else a common one).

Path conventions only: reading nothing, so the workflow's parse lists an archive without loading any reader
(``workflow/rules/detect_archive.smk``).
"""

from __future__ import annotations

from pathlib import Path

from .record_formats import RECORD_FORMATS


def rig_beside(record: Path, rig: str | Path | None) -> str | Path | None:
    """The record's own rig file (same name, ``.yaml``) where there is one, else ``rig``."""
    own = record.with_suffix(".yaml")
    return own if own.is_file() else rig


def archive_records(archive: dict) -> dict[str, str]:
    """The archive's records by name (``detect_archive`` config section); {} where no folder is set."""
    folder = archive["folder"]
    if not folder:
        return {}
    files = sorted(f for f in Path(folder).glob(archive["glob"])
                   if f.is_file() and f.suffix.lower() in RECORD_FORMATS)
    return {f.stem: str(f) for f in files}


def record_rig(record: str, archive: dict) -> list[str]:
    """The rig file of a record (its own beside it, else ``detect_archive.rig``), as a rule's input list."""
    rig = rig_beside(Path(record), archive["rig"])
    return [] if rig is None else [str(rig)]
