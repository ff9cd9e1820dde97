"""The site's figures are a workflow run's, recorded in provenance.json, and the build's check catches a stale one."""

import copy
import importlib.util
import json
import re
import sys
from pathlib import Path

from piezobearing.workflow.registry import READS

REPO = Path(__file__).resolve().parents[1]
FIGURES = REPO / "docs" / "_static" / "figures"


def _extension():
    spec = importlib.util.spec_from_file_location("piezobearing_figures", REPO / "docs" / "_ext" / "piezobearing_figures.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_every_figure_on_the_site_has_its_provenance():
    record = json.loads((FIGURES / "provenance.json").read_text())
    on_disk = {p.name for p in FIGURES.glob("*.png")}
    assert on_disk == set(record["figures"]), on_disk ^ set(record["figures"])
    used = set()
    for page in (REPO / "docs").rglob("*.md"):
        used |= set(re.findall(r"_static/figures/([\w.]+\.png)", page.read_text()))
    assert used and used <= on_disk, used - on_disk


def test_the_figures_are_the_current_code_and_config():
    assert _extension().stale_figures(json.loads((FIGURES / "provenance.json").read_text())) == []


def test_a_figure_of_other_code_or_config_is_caught():
    ext = _extension()
    record = json.loads((FIGURES / "provenance.json").read_text())
    before = set(ext.stale_figures(record))
    name = next(n for n in record["figures"] if not any(p.startswith(f"{n}:") for p in before))
    other_code, other_config = copy.deepcopy(record), copy.deepcopy(record)
    other_code["figures"][name]["code_hash"] = "0" * 64
    other_config["figures"][name]["config_digest"] = "0" * 12
    assert set(ext.stale_figures(other_code)) - before == {
        f"{name}: made by other code than the current {record['figures'][name]['entry']} and its imports"
    }
    assert set(ext.stale_figures(other_config)) - before == {
        f"{name}: made with other config values than rule {record['figures'][name]['rule']} now reads"
    }


def test_a_figure_of_another_run_is_checked_against_its_own_config():
    """A guide's figure made by another run (the detect guide's, on docs/_data/detect_archive.yaml) names that
    run's config file; checked against the paper's config instead, its rule's config values differ."""
    ext = _extension()
    record = json.loads((FIGURES / "provenance.json").read_text())
    others = [n for n, f in record["figures"].items() if "configfiles" in f]
    assert "detect_fe44.png" in others
    before = set(ext.stale_figures(record))
    name = others[0]
    assert not any(p.startswith(f"{name}:") for p in before)
    without = copy.deepcopy(record)
    del without["figures"][name]["configfiles"]
    assert set(ext.stale_figures(without)) - before == {
        f"{name}: made with other config values than rule {record['figures'][name]['rule']} now reads"
    }


def test_every_figure_of_another_run_names_its_script_and_a_validation_figure_a_rule_that_declares_its_config():
    """Each figure of another run names an existing config file and script; a validation script's figure (no
    Snakemake target) names the rule whose declared config values the script reads, so that its config digest
    digests them (a rule without declared values would digest nothing and never go stale)."""
    spec = importlib.util.spec_from_file_location("docs_figures", REPO / "scripts" / "docs_figures.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.RUN_FIGURES["validation"][1] is None
    for group, (configfile, target, figures) in module.RUN_FIGURES.items():
        assert (REPO / configfile).is_file(), group
        for name, rule, entry, _title, _path in figures:
            assert (REPO / entry).is_file(), (group, name, entry)
            if target is None:
                assert READS.get(rule), (group, name, rule)
