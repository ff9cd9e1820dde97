"""Copy the workflow's figures into the documentation, with the code and config they were made with.

The documentation site shows figures a workflow run made; it never makes them itself. This script checks that
the run is current (``snakemake -n`` has nothing to do for the figures and the scorecard), copies each figure
of :data:`FIGURES` to ``docs/_static/figures/``, and writes ``docs/_static/figures/provenance.json``: per figure
the rule that made it, its code hash (``piezobearing.workflow.registry.code_hash`` of the rule's notebook or
script) and config digest (``reads_digest`` of the config values the rule declares), the PNG's SHA-256, and the
scorecard rows the gallery shows beside it. The docs build (``docs/_ext/piezobearing_figures.py``) recomputes
the code hash and the config digest and stops when a figure is not the current code's or config's.

Usage, from the repository root, after the workflow has run on the same configuration::

    python scripts/docs_figures.py --configfile config/ci.yaml

A guide's figure made by another run (:data:`RUN_FIGURES`: ``piezobearing detect`` on the CWRU records of
``tests/data/cwru/``, through the workflow's ``detect_archive``) carries that run's config file in its own
record, and is refreshed on its own, after that run::

    snakemake --cores 2 detect_archive --configfile docs/_data/detect_archive.yaml
    python scripts/docs_figures.py --only detect

The running-bearing guide's ladder figures, its example record diagnosed without and with the dynamic rung
(``running_bearing_guide``, about two minutes of CPU)::

    snakemake --cores 1 running_bearing_guide --configfile docs/_data/running_bearing_guide.yaml
    python scripts/docs_figures.py --only running_bearing

The sensor-design study's figure (the design and studies guides) comes from the paper config's run of that study::

    snakemake --cores 2 study_sensor_design
    python scripts/docs_figures.py --only studies

The runs guide's Fig. 10 of its example variant (the paper's case at 1500 rpm)::

    snakemake --cores 2 results/speed1500/figures/fig10.png --configfile docs/_data/speed1500.yaml
    python scripts/docs_figures.py --only runs

The sensor comparison's calibrated test on the paper configuration (the validation page): the healthy
statistic's distribution and the ROC curves that ``validation/sensor_comparison_calibrated.py --report`` draws from
its seed file (the commands are on docs/validation/sensor_comparison.md, beside the table of the same cases). A
validation script's output is no Snakemake target, so there is no dry run to check; the build checks its code hash
(the script and every package module it imports, the rig's included) and the config digest of rule
``sensor_comparison``, whose config values the script reads case by case. After a change to that code the seeds
are redrawn into a new seed file (the runner skips the seeds its file holds), then the report, then::

    python scripts/docs_figures.py --only validation

A refresh of the paper's figures keeps these records as they are (the build checks them all alike).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path

from piezobearing import config as config_loader
from piezobearing.workflow.registry import code_hash, reads_digest

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "_static" / "figures"

#: file name under results/figures/, the rule that writes it, its notebook or script, a title, and the
#: scorecard rows the gallery shows beside it (each a part of the row's quantity)
FIGURES = [
    ("fig03.png", "fig03", "notebooks/fig03_housing_mesh.ipynb", "Fig. 3: ring, housing and sensor, the FEM mesh",
     ["housing model", "reduced vs direct", "peak-to-peak change"]),
    ("fig05.png", "fig05", "notebooks/fig05_calibration_impulses.ipynb", "Fig. 5: calibration impulses and their sensitivity",
     ["impulse-peak sensitivity"]),
    ("fig06.png", "fig06", "notebooks/fig06_resistance_fit.ipynb", "Fig. 6: the resistance fit", ["circuit resistance", "cable capacitance"]),
    ("fig08a.png", "fig08a", "notebooks/fig08a_lowfreq_sensitivity.ipynb", "Fig. 8a: low-frequency sensitivity",
     ["onset of linearity", "deviation threshold", "reference sensitivity at the onset"]),
    ("fig07.png", "fig07", "notebooks/fig07_sensor_mode.ipynb", "Fig. 7: the sensor's first axial mode", ["first resonance"]),
    ("fig08b.png", "fig08b", "notebooks/fig08b_sensor_harmonic.ipynb", "Fig. 8b: the sensor's high-frequency response",
     ["band low edge", "band high edge", "mid-band sensitivity"]),
    ("fig09.png", "fig09", "notebooks/fig09_voltage.ipynb", "Fig. 9: sensor voltage, healthy and faulty", ["sensor force"]),
    ("fig10.png", "fig10", "notebooks/fig10_envelope.ipynb", "Fig. 10: envelope spectra at 10 dB SNR",
     ["BPFO (11 rollers", "SNR of the added", "fault detected", "detection rate", "false-alarm rate"]),
    ("snr_study.png", "snr_study_figure", "workflow/scripts/snr_study_figure.py", "Detection against SNR", ["lowest SNR"]),
    ("sensor_comparison.png", "sensor_comparison_figure", "notebooks/sensor_comparison.ipynb",
     "The embedded sensor against a housing accelerometer", []),
    ("diagnosis_ladder.png", "diagnosis_notebook", "notebooks/diagnosis.ipynb",
     "The calibration record's diagnosis: the model ladder", []),
    ("diagnosis_bearing.png", "diagnosis_bearing_notebook", "notebooks/diagnosis_bearing.ipynb",
     "The running bearing's diagnosis: the model ladder", []),
]


#: figures of other runs, by group: the run's config file, its Snakemake target (None: a validation script's
#: figure, no workflow output), and per figure its file name on the site, the rule that writes it (a validation
#: script's: the rule whose config values it reads), that rule's script, a title, and its path in the run's
#: results folder
RUN_FIGURES = {
    "detect": ("docs/_data/detect_archive.yaml", "detect_archive", [
        ("detect_fe44.png", "detect_record", "workflow/scripts/detect_record.py",
         "piezobearing detect on the CWRU fan-end record fe44", "detect_archive/fe44/detection.png"),
    ]),
    "studies": ("config/config.yaml", "study_sensor_design", [
        ("study_sensor_design.png", "study_summary", "workflow/scripts/study_summary.py",
         "The sensor_design study's summary on the paper's table of designs", "studies/sensor_design/summary.png"),
    ]),
    "runs": ("docs/_data/speed1500.yaml", "results/speed1500/figures/fig10.png", [
        ("runs_speed1500_fig10.png", "fig10", "notebooks/fig10_envelope.ipynb",
         "Fig. 10 of the run speed1500: the paper's case at 1500 rpm", "figures/fig10.png"),
    ]),
    "validation": ("config/config.yaml", None, [
        ("calibrated_paper_smooth_healthy_statistic.png", "sensor_comparison", "validation/sensor_comparison_calibrated.py",
         "The healthy rig's statistic per sensor, at rest and under base motion, with and without roughness",
         "validation/calibrated_paper_smooth_healthy_statistic.png"),
        ("calibrated_paper_smooth_roc.png", "sensor_comparison", "validation/sensor_comparison_calibrated.py",
         "The ROC curves of those cases (both sensors in each panel)", "validation/calibrated_paper_smooth_roc.png"),
    ]),
    "running_bearing": ("docs/_data/running_bearing_guide.yaml", "running_bearing_guide", [
        ("running_bearing_ladder_qs.png", "running_bearing_guide", "workflow/scripts/running_bearing_guide.py",
         "diagnose-bearing on the guide's LPM record, dynamic rung off", "diagnostics_bearing/guide/diag_qs/figures/ladder.png"),
        ("running_bearing_ladder_dyn.png", "running_bearing_guide", "workflow/scripts/running_bearing_guide.py",
         "diagnose-bearing on the guide's LPM record, dynamic rung on", "diagnostics_bearing/guide/diag_dyn/figures/ladder.png"),
    ]),
}


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def results_dir(cfg: dict) -> Path:
    """Where the run's results are: ``results/`` for the run ``paper``, ``results/<run>/`` otherwise."""
    run = cfg.get("run", "paper")
    return ROOT / "results" if run == "paper" else ROOT / "results" / run


