"""The studies guide lists, for each study of the configs, its target and the number of its cases."""

import re

from conftest import CI_CONFIG, REPO, snakemake

from piezobearing import config
from piezobearing.config.cases import check_studies

GUIDE = REPO / "docs" / "guides" / "studies.md"


def test_the_guide_gives_each_studys_target_and_cases():
    rows = {}
    for line in GUIDE.read_text().splitlines():
        m = re.match(r"\| `(\w+)` \| `snakemake --cores 2 (study_\w+)` \| (\d+) \| (\d+|-) \|", line)
        if m:
            rows[m.group(1)] = (m.group(2), int(m.group(3)), 0 if m.group(4) == "-" else int(m.group(4)))
    paper = {k: len(v) for k, v in check_studies(config.load()).items()}
    ci = {k: len(v) for k, v in check_studies(config.load(CI_CONFIG)).items()}
    assert set(rows) == set(paper)
    for name, (target, n_paper, n_ci) in rows.items():
        assert target == f"study_{name}" and n_paper == paper[name] and n_ci == ci.get(name, 0), name
    total = re.search(r"\| all seven \| `snakemake --cores 2 study_all` \| (\d+) \| (\d+) \|", GUIDE.read_text())
    assert (int(total.group(1)), int(total.group(2))) == (sum(paper.values()), sum(ci.values()))


def test_a_study_target_runs_that_study_only():
    """`snakemake -n study_calibration_circuit` on the CI config: its two cases and its summary, none of the
    other study's jobs."""
    out = snakemake("-n", "study_calibration_circuit", "--configfile", "config/ci.yaml")
    assert out.returncode == 0, out.stderr[-3000:]
    blocks = re.split(r"^(?:local)?rule ", out.stdout, flags=re.M)[1:]  # one job each: its name, then its lines
    jobs = [(b.split(":", 1)[0], "".join(re.findall(r"wildcards: (.*)", b))) for b in blocks]
    studies = {w for rule, w in jobs if rule in ("study_case", "study_summary")}
    assert studies and all("study=calibration_circuit" in w for w in studies), studies
    assert sum(rule == "study_case" for rule, _ in jobs) == 2
    assert "sensor_design_housing" not in out.stdout
