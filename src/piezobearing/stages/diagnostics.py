"""Stage of the model-versus-measurement loop (rule ``diagnose``, CLI ``piezobearing diagnose``).

Reads a calibration record, runs :func:`piezobearing.diagnosis.engine.diagnose`
with the configured model (``model.effects``) and settings
(``diagnostics``), and writes into one folder:

- ``diagnosis.json``: the numbers (baseline, ranking, steps, verdict, ...) and the config used;
- ``diagnosis.npz``: the arrays behind the figures;
- ``figures/*.png``: overlay, residuals, spectrum, correlations, ranking, ladder;
- ``report.md``: the report, readable on its own.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from ..diagnosis import engine as dg
from ..diagnosis import report
from ..diagnosis.calibration.effects import Record, resolve
from ..io import write_json
from .calibration import load_record, nominal_circuit

#: Config sections a diagnosis depends on (copied into diagnosis.json).
CONFIG_KEYS = ("sensor", "calibration", "model", "diagnostics")


def check_effect_names(config: dict) -> None:
    """Raise a one-line EffectError if ``model.effects`` or ``synthesis.hidden_effects`` names an unknown
    effect or parameter (the workflow calls this before any job runs)."""
    from ..diagnosis.calibration.model import model_from_specs

    resolve(config["model"]["effects"])
    probe = Record(np.arange(1000) / 1000.0, np.zeros(1000))
    model_from_specs(nominal_circuit(config), config["synthesis"]["hidden_effects"], probe)


def run(
    measurement_csv: str, config: dict, progress: Callable[[str], None] | None = None
) -> tuple[dict, dict]:
    """Diagnose one record; returns (JSON-ready dict, arrays)."""
    resolve(config["model"]["effects"])  # an unknown effect stops before any work
    m, imps = load_record(measurement_csv, config)
    c = config["calibration"]
    d = dg.diagnose(
        Record(m.time_s, m.force_N),
        m.voltage_V,
        nominal_circuit(config, c["initial_resistance_ohm"]),
        config["model"]["effects"],
        dg.DiagnosticsSettings.from_config(config.get("diagnostics")),
        imps,
        progress=progress,
    )
    out = {"source": m.source, **d.to_dict()}
    used = {k: config[k] for k in CONFIG_KEYS if k in config}
    if not c.get("measurement"):
        used["synthesis"] = config["synthesis"]
        used["seed"] = config["seed"]
    out["config"] = used
    return out, dg.arrays(d)


def write_figures(arrays: dict, diag: dict, fig_dir: str | Path) -> dict[str, str]:
    """Draw every figure of the report into ``fig_dir``; returns name -> path."""
    from ..plotting import save, use_style
    from ..plotting.diagnostics import all_figures

    use_style()
    fig_dir = Path(fig_dir)
    paths = {}
    for name, fig in all_figures(arrays, diag).items():
        paths[name] = str(fig_dir / f"{name}.png")
        save(fig, paths[name])
    return paths


def diagnose(
    measurement_csv: str, out_dir: str | Path, config: dict, progress: Callable[[str], None] | None = None
) -> dict:
    """Write diagnosis.json, diagnosis.npz, figures/ and report.md into ``out_dir``; returns the dict."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    diag, arrays = run(measurement_csv, config, progress)
    write_json(diag, out_dir / "diagnosis.json")
    np.savez_compressed(out_dir / "diagnosis.npz", **arrays)
    figs = write_figures(arrays, diag, out_dir / "figures")
    rel = {k: str(Path(v).relative_to(out_dir)) for k, v in figs.items()}
    (out_dir / "report.md").write_text(report.render(diag, rel) + "\n")
    return diag