def scorecard_rows(results: Path, quantities: list[str]) -> list[dict]:
    """The scorecard's rows whose quantity holds one of ``quantities``, as the gallery shows them."""
    path = results / "scorecard.csv"
    if not quantities or not path.exists():
        return []
    with path.open() as f:
        rows = [r for r in csv.DictReader(f) if any(q in r["quantity"] for q in quantities)]
    return [{k: r.get(k, "") for k in ("section", "quantity", "paper", "ours", "unit", "note")} for r in rows]


def provenance(cfg: dict, configfiles: list[str], results: Path) -> dict:
    figures = {}
    for name, rule, entry, title, quantities in FIGURES:
        src = results / "figures" / name
        if not src.exists():
            raise SystemExit(f"{src} does not exist: run the workflow first (snakemake --cores 2 "
                             f"{' '.join('--configfile ' + c for c in configfiles)})")
        figures[name] = {"rule": rule, "entry": entry, "title": title, "source": str(src.relative_to(ROOT)),
                         "code_hash": code_hash(str(ROOT / entry)), "config_digest": reads_digest(cfg, rule),
                         "sha256": sha256(src), "scorecard": scorecard_rows(results, quantities)}
    return {"configfiles": configfiles, "made_by": "python scripts/docs_figures.py "
            + " ".join(f"--configfile {c}" for c in configfiles), "figures": figures}


