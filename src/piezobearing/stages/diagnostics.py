"""Stage of the model-versus-measurement loop (rule ``diagnose``, CLI ``piezobearing diagnose``).

Reads a calibration record with the calibration subject
(:data:`piezobearing.diagnosis.calibration.subject.SUBJECT`), runs the
diagnosis engine with the configured model (``model.effects``) and settings
(``diagnostics``), and writes into one folder:

- ``diagnosis.json``: the numbers (baseline, ranking, steps, verdict, ...) and the config used;
- ``diagnosis.npz``: the arrays behind the figures;
- ``figures/*.png``: overlay, residuals, spectrum, correlations, ranking, ladder;
- ``report.md``: the report, readable on its own.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from ..diagnosis import engine
from ..diagnosis.calibration.subject import SUBJECT
from ..plotting.diagnostics import all_figures
from .diagnosis_files import write_diagnosis

#: Config sections a diagnosis depends on (copied into diagnosis.json).
CONFIG_KEYS = ("sensor", "calibration", "model", "diagnostics")


def run(
    measurement_csv: str, config: dict, progress: Callable[[str], None] | None = None
) -> tuple[dict, dict]:
    """Diagnose one record; returns (JSON-ready dict, arrays)."""
    SUBJECT.catalogue.resolve(config["model"]["effects"], "model.effects")  # stops before any work
    obs = SUBJECT.read(measurement_csv, config)
    d, diag = SUBJECT.diagnose(obs, config, progress)
    out = {"source": obs[0].source, **diag}
    used = {k: config[k] for k in CONFIG_KEYS if k in config}
    if not config["calibration"].get("measurement"):
        used["synthesis"] = config["synthesis"]
        used["seed"] = config["seed"]
    out["config"] = used
    return out, engine.arrays(d)


def diagnose(
    measurement_csv: str, out_dir: str | Path, config: dict, progress: Callable[[str], None] | None = None
) -> dict:
    """Write diagnosis.json, diagnosis.npz, figures/ and report.md into ``out_dir``; returns the dict."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    diag, arrays = run(measurement_csv, config, progress)
    write_diagnosis(out_dir, diag, arrays, all_figures, SUBJECT.report)
    return diag
