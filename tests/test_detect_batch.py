"""``piezobearing detect`` over several records or a folder: a row per record in one table, each record's report
in its own folder, the rig file beside a record, the records' time from a field or the file name, a trend
figure, and a record that cannot be read stopping nothing."""

from __future__ import annotations

import json
import re
import shutil
from datetime import datetime
from pathlib import Path

import pandas as pd
import pytest
from conftest import copy_repo, snakemake
from scipy.io import loadmat, savemat

from piezobearing import cli
from piezobearing.stages.recording import RigError, detect_records, time_from_name

DATA = Path(__file__).parent / "data" / "cwru"
TRUTH = {"fe37": "inner_race", "fe39": "none", "fe44": "outer_race"}


@pytest.fixture()
def folder(tmp_path) -> Path:
    """The three CWRU records, each with its rig file beside it, and a file that is not a record."""
    d = tmp_path / "records"
    d.mkdir()
    for name in TRUTH:
        shutil.copy(DATA / f"{name}.mat", d)
        shutil.copy(DATA / f"{name}.yaml", d)
    (d / "fe50.mat").write_bytes(b"not a MATLAB file")
    shutil.copy(DATA / "fe39.yaml", d / "fe50.yaml")
    return d


def test_a_folder_gives_a_table_a_trend_and_a_report_per_record(folder, tmp_path, capsys):
    out = tmp_path / "out"
    code = cli.main(["detect", str(folder), "--out", str(out), "--quiet"])
    said = capsys.readouterr().out
    assert code == cli.EXIT_USER  # one record could not be read: the exit status says so, the rest ran
    table = pd.read_csv(out / "detections.csv")
    assert list(table["file"].map(lambda f: Path(f).stem)) == ["fe37", "fe39", "fe44", "fe50"]
    ok = table[table["status"] == "ok"]
    assert dict(zip(ok["file"].map(lambda f: Path(f).stem), ok["call"], strict=True)) == TRUTH
    for _, row in ok.iterrows():  # the row is the record's own detection.json
        d = json.loads((out / Path(row["file"]).stem / "detection.json").read_text())
        assert row["call"] == d["fault_type"] and row["shaft_speed_found_rpm"] == pytest.approx(
            d["shaft_speed_found_rpm"], rel=1e-5)
        for family in ("outer_race", "inner_race", "rolling_element"):
            assert row[f"{family}_margin_dB"] == pytest.approx(d["families"][family]["margin_dB"], rel=1e-5)
    bad = table[table["status"] == "error"].iloc[0]
    assert "fe50.mat: not a readable MATLAB" in bad["error"] and "\n" not in bad["error"]
    assert not (out / "fe50").exists()
    assert (out / "trend.png").stat().st_size > 10_000
    assert "3 of 4 records detected, 1 not read" in said and "fe50.mat: not read:" in said


def test_a_glob_picks_the_folders_records(folder, tmp_path, capsys):
    (folder / "labels.csv").write_text("record,fault_type\nfe37,inner_race\n")  # a table, not a record
    assert cli.main(["detect", str(folder), "--glob", "fe3*.mat", "--out", str(tmp_path / "out"), "--quiet"]) == 0
    table = pd.read_csv(tmp_path / "out" / "detections.csv")
    assert list(table["file"].map(lambda f: Path(f).name)) == ["fe37.mat", "fe39.mat"]
    assert cli.main(["detect", str(folder), "--glob", "*.wav", "--out", str(tmp_path / "o2")]) == cli.EXIT_USER
    assert "no record files in the folder (looked for '*.wav')" in capsys.readouterr().err


def test_options_apply_to_all_and_the_time_comes_from_the_name(folder, tmp_path):
    for name in TRUTH:  # no rig files: the options give what they held
        (folder / f"{name}.yaml").unlink()
    (folder / "fe50.mat").unlink()
    (folder / "fe50.yaml").unlink()
    stamps = {"fe44": "20240105_0600", "fe37": "20240103_0600", "fe39": "20240101_0600"}
    for name, stamp in stamps.items():
        (folder / f"{name}.mat").rename(folder / f"pump_{stamp}_{name}.mat")
    table = detect_records([folder], tmp_path / "out", bearing="SKF 6203", fs=12000.0, channel="_FE_time",
                           time_pattern="%Y%m%d_%H%M")
    assert list(table["time"]) == [datetime(2024, 1, 1, 6), datetime(2024, 1, 3, 6), datetime(2024, 1, 5, 6)]
    assert list(table["call"]) == ["none", "inner_race", "outer_race"] and (table["status"] == "ok").all()
    with pytest.raises(RigError, match="no time matching --time-from-name '%Y-%m-%d'"):
        time_from_name("pump_20240101_0600_fe39.mat", "%Y-%m-%d")