def run_figures(group: str) -> dict:
    """The records of ``group``'s figures (:data:`RUN_FIGURES`), each naming its run's config file."""
    configfile, target, figures = RUN_FIGURES[group]
    cfg = config_loader.load(ROOT / configfile)
    results = results_dir(cfg)
    out = {}
    for name, rule, entry, title, path in figures:
        src = results / path
        if not src.exists():
            first = (f"snakemake --cores 2 {target} --configfile {configfile}" if target is not None else
                     f"{entry} and its --report, as docs/validation/sensor_comparison.md gives them")
            raise SystemExit(f"{src} does not exist: run it first ({first})")
        out[name] = {"rule": rule, "entry": entry, "title": title, "source": str(src.relative_to(ROOT)),
                     "code_hash": code_hash(str(ROOT / entry)), "config_digest": reads_digest(cfg, rule),
                     "sha256": sha256(src), "scorecard": [], "configfiles": [configfile],
                     "made_by": f"python scripts/docs_figures.py --only {group}"}
    return out


def run_is_current(configfiles: list[str], targets: list[Path | str]) -> None:
    """Stop unless Snakemake has nothing to do for ``targets`` (files, or rule names; the figures come from the
    current code)."""
    cmd = [str(Path(sys.executable).parent / "snakemake"), "-n", "--cores", "1"]
    # before --configfile, which takes every name after it
    cmd += [str(t.relative_to(ROOT)) if isinstance(t, Path) else t for t in targets]
    for c in configfiles:
        cmd += ["--configfile", c]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit(f"snakemake -n failed:\n{(run.stdout + run.stderr)[-2000:]}")
    if "Nothing to be done" not in run.stdout + run.stderr:
        raise SystemExit(f"the workflow run is not current; snakemake -n would run:\n{run.stdout[-2000:]}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--configfile", action="append", default=[], help="the run's config files (as for snakemake)")
    ap.add_argument("--no-dry-run", action="store_true", help="skip the check that the run is current")
    ap.add_argument("--only", choices=sorted(RUN_FIGURES), help="refresh only this group of another run's figures")
    a = ap.parse_args(argv)
    previous = json.loads((OUT / "provenance.json").read_text()) if (OUT / "provenance.json").exists() else None
    if a.only:
        if previous is None:
            raise SystemExit(f"{OUT / 'provenance.json'} does not exist: copy the paper's figures first")
        configfile, target, _ = RUN_FIGURES[a.only]
        copied = run_figures(a.only)
        if not a.no_dry_run and target is not None:
            run_is_current([configfile], [target])
        record = {**previous, "figures": {**previous["figures"], **copied}}
    else:
        cfg = config_loader.load(*a.configfile)
        results = results_dir(cfg)
        record = provenance(cfg, a.configfile, results)
        if not a.no_dry_run:
            run_is_current(a.configfile, [results / "figures" / n for n in record["figures"]])
        copied = dict(record["figures"])
        # the other runs' figures stay as they are (refreshed with --only)
        record["figures"].update({n: f for n, f in (previous or {"figures": {}})["figures"].items()
                                  if "configfiles" in f})
    OUT.mkdir(parents=True, exist_ok=True)
    for name, fig in copied.items():
        shutil.copyfile(ROOT / fig["source"], OUT / name)
    (OUT / "provenance.json").write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n")
    print(f"{len(record['figures'])} figures -> {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
