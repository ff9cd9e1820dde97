"""The fault type's call: the winning family and why the others lost, a fault of ``unknown`` type where the
families' margins do not separate, ``unknown`` counted as an alarm, and the grouped cross-validation that
chooses the call settings."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from piezobearing import cli
from piezobearing.signals import tuning
from piezobearing.signals.classification import confusion_matrix
from piezobearing.signals.detectors import UNKNOWN, Detection, envelope, is_alarm
from piezobearing.stages.recording import detect_recording, write_detection

DATA = Path(__file__).parent / "data" / "cwru"


@pytest.fixture(scope="module")
def fe37_loose():
    """fe37 (inner race, 21 mil: its impacts put lines into every family) with the fault frequencies'
    tolerance at 1 %: inner race +10.2 dB, outer race +9.4 dB, 0.8 dB apart."""
    return detect_recording(DATA / "fe37.mat", DATA / "fe37.yaml", settings=envelope.Settings(frequency_tolerance=0.01))


def test_families_nearer_than_the_separation_give_a_fault_of_unknown_type(fe37_loose, tmp_path, capsys):
    d = fe37_loose.detection
    typed = d.details["type_call"]
    assert d.fault_type == UNKNOWN and is_alarm(d.fault_type)
    assert typed["winner"] == "inner_race" and typed["runner_up"] == "outer_race"
    assert typed["candidates"] == ["inner_race", "outer_race"]
    assert typed["separation_dB"] == pytest.approx(typed["margins_dB"]["inner_race"] - typed["margins_dB"]["outer_race"],
                                                   rel=1e-12)
    assert 0 < typed["separation_dB"] < typed["required_separation_dB"] == 1.0
    assert d.margin_dB == max(f.margin_dB for f in d.families.values())  # the largest, as for none
    paths = write_detection(fe37_loose, tmp_path)
    written = json.loads(paths["json"].read_text())
    assert written["fault_type"] == "unknown" and written["type_call"]["candidates"] == ["inner_race", "outer_race"]
    assert written["summary"].startswith("fault of unknown type") and "candidates: inner race, outer race" in \
        written["summary"]
    report = paths["report"].read_text()
    assert "## Why this call" in report and "a type is called only 1 dB apart" in report
    assert Detection.from_dict(d.to_dict()).fault_type == UNKNOWN


def test_a_called_type_is_the_winning_family_and_the_report_says_why_the_others_lost(tmp_path, capsys):
    assert cli.main(["detect", str(DATA / "fe44.mat"), "--config", str(DATA / "fe44.yaml"), "--out",
                     str(tmp_path)]) == 0
    said = capsys.readouterr().out
    d = json.loads((tmp_path / "detection.json").read_text())
    typed = d["type_call"]
    assert d["fault_type"] == typed["winner"] == "outer_race" and typed["candidates"] == ["outer_race"]
    margins = {f: e["margin_dB"] for f, e in d["families"].items()}
    assert typed["margins_dB"]["outer_race"] == pytest.approx(max(margins.values()), rel=1e-12)
    assert set(typed["why_not"]) == {"inner_race", "rolling_element"}
    for family, why in typed["why_not"].items():
        below = margins["outer_race"] - typed["margins_dB"][family]
        assert why.startswith(f"{below:.1f} dB below the outer race") and below >= 1.0
        assert why.endswith("detected but not the largest" if d["families"][family]["detected"] else "not detected")
    report = (tmp_path / "report.md").read_text()
    assert "outer race: the winning family" in report and "the winning family" in d["summary"]
    assert "  outer race: the winning family" in said and "  inner race: " in said


def test_the_workflows_settings_keep_the_largest_margin_and_no_type_record():
    """The simulated records' settings (from the config) call the detected family of largest margin, as they
    always did: no unknown call and no type_call in the details, two lines above their threshold."""
    s = envelope.Settings.from_config({"detector": {"n_harmonics": 3, "n_sidebands": 1, "slip_max": 0.02},
                                       "false_alarm_probability": 1e-3, "band_rule": "kurtogram"})
    assert s.min_type_separation_dB is None and s.min_lines_above == 2
    rec = detect_recording(DATA / "fe37.mat", DATA / "fe37.yaml", settings=replace(
        envelope.Settings(frequency_tolerance=0.01), min_type_separation_dB=None))
    assert rec.detection.fault_type == "inner_race" and "type_call" not in rec.detection.details


def test_unknown_is_an_alarm_and_a_column_of_the_confusion_matrix_only_where_called():
    assert [is_alarm(c) for c in ("outer_race", "unknown", "none")] == [True, True, False]
    plain = confusion_matrix(["outer_race", "none"], ["outer_race", "none"])
    assert plain["classes"] == ["outer_race", "inner_race", "rolling_element", "none"]
    with_unknown = confusion_matrix(["outer_race", "inner_race", "none"], ["unknown", "inner_race", "unknown"])
    assert with_unknown["classes"] == ["outer_race", "inner_race", "rolling_element", "unknown", "none"]
    assert with_unknown["counts"][0][3] == 1 and with_unknown["counts"][4][3] == 1
    assert with_unknown["correct_rate"]["outer_race"] == 0.0


# --------------------------------------------------------------------------- the choice of the call settings


def test_an_unknown_call_is_neither_right_nor_wrong_and_a_healthy_records_alarm_is_false():
    truths = ["outer_race", "outer_race", "inner_race", "rolling_element", "none", "none"]
    calls = ["outer_race", "unknown", "outer_race", "none", "unknown", "none"]
    s = tuning.score(truths, calls)
    assert (s["right"], s["unknown"], s["wrong_type"], s["missed"], s["false_alarm"]) == (2, 1, 1, 1, 1)
    assert s["objective"] == 2 - tuning.WRONG_TYPE_COST * 2
    assert s["per_type"]["outer_race"] == {"right": 1, "wrong_type": 0, "unknown": 1, "missed": 0, "false_alarm": 0,
                                           "n": 2}


def _table(rows: list[tuple[float, list[str], list[float]]]) -> tuning.CallTable:
    """A call table of settings differing in the type rule's separation (and the frequency tolerance, to tell
    settings with the same separation apart): (separation, calls, separations) per setting."""
    settings = [envelope.Settings(min_type_separation_dB=sep, frequency_tolerance=0.001 * (i + 1))
                for i, (sep, _, _) in enumerate(rows)]
    return tuning.CallTable(settings, np.array([c for _, c, _ in rows], dtype=object),
                            [[{}] * len(rows[0][1]) for _ in rows], np.array([s for _, _, s in rows], dtype=float))


def test_the_separation_is_the_grids_first_value_above_every_wrong_type_call_and_cross_validation_holds_out():
    truths = ["outer_race", "inner_race", "inner_race", "rolling_element"]
    groups = ["a", "b", "b", "c"]
    nan = math.nan
    table = _table([
        # without the rule: record 2 is called outer race 0.7 dB above inner race, record 3 right 3 dB apart
        (0.0, ["outer_race", "inner_race", "outer_race", "rolling_element"], [5.0, 4.0, 0.7, 3.0]),
        (0.5, ["outer_race", "inner_race", "outer_race", "rolling_element"], [5.0, 4.0, 0.7, 3.0]),
        (1.0, ["outer_race", "inner_race", "unknown", "rolling_element"], [5.0, 4.0, nan, 3.0]),
        (4.0, ["outer_race", "unknown", "unknown", "unknown"], [5.0, nan, nan, nan]),
    ])
    assert tuning.wrong_type_separations(table, truths, range(4)) == [0.7]
    assert tuning.supported_separation(table, truths, range(4)) == 1.0
    assert tuning.supported_separation(table, truths, [0, 1, 3]) == 0.0  # no wrong type among these
    assert tuning.choose(table, truths, range(4)) == 2
    cv = tuning.cross_validate(table, truths, groups)
    # group b held out: the others show no wrong type, so the rule is off and record 2 is called wrong
    assert cv["chosen"] == {"a": 2, "b": 0, "c": 2}
    assert cv["calls"] == ["outer_race", "inner_race", "outer_race", "rolling_element"]
    assert cv["score"]["wrong_type"] == 1 and cv["score"]["right"] == 3
    with pytest.raises(ValueError, match="beyond the grid's largest separation 0.5 dB"):
        tuning.supported_separation(table, truths, range(4), values=(0.0, 0.5))
