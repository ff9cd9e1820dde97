"""The fault_detection study kind: one case on a CI-sized config, bearing to indicator, and its summary."""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from piezobearing.stages.studies import KINDS, run_case, summarize

SUMMARY_KEYS = {
    "bpfo_Hz",
    "indicator_healthy",
    "indicator_faulty",
    "threshold",
    "detection_rate_healthy",
    "detection_rate_faulty",
}


@pytest.fixture()
def tiny(tmp_path, ci_config):
    """CI config cut further: 0.35 s record (0.25 s analysed), coarse housing mesh, 5 noise seeds, no FEM input."""
    cfg = copy.deepcopy(ci_config)
    cfg["bearing"].update(duration_s=0.35, settle_s=0.01)
    cfg["housing"].update(mesh_level=0.35, n_modes=4)
    cfg["signals"].update(study_n_seeds=5, sensor_fem_correction=False)
    res = tmp_path / "resistance.json"
    res.write_text(json.dumps({"resistance_ohm": 50.0e6}))
    return cfg, str(res)


def test_one_case_detects_the_fault_and_gathers(tmp_path, tiny):
    cfg, res = tiny
    rpm, width = 1200.0, 0.9e-3
    out = tmp_path / "fd" / "case" / "summary.json"
    ov = {"bearing__shaft_speed_rpm": rpm, "bearing__defects__0__width_m": width}
    run_case("fault_detection", "case", ov, cfg, str(out), {"resistance": res})
    d = json.loads(out.read_text())
    s = d["summary"]
    assert SUMMARY_KEYS <= set(s)
    # BPFO = Z/2 f_shaft (1 - D_r/D_p) with the case's speed, not the config's 1000 rpm
    assert s["bpfo_Hz"] == pytest.approx(5.5 * rpm / 60 * (1 - 10 / 44), rel=1e-12)
    # a roller centre crosses the groove at the cage speed on the outer raceway, (D_p + D_r)/2 = 27 mm
    ftf = 0.5 * rpm / 60 * (1 - 10 / 44)
    assert s["defect_crossing_s"] == pytest.approx(width / (0.027 * 2 * np.pi * ftf), rel=1e-12)
    assert s["indicator_faulty"] > 10 * s["indicator_healthy"]
    assert s["indicator_faulty"] > s["threshold"] > 0
    assert s["detection_rate_faulty"] == 1.0
    assert s["detection_rate_healthy"] <= 0.2  # 5 seeds: at most one false alarm
    # in memory: the case folder holds its summary only (no intermediate files written and deleted)
    assert [p.name for p in out.parent.iterdir()] == ["summary.json"]
    summarize(
        "fault_detection", [str(out)], str(tmp_path / "fd" / "summary.csv"), str(tmp_path / "fd" / "s.png")
    )
    row = pd.read_csv(tmp_path / "fd" / "summary.csv").iloc[0]
    assert row["bearing__shaft_speed_rpm"] == rpm and row["indicator_faulty"] == pytest.approx(
        s["indicator_faulty"]
    )
    assert (tmp_path / "fd" / "s.png").stat().st_size > 10_000


def test_fem_correction_without_its_input_is_named(tmp_path, tiny):
    cfg, res = tiny
    cfg = copy.deepcopy(cfg)
    cfg["signals"]["sensor_fem_correction"] = True
    with pytest.raises(ValueError, match="harmonic.csv"):
        KINDS["fault_detection"](cfg, tmp_path, resistance=res)
