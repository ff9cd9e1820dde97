"""Quality gates and workflow behaviour: lint, formatting, incremental rebuilds, report."""

import json
import re
import subprocess
from collections import Counter
from pathlib import Path

import pytest
from conftest import BIN, REPO, snakemake


def run(*cmd, cwd=REPO, timeout=300):
    return subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def test_ruff_is_clean():
    out = run(BIN / "ruff", "check", "src", "tests")
    assert out.returncode == 0, out.stdout[-3000:]


def test_snakefmt_is_clean():
    out = run(BIN / "snakefmt", "--check", "Snakefile", "workflow")
    assert out.returncode == 0, out.stderr[-3000:]


def test_snakemake_lint_is_clean():
    out = snakemake("--lint", "--configfile", "config/ci.yaml")
    assert out.returncode == 0, (out.stdout + out.stderr)[-3000:]


def test_slurm_profile_dry_run():
    out = snakemake(
        "-n", "--profile", "workflow/profiles/slurm", "--configfile", "config/ci.yaml", "--forceall", "all", "study_all"
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert "study_case" in out.stdout


def _prioritised(dry_run_stdout: str, level: str) -> Counter:
    """The jobs of a dry run at priority ``level`` (``1``, ``highest``), counted per rule."""
    return Counter(re.findall(rf"^(?:local)?rule (\w+):\n(?:    .*\n)*?    priority: {level}$", dry_run_stdout, re.M))


def test_the_longest_chains_start_first_and_are_exactly_the_jobs_they_need():
    """The rules that say ``priority: LONGEST_CHAINS`` are exactly the jobs the two longest chains need: the jobs
    Snakemake's own ``--prioritize`` of their last rules picks, counted per rule, and nothing else (a rule added to a
    chain without it would leave it at the default priority); the plain run reads profiles/default."""
    out = snakemake("-n", "--forceall", "--configfile", "config/ci.yaml")
    assert out.returncode == 0, out.stderr[-3000:]
    assert "workflow specific profile profiles/default" in out.stderr + out.stdout
    first = _prioritised(out.stdout, "1")
    assert {"fault_classification", "fault_type_voltage", "sensor_comparison", "sensor_comparison_figure"} <= set(first)
    assert not {"scorecard", "fig05", "diagnose"} & set(first)
    chains = snakemake("-n", "--forceall", "--configfile", "config/ci.yaml", "--prioritize", "fault_classification",
                       "sensor_comparison_figure")
    assert chains.returncode == 0, chains.stderr[-3000:]
    assert _prioritised(chains.stdout, "highest") == first


def test_a_target_builds_only_what_it_needs():
    """A run asked for one file plans only the jobs that file needs (the profile names no targets of its own)."""
    out = snakemake("-n", "--forceall", "results/calibration/measurement.csv", "--configfile", "config/ci.yaml")
    assert out.returncode == 0, out.stderr[-3000:]
    assert _jobs(out.stdout) == {"synthesize_calibration"}


def _jobs(dry_run_stdout: str) -> set[str]:
    table = dry_run_stdout.split("Job stats:")[-1]
    return {m.group(1) for m in re.finditer(r"^(\w+)\s+\d+$", table, re.M)} - {"total", "job"}


@pytest.mark.slow
def test_changing_one_parameter_reruns_only_what_depends_on_it(ci_run: Path):
    override = ci_run / "threshold.yaml"
    override.write_text("lowfreq:\n  deviation_threshold: 0.04\n")
    out = snakemake("--cores", "2", "-n", "--configfile", "config/ci.yaml", str(override), cwd=ci_run)
    assert out.returncode == 0, out.stderr[-3000:]
    jobs = _jobs(out.stdout)
    assert "lowfreq_sensitivity" in jobs and "fig08a" in jobs
    assert not {"synthesize_calibration", "extract_sensitivity", "fit_resistance", "fig05", "fig06"} & jobs


@pytest.mark.slow
def test_study_runs_and_gathers_its_summary(ci_run: Path):
    """`study_all` (built by the ``ci_run`` fixture's call, which stops the session if a study fails) gathers
    each study's cases into its summary."""
    import pandas as pd

    df = pd.read_csv(ci_run / "results/studies/calibration_circuit/summary.csv")
    assert len(df) == 2
    # each case recovers its own resistance
    assert (abs(df["resistance_fitted_ohm"] / df["synthesis__resistance_ohm"] - 1) < 0.05).all()
    assert (ci_run / "results/studies/calibration_circuit/summary.png").stat().st_size > 0
    sd = pd.read_csv(ci_run / "results/studies/sensor_design/summary.csv")
    contract = ["material", "pzt_diameter_m", "pzt_thickness_m", "sensitivity_V_per_N", "first_resonance_short_Hz",
                "band_high_Hz", "linear_from_Hz", "load_share", "indicator_faulty"]
    assert len(sd) == 2 and not sd[contract].isna().any().any()
    # the paper's stack on the study mesh: within 1% of the sensor FEM stages' first resonance (CI mesh: the same)
    band = json.loads((ci_run / "results/sensor/band.json").read_text())
    paper = sd[sd["material"] == "apc850_paper"].iloc[0]
    assert paper["first_resonance_short_Hz"] == pytest.approx(band["first_axial_short_Hz"], rel=0.01)
    assert (ci_run / "results/studies/sensor_design/summary.png").stat().st_size > 0


@pytest.mark.slow
def test_sensor_comparison_study_gives_the_calibrated_test(ci_run: Path):
    """The CI run's sensor comparison study (12 healthy and 6 faulty seeds a case): per case and sensor the
    threshold set on the healthy seeds holds their false-alarm rate, the detection probability lies in its
    Clopper-Pearson interval, the earlier columns stay, and the calibrated figures are drawn."""
    import pandas as pd

    d = ci_run / "results/studies/sensor_comparison"
    df = pd.read_csv(d / "summary.csv")
    assert len(df) == 8 and set(df["sensor"]) == {"pzt", "accelerometer"}
    for col in ("detection_rate", "false_alarm_rate", "margin_dB", "margin_over_healthy_dB",
                "detection_rate_over_healthy", "calibrated_threshold_dB", "calibrated_detection_probability",
                "roc_auc", "type_correct_rate", "alarm_rate_faulty", "smallest_detected_width_m"):
        assert col in df, col
    assert (df["n_healthy_seeds"] == 12).all() and (df["n_faulty_seeds"] == 6).all()
    p = df["calibrated_detection_probability"]
    assert ((df["calibrated_detection_ci_low"] <= p) & (p <= df["calibrated_detection_ci_high"])).all()
    for case in d.glob("*/summary.json"):
        summary = json.loads(case.read_text())["summary"]
        rows = {r["sensor"]: r for r in summary["rows"]}
        for per in summary["per_seed"]:
            healthy = per["healthy_margin_dB"]
            above = sum(h > rows[per["sensor"]]["calibrated_threshold_dB"] for h in healthy)
            assert len(healthy) == 12 and above <= 0.05 * len(healthy)
    for name in ("summary.png", "healthy_statistic.png", "roc.png"):
        assert (d / name).stat().st_size > 0


@pytest.mark.slow
def test_report_holds_every_figure_with_its_caption(ci_run: Path):
    out = snakemake("--configfile", "config/ci.yaml", "--report", "report.html", cwd=ci_run)
    assert out.returncode == 0, out.stderr[-3000:]
    html = (ci_run / "report.html").read_text()
    assert "System Message" not in html, "a caption is not valid reStructuredText"
    figures = sorted(p.name for p in (ci_run / "results/figures").glob("*.png"))
    assert figures
    for name in figures:
        assert name in html, name
        caption = REPO / "workflow/report" / f"{Path(name).stem}.rst"
        assert caption.exists(), f"{name} has no caption ({caption.name}) for the report"
        text = caption.read_text().replace("**", "").split(": ", 1)[-1]
        assert text[:25] in html, caption.name
    for caption in sorted((REPO / "workflow/report").glob("fig*.rst")):
        assert f"Fig. {caption.stem[3:].lstrip('0')}" in html, caption.name