def test_the_time_from_a_field_and_several_jobs_give_the_same_table(tmp_path):
    d = tmp_path / "records"
    d.mkdir()
    hours = {"fe44": 300.0, "fe37": 100.0, "fe39": 200.0}
    for name, h in hours.items():
        v = loadmat(DATA / f"{name}.mat")
        channel = next(k for k in v if k.endswith("_FE_time"))
        savemat(d / f"{name}.mat", {"run": {"acc": v[channel], "fs": 12000, "hours": h, "rpm": 1797.0}})
    one = detect_records([d], tmp_path / "one", bearing="SKF 6203", fs="run.fs", channel="run.acc",
                         time_field="run.hours")
    two = detect_records(sorted(d.iterdir()), tmp_path / "two", bearing="SKF 6203", fs="run.fs", channel="run.acc",
                         time_field="run.hours", jobs=2)
    assert list(one["x"]) == [100.0, 200.0, 300.0] and list(one["call"]) == ["inner_race", "none", "outer_race"]
    cols = [c for c in one.columns if c != "out"]
    pd.testing.assert_frame_equal(one[cols].reset_index(drop=True), two[cols].reset_index(drop=True))


def test_a_batch_with_nothing_to_read_or_two_records_of_one_name_stops_with_one_line(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cli.main(["detect", str(empty), "--out", str(tmp_path / "o")]) == cli.EXIT_USER
    assert "no record files in the folder" in capsys.readouterr().err
    for sub in ("a", "b"):
        (tmp_path / sub).mkdir()
        shutil.copy(DATA / "fe39.mat", tmp_path / sub)
    code = cli.main(["detect", str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == cli.EXIT_USER and "fe39: two records share this name" in err and len(err.strip().splitlines()) == 1


def _jobs(dry_run: str) -> dict[str, int]:
    table = dry_run.split("Job stats:")[-1]
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"^(\w+)\s+(\d+)$", table, re.M)
            if m.group(1) not in ("total", "job")}


@pytest.mark.slow
def test_the_archive_rule_detects_each_record_once_outside_rule_all(tmp_path):
    repo = copy_repo(tmp_path / "repo")
    archive = tmp_path / "archive"
    archive.mkdir()
    for name in ("fe37", "fe44"):
        shutil.copy(DATA / f"{name}.mat", archive)
        shutil.copy(DATA / f"{name}.yaml", archive)
    cfg = tmp_path / "archive.yaml"
    cfg.write_text(f"detect_archive:\n  folder: {archive}\n")
    run = snakemake("--cores", "1", "detect_archive", "--configfile", "config/ci.yaml", str(cfg), cwd=repo)
    assert run.returncode == 0, run.stderr[-3000:]
    table = pd.read_csv(repo / "results" / "detect_archive" / "detections.csv")
    assert list(table["call"]) == ["inner_race", "outer_race"] and list(table["order"]) == [1, 2]
    assert (repo / "results" / "detect_archive" / "trend.png").stat().st_size > 10_000
    assert json.loads((repo / "results" / "detect_archive" / "fe44" / "detection.json").read_text())[
        "fault_type"] == "outer_race"
    shutil.copy(DATA / "fe39.mat", archive)  # a new record: its job and the table, nothing else
    shutil.copy(DATA / "fe39.yaml", archive)
    again = snakemake("-n", "detect_archive", "--configfile", "config/ci.yaml", str(cfg), cwd=repo)
    assert _jobs(again.stdout) == {"detect_record": 1, "detect_archive": 1}, again.stdout[-2000:]
    everything = snakemake("-n", "--forceall", "--configfile", "config/ci.yaml", str(cfg), cwd=repo)
    assert everything.returncode == 0 and not {"detect_record", "detect_archive"} & set(_jobs(everything.stdout))
