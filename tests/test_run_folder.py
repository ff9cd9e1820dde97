"""Results per run: the paper's case (`run: paper`, the default) writes results/, any other run results/<run>/
beside it, so a variant never overwrites the reproduction; run names that would mix with the paper's folders stop."""

import hashlib
import re

import pytest
from conftest import REPO, copy_repo, snakemake

from piezobearing import config


def test_the_paper_run_writes_results_and_another_run_a_folder_beside_it(paper_config):
    assert paper_config["run"] == config.PAPER_RUN
    assert config.results_folder(paper_config) == "results"
    assert config.results_folder({**paper_config, "run": "speed1500"}) == "results/speed1500"
    assert config.results_folder({}) == "results"  # a config without the key is the paper's case


def test_every_folder_the_rules_write_is_a_reserved_run_name():
    written = set()
    for smk in (REPO / "workflow/rules").glob("*.smk"):
        written.update(re.findall(r"\{RESULTS\}/([A-Za-z0-9_]+)/", smk.read_text()))
    assert written, "no {RESULTS}/<folder>/ paths found in workflow/rules"
    assert written <= config.RESULTS_FOLDERS, sorted(written - config.RESULTS_FOLDERS)


@pytest.mark.parametrize("name", sorted(config.RESULTS_FOLDERS))
def test_a_run_named_like_a_results_folder_stops_in_one_line(paper_config, name):
    with pytest.raises(config.ConfigError, match=rf"key 'run': '{name}' is a results folder") as e:
        config.validate({**paper_config, "run": name})
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("name", ["../elsewhere", "a/b", "", "Paper Case", "-x"])
def test_a_run_name_that_is_no_folder_name_stops(paper_config, name):
    with pytest.raises(config.ConfigError, match=r"key 'run'"):
        config.validate({**paper_config, "run": name})


def _job_paths(dry_run_stdout: str) -> list[str]:
    """The output, log and benchmark paths of every job a dry run lists."""
    paths = []
    for line in dry_run_stdout.splitlines():
        m = re.match(r"\s+(output|log|benchmark): (.*)", line)
        if m:
            paths.extend(p.strip() for p in m.group(2).split(","))
    return paths


def test_a_dry_run_of_another_run_writes_only_under_its_folder(tmp_path):
    variant = tmp_path / "speed1500.yaml"
    variant.write_text("run: speed1500\nbearing:\n  shaft_speed_rpm: 1500.0\n")
    out = snakemake("-n", "all", "study_all", "--configfile", "config/ci.yaml", str(variant))
    assert out.returncode == 0, out.stderr[-3000:]
    paths = _job_paths(out.stdout)
    assert len(paths) > 100, out.stdout[-3000:]
    outside = [p for p in paths if not p.startswith("results/speed1500/")]
    assert not outside, outside[:5]
    for kept in ("results/speed1500/scorecard.md", "results/speed1500/signals/", "results/speed1500/figures/"):
        assert any(p.startswith(kept) for p in paths), kept


def _sha256(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.slow
def test_a_variant_run_leaves_the_papers_results_untouched(tmp_path):
    """One cheap job for each run in a fresh copy: the paper's synthetic calibration record, then a variant's with
    another seed and a longer record: the variant's lands in results/<run>/, the paper's keeps its bytes."""
    work = copy_repo(tmp_path / "repo")
    (work / "variant.yaml").write_text("run: longer_record\nseed: 8\nsynthesis:\n  duration_s: 14.0\n")
    paper = work / "results/calibration/measurement.csv"
    variant = work / "results/longer_record/calibration/measurement.csv"

    out = snakemake("--cores", "1", str(paper.relative_to(work)), "--configfile", "config/ci.yaml",
                    cwd=work)
    assert out.returncode == 0, out.stderr[-3000:]
    before = _sha256(paper)
    out = snakemake("--cores", "1", str(variant.relative_to(work)), "--configfile", "config/ci.yaml",
                    "variant.yaml", cwd=work)
    assert out.returncode == 0, out.stderr[-3000:]
    assert variant.is_file()
    assert _sha256(paper) == before
    assert _sha256(variant) != before
    assert (work / "results/longer_record/logs/synthesize_calibration.log").is_file()
