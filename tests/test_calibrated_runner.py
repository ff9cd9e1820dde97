"""The calibrated runner's width sweep: a case's faulty seeds judged against another case's healthy ones
(``--healthy-of``), and the smallest detected width the report adds.

Seed records are written by hand here (the runner's JSON-lines format) so that the reduction is checked without
running the rig: the rig's own realisations are checked by tests/test_sensor_comparison.py.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def runner():
    spec = importlib.util.spec_from_file_location("calibrated_runner",
                                                  REPO / "validation" / "sensor_comparison_calibrated.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _rows(case: str, faulty: bool, margins: np.ndarray) -> list[dict]:
    called = "outer_race" if faulty else "none"
    return [{"case": case, "faulty": faulty, "replicate": k,
             "pzt": {"called": called, "margin_dB": float(m)},
             "accelerometer": {"called": called, "margin_dB": float(m - 3.0)}} for k, m in enumerate(margins)]


def test_healthy_sources_names_cases_of_the_run(runner):
    assert runner.healthy_sources(["w02=rest"], ["rest", "w02"]) == {"w02": "rest"}
    with pytest.raises(SystemExit, match="--healthy-of w02=frame"):
        runner.healthy_sources(["w02=frame"], ["rest", "w02"])
    with pytest.raises(SystemExit, match="two different"):
        runner.healthy_sources(["rest=rest"], ["rest", "w02"])


def test_a_width_sweep_borrows_the_healthy_seeds_and_finds_the_smallest_width(runner, tmp_path):
    """Hide-and-find: healthy margins N(0, 1); a wide groove's far above the 0.05 threshold, a narrow one's at
    the healthy level. The sweep's rows take the reference's 40 healthy seeds (its own healthy records, written
    to the file as a decoy far above, are ignored), and the smallest detected width is the wide groove's."""
    rng = np.random.default_rng(3)
    healthy = rng.standard_normal(40)
    rows = (_rows("rest", False, healthy) + _rows("rest", True, 10.0 + rng.standard_normal(20))
            + _rows("w01", True, rng.standard_normal(20)) + _rows("w01", False, np.full(5, 50.0)))
    out = tmp_path / "seeds.jsonl"
    out.write_text("".join(json.dumps(r) + "\n" for r in rows))
    report = tmp_path / "report.json"
    runner.main(["--configfile", str(REPO / "config" / "config.yaml"),
                 "--case", "rest:base_motion__level=0.0",
                 "--case", "w01:base_motion__level=0.0,bearing__defects__0__width_m=0.1e-3",
                 "--healthy-of", "w01=rest", "--out", str(out), "--report", str(report)])
    table = {(r["case"], r["sensor"]): r for r in json.loads(report.read_text())["cases"]}
    wide, narrow = table[("rest", "pzt")], table[("w01", "pzt")]
    assert wide["n_healthy_seeds"] == narrow["n_healthy_seeds"] == 40
    assert narrow["healthy_seeds_of"] == "rest"
    assert narrow["calibrated_threshold_dB"] == pytest.approx(wide["calibrated_threshold_dB"], rel=1e-12)
    assert wide["calibrated_detection_probability"] == 1.0
    assert narrow["calibrated_detection_probability"] < 0.5
    assert wide["smallest_detected_width_m"] == narrow["smallest_detected_width_m"] == pytest.approx(0.9e-3)
    assert (tmp_path / "report_roc.png").exists() and (tmp_path / "report_healthy_statistic.png").exists()


def test_a_reference_of_another_fault_type_or_rig_is_refused(runner, tmp_path):
    """A seed record holds its case's true family's margin: an inner-race case judged against an outer-race case's
    healthy seeds would compare two families' statistics, and another speed is another rig; both stop with one line
    naming the pair, before any seed runs or any report is written. A width alone passes."""
    base = ["--configfile", str(REPO / "config" / "config.yaml"), "--case", "rest:base_motion__level=0.0"]
    out, report = tmp_path / "seeds.jsonl", tmp_path / "report.json"
    out.write_text("".join(json.dumps(r) + "\n" for r in _rows("rest", False, np.zeros(5))))
    for case, message in [("ir:base_motion__level=0.0,bearing__defects__0__type=inner_race", "fault types differ"),
                          ("fast:base_motion__level=0.0,bearing__shaft_speed_rpm=2000.0", "differ outside bearing.defects"),
                          ("moved:base_motion__level=1.0", "base_motion")]:
        label = case.split(":")[0]
        for mode in ([], ["--report", str(report)]):
            with pytest.raises(SystemExit, match=f"--healthy-of {label}=rest: .*{message}"):
                runner.main([*base, "--case", case, "--healthy-of", f"{label}=rest", "--out", str(out), *mode])
    assert not report.exists()
    configs = {label: runner.case_config(runner.config_loader.load(str(REPO / "config" / "config.yaml")), o,
                                         source=label)
               for label, o in map(runner.parse_case, ["rest:base_motion__level=0.0",
                                                       "w02:base_motion__level=0.0,bearing__defects__0__width_m=0.2e-3"])}
    runner.check_borrowed(configs, {"w02": "rest"})  # the width sweep's pair: no exit
