"""Stage functions of the parameter studies (rules study_case, study_summary).

Each study kind runs, per case, only the stages its varied keys affect, in
process, into the case's own folder, and reduces them to one summary row.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from ..studies import case_config
from .calibration import (
    extract_sensitivity,
    fit_resistance,
    lowfreq,
    read_json,
    synthesize_calibration,
    write_json,
)


def calibration_circuit_case(config: dict, outdir: Path) -> dict:
    """Synthesis, sensitivity, resistance fit and low-frequency limit for one case."""
    meas = outdir / "measurement.csv"
    synthesize_calibration(config, str(meas))
    extract_sensitivity(str(meas), str(outdir / "sensitivity.json"), config)
    fit_resistance(str(meas), str(outdir / "resistance.json"), str(outdir / "fit.csv"), config)
    lowfreq(
        str(outdir / "resistance.json"), str(outdir / "lowfreq.json"), str(outdir / "lowfreq.csv"), config
    )
    s, r, lf = (read_json(outdir / n) for n in ("sensitivity.json", "resistance.json", "lowfreq.json"))
    return {
        "impulse_sensitivity_V_per_N": s["sensitivity_V_per_N"],
        "resistance_fitted_ohm": r["resistance_ohm"],
        "resistance_ci95_ohm": r["resistance_ci95_ohm"],
        "tau_s": r["tau_s"],
        "nrmse": r["nrmse"],
        "linear_from_Hz": lf["linear_from_Hz"],
        "reference_sensitivity_V_per_N": lf["reference_sensitivity_V_per_N"],
        "open_circuit_sensitivity_V_per_N": lf["open_circuit_sensitivity_V_per_N"],
    }


#: Study kinds by name: the function that runs one case and returns its summary row.
KINDS = {"calibration_circuit": calibration_circuit_case}


def run_case(study: str, case: str, overrides: dict, config: dict, out_json: str) -> None:
    """Run one case of ``study`` with the table row ``overrides``; write its summary."""
    if study not in KINDS:
        raise KeyError(f"study '{study}' is unknown; known: {', '.join(sorted(KINDS))}")
    cfg = case_config(config, overrides, source=f"study {study}, case {case}")
    outdir = Path(out_json).parent
    outdir.mkdir(parents=True, exist_ok=True)
    row = KINDS[study](cfg, outdir)
    write_json({"study": study, "case": case, "overrides": overrides, "summary": row}, out_json)


def summarize(study: str, case_jsons: list[str], out_csv: str, out_png: str) -> None:
    """Gather the cases into one table and draw the study's summary figure."""
    from ..plotting import save, use_style
    from ..plotting.studies import SUMMARY_FIGURES

    rows = []
    for p in case_jsons:
        d = json.loads(Path(p).read_text())
        rows.append({**d["overrides"], **{k: v for k, v in d["summary"].items() if not isinstance(v, list)}})
    df = pd.DataFrame(rows)
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)
    use_style()
    save(SUMMARY_FIGURES[study](df), out_png)


__all__ = ["run_case", "summarize", "KINDS", "write_json"]
