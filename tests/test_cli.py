"""The ``piezobearing`` console script: diagnose and validate, with one-line errors and no tracebacks."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from piezobearing.cli import main
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.io import write_measurement
from piezobearing.stages.calibration import nominal_circuit

CI_OVERRIDE = "seed: 7\nsynthesis: {duration_s: 12.0, sample_rate_Hz: 500.0, n_impulses: 6}\n"


@pytest.fixture(scope="module")
def files(tmp_path_factory, ci_config) -> dict:
    """A short record with a 15 ms channel delay, a config file, a broken CSV."""
    d = tmp_path_factory.mktemp("cli")
    c = ci_config
    m = synthesize(
        PressProtocol.from_config(c["synthesis"]),
        nominal_circuit(c),
        c["seed"],
        [{"name": "channel_delay", "params": {"delay_s": 0.015}}],
    )
    write_measurement(m, d / "record.csv")
    (d / "ci.yaml").write_text(CI_OVERRIDE)
    (d / "bad_effect.yaml").write_text(CI_OVERRIDE + "model: {effects: [ringing]}\n")
    (d / "bad_key.yaml").write_text("diagnostics: {max_step: 3}\n")
    (d / "broken.csv").write_text("time_s,force_N,volts\n0,0,0\n0.001,0,0\n0.002,0,0\n")
    return {"dir": d, "record": d / "record.csv"}


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "piezobearing.cli", *args], capture_output=True, text=True)


def test_validate_ok(files, capsys):
    assert main(["validate", str(files["record"])]) == 0
    out = capsys.readouterr().out
    assert out.startswith("OK: ") and "500 Hz" in out and "6 impulses" in out


def test_validate_says_the_voltage_is_clipped(files, capsys):
    """The largest press just touches the DAQ's range: 4 samples held at its top (fewer than the reader's
    error limit for a clipped channel). validate accepts the file (exit 0) and says in one line that the
    voltage is stuck there, naming the column, the level and the fix."""
    import pandas as pd

    df = pd.read_csv(files["record"])
    v = df["voltage_V"].to_numpy().copy()
    i = int(np.argmax(v))
    v[i - 1 : i + 3] = v[i]
    clipped = files["dir"] / "clipped.csv"
    df.assign(voltage_V=v).to_csv(clipped, index=False)
    assert main(["validate", str(clipped)]) == 0
    warn = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("WARNING")]
    assert len(warn) == 1 and "voltage_V is stuck at" in warn[0] and "clipped" in warn[0] and "range" in warn[0]
    assert main(["validate", str(files["record"])]) == 0
    assert "WARNING" not in capsys.readouterr().out


def test_hide_and_find_says_whether_the_diagnosis_finds_the_hidden_effect(files, capsys):
    """A 15 ms channel delay (the effect's example size: no --param needed) hidden in the CI-sized record:
    found first, its fitted value printed beside the hidden one, exit 0; an unknown effect or parameter is
    one line naming it (exit 1)."""
    ci = str(files["dir"] / "ci.yaml")
    assert main(["hide-and-find", "channel_delay", "--config", ci]) == 0
    out = capsys.readouterr().out
    assert "hidden: channel_delay {'delay_s': 0.015} (the effect's example)" in out
    assert "ranked first: channel_delay" in out and "verdict: explained" in out and out.rstrip().endswith("FOUND")
    line = [ln for ln in out.splitlines() if ln.strip().startswith("delay_s =")][0]
    assert "(hidden 0.015)" in line and abs(float(line.split("=")[1].split()[0]) - 0.015) < 1e-4
    assert main(["hide-and-find", "no_such_effect", "--config", ci]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown effect 'no_such_effect'" in err[0] and "channel_delay" in err[0]
    assert main(["hide-and-find", "channel_delay", "--param", "delay_ms=15", "--config", ci]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--param delay_ms" in err[0] and "delay_s" in err[0]


def test_validate_runs_the_workflows_checks(files, capsys):
    # A file the workflow rejects before any job must not pass validate: inverted polarity, one press.
    import pandas as pd

    df = pd.read_csv(files["record"])
    inverted = files["dir"] / "inverted.csv"
    df.assign(voltage_V=-df["voltage_V"]).to_csv(inverted, index=False)
    assert main(["validate", str(inverted)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "polarity inverted" in err[0] and "inverted.csv" in err[0]
    one_press = files["dir"] / "one_press.csv"
    df[df["time_s"] < 2.5].to_csv(one_press, index=False)
    assert main(["validate", str(one_press)]) == 1
    assert "at least 2 are needed" in capsys.readouterr().err
    assert main(["validate", str(files["record"]), "--config", str(files["dir"] / "bad_key.yaml")]) == 1
    assert "max_step" in capsys.readouterr().err


def test_validate_bad_file_is_one_line_without_traceback(files, capsys):
    """The console script's own process (``python -m piezobearing.cli``): a broken file is one line on stderr, no
    traceback, exit status 1. A missing file goes the same way out of ``main`` (its return value is the process's
    exit status, as the first case shows), so it is checked in this process: one process start less (0.5 s of
    CPU); the same assertions."""
    r = run_cli("validate", str(files["dir"] / "broken.csv"))
    assert r.returncode == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr
    assert "column 'voltage_V' missing" in lines[0] and "broken.csv" in lines[0]
    capsys.readouterr()
    rc = main(["validate", str(files["dir"] / "nope.csv")])
    err = capsys.readouterr().err
    assert rc == 1 and len(err.strip().splitlines()) == 1 and "not found" in err and "Traceback" not in err


def test_diagnose_writes_json_report_and_figures(files, capsys):
    out = files["dir"] / "out"
    rc = main(
        [
            "diagnose",
            str(files["record"]),
            "--out",
            str(out),
            "--config",
            str(files["dir"] / "ci.yaml"),
            "--quiet",
        ]
    )
    assert rc == 0
    printed = capsys.readouterr().out
    assert "verdict: explained" in printed and "channel_delay" in printed
    d = json.loads((out / "diagnosis.json").read_text())
    assert d["selected"] == ["channel_delay"]
    assert d["config"]["calibration"]["measurement"] == str(files["record"])
    assert d["config"]["diagnostics"]["min_delta_bic"] == 10.0
    report = (out / "report.md").read_text()
    for name in ("overlay", "residuals", "spectrum", "correlations", "ranking", "ladder"):
        assert (out / "figures" / f"{name}.png").stat().st_size > 10_000
        assert f"(figures/{name}.png)" in report
    assert "Most likely missing: `channel_delay`" in report and "Verdict: explained" in report
    assert (out / "diagnosis.npz").exists()


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ("bad_effect.yaml", "model.effects[0]: unknown effect 'ringing'"),
        ("bad_key.yaml", "key 'diagnostics.max_step' is not a config key"),
        ("missing.yaml", "config file not found"),
    ],
)
def test_diagnose_user_errors_are_one_line(files, config, message, capsys):
    """In this process (``main``, as the console script calls it: an exception would fail the test with its
    traceback); the console script's own process is test_validate_bad_file_is_one_line_without_traceback's."""
    rc = main(
        [
            "diagnose",
            str(files["record"]),
            "--out",
            str(files["dir"] / "x"),
            "--config",
            str(files["dir"] / config),
            "--quiet",
        ]
    )
    err = capsys.readouterr().err
    assert rc == 1
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1 and message in err
    assert not (files["dir"] / "x" / "diagnosis.json").exists()


def test_console_script_is_declared():
    text = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
    assert 'piezobearing = "piezobearing.cli:main"' in text
