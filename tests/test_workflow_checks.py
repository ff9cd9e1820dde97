"""The workflow's parse-time check of a diagnosis subject's config, done once per config and code."""

from __future__ import annotations

import copy
import json
import subprocess
import sys

import pytest

from piezobearing.diagnosis.effect import EffectError
from piezobearing.workflow import registry
from piezobearing.workflow.checks import check_subject_once

SUBJECTS = ("piezobearing.diagnosis.calibration.subject", "piezobearing.diagnosis.bearing.subject")
RULES = dict(zip(SUBJECTS, ("diagnose", "diagnose_bearing"), strict=True))


@pytest.mark.parametrize("subject", SUBJECTS)
def test_a_config_that_passed_is_checked_once(subject, paper_config, tmp_path):
    """The first start checks, the next one with the same settings remembers; a change of a key the rule reads
    is checked again, a change of another key is not."""
    rule = RULES[subject]
    assert check_subject_once(subject, rule, paper_config, tmp_path) is True
    assert check_subject_once(subject, rule, paper_config, tmp_path) is False
    assert len(list(tmp_path.glob("*.ok"))) == 1
    elsewhere = copy.deepcopy(paper_config)
    elsewhere["housing"]["n_modes"] += 1
    assert check_subject_once(subject, rule, elsewhere, tmp_path) is False
    other = copy.deepcopy(paper_config)
    other["seed"] += 1
    assert check_subject_once(subject, rule, other, tmp_path) is True
    assert len(list(tmp_path.glob("*.ok"))) == 2


@pytest.mark.parametrize(("subject", "section", "key"), [
    (SUBJECTS[0], "model", "effects"), (SUBJECTS[1], "bearing_diagnosis", "effects")])
def test_a_bad_effect_stops_every_start(subject, section, key, paper_config, tmp_path):
    """An unknown effect raises the subject's one-line error, and the failure is not remembered."""
    bad = copy.deepcopy(paper_config)
    bad[section][key] = ["ringing"]
    for _ in range(2):
        with pytest.raises(EffectError, match="unknown effect 'ringing'") as e:
            check_subject_once(subject, RULES[subject], bad, tmp_path)
        assert "\n" not in str(e.value)
    assert not list(tmp_path.glob("*.ok"))


def test_a_remembered_check_imports_no_model(paper_config, tmp_path):
    """With the check remembered, a start reads neither the subjects nor scipy.signal or numba."""
    for subject in SUBJECTS:
        check_subject_once(subject, RULES[subject], paper_config, tmp_path)
    code = (
        "import json, sys\n"
        "from piezobearing import config\n"
        "from piezobearing.workflow.checks import check_subject_once\n"
        f"ran = [check_subject_once(s, r, config.load(), {str(tmp_path)!r}) for s, r in {tuple(RULES.items())!r}]\n"
        "print(json.dumps([ran, sorted(m for m in ('scipy.signal', 'numba', *" + repr(SUBJECTS) + ") "
        "if m in sys.modules)]))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    ran, loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert ran == [False, False]
    assert loaded == []


def test_module_code_hash_follows_the_imports():
    """A subject's code hash covers the modules it imports (its models), not only its own file."""
    files = registry._closure([registry._module_file(SUBJECTS[1])])
    assert any(f.name == "lpm.py" for f in files) and any(f.name == "engine.py" for f in files)
    assert registry.module_code_hash(SUBJECTS[0]) != registry.module_code_hash(SUBJECTS[1])
    with pytest.raises(ValueError, match="not a module of this package"):
        registry.module_code_hash("piezobearing.no_such_module")
