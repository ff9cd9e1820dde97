"""The scorecard states its conditions: row labels from the config, the run's conditions beside the paper's case,
and only rows whose conditions are the paper's compared with the paper (the paper's config against a 1500 rpm one)."""

import copy

import pandas as pd
import pytest

from piezobearing.config import paper
from piezobearing.scorecard import NOT_THE_PAPERS_CASE, Row, assemble, changed_conditions
from piezobearing.scorecard import bearing as bearing_rows
from piezobearing.scorecard import signals as signals_rows
from piezobearing.workflow.registry import declared


def _kinematics(b: dict) -> dict:
    """Roller-bearing frequencies [Hz] of the config's ``bearing`` section (zero contact angle)."""
    fr = b["shaft_speed_rpm"] / 60
    ratio = b["roller_diameter_m"] / b["pitch_diameter_m"]
    ftf = fr / 2 * (1 - ratio)
    return {"shaft_Hz": fr, "ftf_Hz": ftf, "bpfo_Hz": b["n_rollers"] * ftf,
            "bpfi_Hz": b["n_rollers"] * (fr - ftf), "bsf_Hz": fr / (2 * ratio) * (1 - ratio**2)}


def _bearing_results() -> tuple[dict, dict, dict, dict]:
    """lpm.json, the transient records, mesh_convergence.json and sampling_phase.json, with made-up numbers of the
    right shape (the rows' arithmetic on them is not what these tests check)."""
    lpm = {
        "healthy": {"mean_vertical_load_N": 500.0, "harris_roller_at_bottom": {"max_rel_diff": 0.01},
                    "harris_rollers_straddling": {"max_rel_diff": 0.02}},
        "faulty": {"defect_max_drop_m": 20e-6, "defects": [{"max_drop_flat_raceway_m": 25e-6}], "n_impacts": 70,
                   "impact_frequency_Hz": 70.8},
    }
    case = {"direct_check": {"rms_rel_diff": 1e-3, "duration_s": 0.05}, "first_natural_frequency_Hz": 3500.0,
            "sensor_force_mean_N": 10.0, "sensor_force_max_N": 12.0, "sensor_force_min_N": 8.0}
    conv = {"levels": [{"level": lv, "n_dofs": n, "peak_to_peak_N": 4.0} for lv, n in ((0.7, 1), (1.0, 2), (1.4, 3))]}
    samp = {"sample": {"bpfo_amplitude_spread": 0.3}, "average": {"bpfo_amplitude_spread": 0.01}}
    return lpm, {"healthy": case, "faulty": case}, conv, samp


def _signal_results(snr_dB: float) -> tuple[dict, dict]:
    ind = {c: {"detected": c == "faulty", "indicator": 30.0, "threshold": 20.0, "false_alarm_probability": 1e-3,
               "band_Hz": [300.0, 1200.0], "in_band_snr_dB": -20.0} for c in ("healthy", "faulty")}
    rates = {"detection_rate_at_snr": 1.0, "detection_limit_dB": -3.0, "snr_50pct_dB": -6.0,
             "first_snr_rate_above_dB": 20.0}
    study = {"snr_dB": snr_dB, "n_seeds": 10, "faulty": rates, "healthy": rates, "required_detection_rate": 0.95,
             "band_rule": "fixed", "other_band_rule": {"band_rule": "kurtogram", "healthy": rates}}
    return ind, study


def _card(tmp_path, config: dict) -> tuple[pd.DataFrame, str]:
    """The scorecard of the bearing and signal rows under ``config``, through the fragments' CSV files."""
    from piezobearing.scorecard import write_part

    kin = _kinematics(config["bearing"])
    lpm, tr, conv, samp = _bearing_results()
    ind, study = _signal_results(config["signals"]["snr_dB"])
    parts = [tmp_path / "bearing.csv", tmp_path / "signals.csv"]
    write_part(bearing_rows.rows(kin, lpm, tr, conv, samp, config["bearing"]), parts[0])
    write_part(signals_rows.rows(ind, study, kin), parts[1])
    df = assemble(parts, tmp_path / "scorecard.csv", tmp_path / "scorecard.md", declared(config, "scorecard"))
    assert pd.read_csv(tmp_path / "scorecard.csv").shape == df.shape
    return df.set_index("quantity"), (tmp_path / "scorecard.md").read_text()


