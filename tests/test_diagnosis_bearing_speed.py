"""The running-bearing diagnosis's nominal shaft speed: ``--rpm``, the rig file's, the record's scalar ``*RPM``
variable (a .mat file, as ``piezobearing detect`` reads it), the default config's, in that order.

A synthetic record of a shaft at 1040 rpm (4 % over the default config's 1000 rpm, twice the fitted speed's
tolerance) written as a .mat file with its ``X105RPM`` variable: the command starts from the record's speed and
explains the record with the healthy bearing.
"""

import copy
import json

import pandas as pd
import pytest
import yaml
from scipy.io import savemat

from piezobearing.cli import main
from piezobearing.diagnosis.bearing.subject import synthesise
from piezobearing.stages.bearing_diagnosis import shaft_speed_given

RECORD_RPM = 1040.0


@pytest.fixture(scope="module")
def mat_record(ci_config, ci_influence, tmp_path_factory):
    """(record.mat holding voltage_V, sample_rate_Hz and X105RPM, influence line CSV, the config)."""
    c = copy.deepcopy(ci_config)
    c["bearing_diagnosis"].update(synthetic_duration_s=0.5, synthetic_sample_rate_Hz=2550.0, synthetic_snr_dB=30.0)
    influence = ci_influence
    rec = synthesise({**c, "bearing": {**c["bearing"], "shaft_speed_rpm": RECORD_RPM}}, 5, [], influence)
    d = tmp_path_factory.mktemp("speed")
    savemat(d / "record.mat", {"voltage_V": rec.voltage_V[:, None], "sample_rate_Hz": 2550.0,
                               "X105RPM": RECORD_RPM})
    pd.DataFrame({"angle_rad": influence.angle_rad, "sensor_per_radial_load": influence.sensor_per_radial_load}).to_csv(
        d / "influence.csv", index=False)
    return d / "record.mat", d / "influence.csv", c


def test_speed_order_rpm_rig_record_default(mat_record):
    path, _, c = mat_record
    assert shaft_speed_given(path, c, 990.0, True)["source"] == "--rpm"
    given = shaft_speed_given(path, c, None, True)
    assert given["rpm"] == c["bearing"]["shaft_speed_rpm"] and given["record_rpm"] == RECORD_RPM
    given = shaft_speed_given(path, c, None, False)
    assert given["rpm"] == RECORD_RPM and "X105RPM" in given["source"]


def test_cli_reads_the_records_rpm_variable(mat_record, tmp_path, capsys):
    path, influence, c = mat_record
    rig = tmp_path / "rig.yaml"  # the CI mesh's housing is the influence line's; no shaft speed in the rig file
    rig.write_text(yaml.safe_dump({"diagnostics": {"max_steps": 1}}))
    out = tmp_path / "out"
    assert main(["diagnose-bearing", str(path), "--out", str(out), "--config", str(rig), "--influence",
                 str(influence), "--quiet"]) == 0
    d = json.loads((out / "diagnosis.json").read_text())
    assert d["shaft_speed"]["rpm"] == RECORD_RPM and "X105RPM" in d["shaft_speed"]["source"]
    assert "shaft speed: 1040 rpm from the record's X105RPM variable" in capsys.readouterr().out
    assert d["selected"] == [] and d["verdict"] == "explained", (d["selected"], d["verdict"])
    assert d["final"]["params"]["shaft_speed_Hz"] == pytest.approx(RECORD_RPM / 60, rel=1e-3)
    assert not d["record_warnings"]
    # --rpm stands before the record's: 1000 rpm is 4 % off, the record's variable is named in a warning
    out2 = tmp_path / "out2"
    assert main(["diagnose-bearing", str(path), "--out", str(out2), "--config", str(rig), "--influence",
                 str(influence), "--quiet", "--rpm", "1000"]) == 0
    d2 = json.loads((out2 / "diagnosis.json").read_text())
    assert d2["shaft_speed"]["source"] == "--rpm"
    assert any("X105RPM states 1040 rpm" in w for w in d2["record_warnings"]), d2["record_warnings"]
