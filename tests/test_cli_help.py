"""The command line describes itself: a paragraph per command in --help, every supported record format named,
and every command saying which config and which model it used."""

import pytest

from piezobearing import cli, config
from piezobearing.io.record_formats import RECORD_FORMATS

COMMANDS = ("diagnose", "diagnose-bearing", "validate", "hide-and-find")


def _help(capsys, *argv) -> str:
    with pytest.raises(SystemExit) as e:
        cli.main([*argv, "--help"])
    assert e.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def test_the_script_and_every_command_describe_themselves_in_a_paragraph(capsys):
    top = _help(capsys)
    assert "console script" not in top and len(cli.DESCRIPTION) > 300
    for command in COMMANDS:
        assert f"'{command}'" in cli.DESCRIPTION, command
        text = _help(capsys, command)
        description = text.split("positional arguments:")[0]
        assert len(description) > 300, (command, description)
    assert "'detect'" in cli.DESCRIPTION and "rig file" in cli.DESCRIPTION, "detect and its --config in the summary"


@pytest.mark.parametrize("command", ["validate", "diagnose", "diagnose-bearing"])
def test_the_record_commands_name_every_supported_format(capsys, command):
    text = _help(capsys, command)
    assert "calibration CSV" not in text
    for ext in RECORD_FORMATS:
        assert ext in text, (command, ext)


def test_diagnose_bearing_says_which_config_and_model_it_used(monkeypatch, capsys, tmp_path):
    """The command's own lines, around a stand-in for the diagnosis (the diagnosis itself: test_diagnosis_bearing)."""
    import piezobearing.stages.bearing_diagnosis as stage

    fit = {"nrmse": 0.03, "noise_floor_nrmse": 0.03}
    answer = {"record_warnings": [], "baseline": fit, "final": fit, "selected": [], "verdict": "explained",
              "fault": {"type": "none", "params": {}, "ci95": {}}, "unexplained": [],
              "sensor_model": {"fem_factor": 0.938, "source": "the sensor FEM"},
              "shaft_speed": {"rpm": 1000.0, "source": "bearing.shaft_speed_rpm of the default config"},
              "model_rate": {"reason": "recorded at 2550 Hz, held as it is"}}
    monkeypatch.setattr(stage, "diagnose_bearing", lambda *args, **kw: answer)
    assert cli.main(["diagnose-bearing", "record.csv", "--out", str(tmp_path / "out"), "--quiet"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("config: ") and lines[0].endswith("config.yaml")
    model = lines[1]
    assert model.startswith("model: 11-roller bearing (D_r 10 mm, D_p 44 mm) at 1000 rpm and 500 N")
    assert "influence line solved from the config" in model and "R = 50 MOhm" in model
    assert "shaft speed: 1000 rpm from bearing.shaft_speed_rpm of the default config" in lines[2]
    # a defect the record cannot pin down is said beside the fault, with why
    reason = "the interval of outer_defect_width_m reaches the widest defect the catalogue holds (3 mm)"
    answer["fault"]["unidentified"] = [{"effect": "outer_race_defect", "ci95": {}, "reason": reason}]
    assert cli.main(["diagnose-bearing", "record.csv", "--out", str(tmp_path / "out"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert f"left out, not identified: outer_race_defect: {reason}" in out
    assert out.index("fault: none") < out.index("left out, not identified") < out.index("verdict:")


def test_the_model_lines_follow_the_config():
    c = config.load()
    c["bearing"]["shaft_speed_rpm"] = 1500.0
    c["bearing_diagnosis"]["effects"] = ["outer_race_defect"]
    c["model"]["effects"] = ["channel_delay"]
    assert "at 1500 rpm" in cli._bearing_model(c, "infl.csv") and "influence line from infl.csv" in (
        cli._bearing_model(c, "infl.csv"))
    assert cli._bearing_model(c, None).endswith("effects switched on: outer_race_defect")
    assert "the apc850_paper disk 4.7 x 3.4 mm" in cli._calibration_model(c)
    assert cli._calibration_model(c).endswith("effects switched on: channel_delay")