@pytest.fixture
def speed1500(paper_config) -> dict:
    c = copy.deepcopy(paper_config)
    c["run"] = "speed1500"
    c["bearing"]["shaft_speed_rpm"] = 1500.0
    return c


def test_the_papers_case_is_compared_row_by_row(tmp_path, paper_config):
    assert changed_conditions(paper_config) == []
    df, md = _card(tmp_path, paper_config)
    assert "This run is the paper's case" in md and NOT_THE_PAPERS_CASE not in md
    assert "**differs**" not in md
    bpfo = df.loc["BPFO at 1000 rpm"]
    assert bpfo["compared"] and bpfo["rel_error"] == pytest.approx(70.83 / 70.8 - 1, abs=2e-4)
    assert df.loc["BPFO (11 rollers, 1000 rpm)", "compared"]
    assert "steps per roller passage: every sample at the same phase" in df.loc["FEM time step", "note"]


def test_a_1500_rpm_run_states_its_conditions_and_is_not_scored_as_the_paper(tmp_path, speed1500):
    assert changed_conditions(speed1500) == ["bearing.shaft_speed_rpm"]
    df, md = _card(tmp_path, speed1500)
    # labels follow the config: no row names the paper's speed as if it were this run's
    assert "BPFO at 1500 rpm" in df.index and "BPFO (11 rollers, 1500 rpm)" in df.index
    assert not any("1000 rpm" in q for q in df.index)
    # the run's conditions, listed beside the paper's case; the one that differs marked
    assert f"(`{tmp_path / 'scorecard.md'}`)" in md  # where this run's scorecard is
    speed_line = next(line for line in md.splitlines() if "`bearing.shaft_speed_rpm`" in line and "| 1500 |" in line)
    assert "| 1000 |" in speed_line and "**differs**" in speed_line
    assert md.count("**differs**") == 1
    # rows depending on the speed: the paper's number shown, not compared; the others still compared
    for q in ("BPFO at 1500 rpm", "shaft speed", "defect impact frequency (LPM)",
              "outer-ring fault detected, faulty bearing (1 = yes)"):
        assert not df.loc[q, "compared"] and pd.isna(df.loc[q, "rel_error"]), q
        assert not pd.isna(df.loc[q, "paper"]), q
    for q in ("radial load", "rollers", "FEM time step", "SNR of the added white noise", "defect width"):
        assert df.loc[q, "compared"], q
    row = next(line for line in md.splitlines() if line.startswith("| IV | BPFO at 1500 rpm"))
    assert f"{NOT_THE_PAPERS_CASE} (`bearing.shaft_speed_rpm`)" in row
    # the time-step note is computed for this run: 1/(36 BPFO) at 1500 rpm, and the phase drift it implies
    note = df.loc["FEM time step", "note"]
    bpfo = _kinematics(speed1500["bearing"])["bpfo_Hz"]
    assert f"{1 / (36 * bpfo):.7g} s" in note and "24 steps per roller passage" in note


def test_every_condition_a_row_names_is_one_of_the_papers_case():
    with pytest.raises(KeyError, match="not a key of piezobearing.config.paper.CASE"):
        Row("IV", "x", 1.0, 1.0, "-", "", ("bearing.shaft_speed",))
    assert set(paper.DETECTION) <= set(paper.CASE)


def test_the_papers_case_is_the_default_config(paper_config, ci_config):
    """The default config is the paper's case, and the CI config (shorter records, coarser meshes) too."""
    assert changed_conditions(paper_config) == [] and changed_conditions(ci_config) == []
    other = copy.deepcopy(paper_config)
    other["bearing"]["defects"][0]["width_m"] = 0.5e-3
    other["sensor"]["material"] = "pzt5a"
    assert changed_conditions(other) == ["bearing.defects", "sensor.material"]
