"""What a diagnosis writes, for either subject: diagnosis.json, diagnosis.npz, its figures and report.md."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..io import write_json
from ..plotting import save, use_style


def write_diagnosis(out_dir: str | Path, diag: dict, arrays: dict, figures: Callable[[dict, dict], dict],
                    report: Callable[[dict, dict], str]) -> None:
    """Write ``diag`` (diagnosis.json), ``arrays`` (diagnosis.npz), every figure of ``figures(arrays, diag)``
    (figures/<name>.png) and ``report(diag, figure paths relative to out_dir)`` (report.md) into ``out_dir``."""
    out_dir = Path(out_dir)
    write_json(diag, out_dir / "diagnosis.json")
    np.savez_compressed(out_dir / "diagnosis.npz", **arrays)
    use_style()
    rel = {}
    for name, fig in figures(arrays, diag).items():
        path = out_dir / "figures" / f"{name}.png"
        save(fig, path)
        rel[name] = str(path.relative_to(out_dir))
    (out_dir / "report.md").write_text(report(diag, rel) + "\n")
