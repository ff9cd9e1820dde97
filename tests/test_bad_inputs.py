"""Every bad input a user can give: one line naming the file or key and the fix, exit status 1, no
traceback, data/ untouched. The messages collected here ARE the table in docs/reference/bad_inputs.md:
``test_table_is_current`` fails when the table differs from what the code prints; regenerate it with
``PIEZOBEARING_WRITE_TABLE=1 pytest tests/test_bad_inputs.py``.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
from conftest import CI_CONFIG, copy_repo, snakemake
from scipy.io import savemat

from piezobearing import cli, config
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.io import write_measurement
from piezobearing.stages.calibration import nominal_circuit

REPO = Path(__file__).resolve().parents[1]
TABLE = REPO / "docs" / "reference" / "bad_inputs.md"
CI = "seed: 7\nsynthesis: {duration_s: 12.0, sample_rate_Hz: 500.0, n_impulses: 6}\n"


def data_checksums() -> dict[str, str]:
    """SHA-256 of every file under the checkout's data/."""
    return {
        str(p.relative_to(REPO)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted((REPO / "data").rglob("*"))
        if p.is_file()
    }


@pytest.fixture(autouse=True)
def data_untouched():
    before = data_checksums()
    yield
    assert data_checksums() == before, "a bad input changed data/"


# --------------------------------------------------------------------------- the files of the cases


#: The session's pytest temporary-folder factory (set by :func:`_temporary_folders`).
_TMP: dict = {}


@pytest.fixture(scope="session", autouse=True)
def _temporary_folders(tmp_path_factory):
    """The cases' folder goes under pytest's temporary folder (pytest keeps the last three sessions' and removes
    older ones), not a folder of its own in /tmp that nobody removes (4 MB a test session). Session-scoped: the
    module's tests stay free to run on either xdist worker."""
    _TMP["factory"] = tmp_path_factory
    yield
    _TMP.clear()


@functools.cache
def workdir() -> Path:
    """One folder with the good record and every bad file and config of the cases."""
    d = _TMP["factory"].mktemp("bad_inputs")
    c = config.load(CI_CONFIG)
    m = synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"])
    write_measurement(m, d / "record.csv")
    df = m.to_frame()
    (d / "ci.yaml").write_text(CI)
    (d / "a_folder").mkdir()
    (d / "empty.csv").write_text("")
    text = (d / "record.csv").read_text()
    (d / "latin1.csv").write_bytes(("# Kraftmessung, Prüfstand 2\n" + text).encode("latin-1"))
    df.to_csv(d / "decimal_comma.csv", index=False, decimal=",")  # pandas quotes "0,002"
    lines = text.splitlines()
    (d / "decimal_comma_unquoted.csv").write_text(
        "\n".join(
            [lines[0], *(line.replace(",", ";").replace(".", ",").replace(";", ",") for line in lines[1:])]
        )
        + "\n"
    )
    df.to_csv(d / "semicolon.csv", index=False, sep=";", decimal=",")
    df.rename(columns={"voltage_V": "volts"}).to_csv(d / "renamed.csv", index=False)
    bad = df.astype({"force_N": object})
    bad.loc[10, "force_N"] = "n/a"
    bad.to_csv(d / "cell.csv", index=False)
    df.assign(voltage_V=0.0).to_csv(d / "dead_voltage.csv", index=False)
    df.assign(force_N=0.0).to_csv(d / "dead_force.csv", index=False)
    df.assign(voltage_V=0.25).to_csv(d / "constant_voltage.csv", index=False)
    df.assign(voltage_V=df["voltage_V"].clip(-0.5, 0.5)).to_csv(d / "clipped_voltage.csv", index=False)
    noise = np.random.default_rng(1).normal(0.0, 2.0e-3, len(df))
    df.assign(voltage_V=noise).to_csv(d / "flat_voltage.csv", index=False)
    df.assign(voltage_V=-df["voltage_V"]).to_csv(d / "inverted.csv", index=False)
    df[df["time_s"] < 2.5].to_csv(d / "one_press.csv", index=False)
    df.assign(time_s=1e3 * df["time_s"]).to_csv(d / "milliseconds.csv", index=False)
    df.drop(index=range(500, 505)).to_csv(d / "uneven.csv", index=False)
    back = df.copy()
    back.loc[100, "time_s"] = back.loc[98, "time_s"]
    back.to_csv(d / "time_back.csv", index=False)
    configs = {
        "syntax.yaml": "calibration: {measurement: [data.csv\n",
        "list.yaml": "- seed: 3\n- sensor: {}\n",
        "unknown_key.yaml": "synthesis:\n  resistence_ohm: 20.0e+6\n",
        "string_number.yaml": "synthesis:\n  resistance_ohm: 50e6\n",
        "nan.yaml": "sensor:\n  cable_length_m: .nan\n",
        "pitch.yaml": "bearing:\n  pitch_diameter_m: 5.0e-3\n",
        "defect.yaml": "bearing:\n  defects:\n    - {type: outer_race, width_m: 12.0e-3, depth_m: 1.0e-3, angle_deg: 0.0}\n",
        "mesh_level.yaml": "sensor_fem:\n  mesh_level: 5\n",
        "rollers.yaml": "bearing:\n  n_rollers: 14\n",
        "flat_roller.yaml": "bearing:\n  defects:\n    - {type: rolling_element, width_m: 0.9e-3, depth_m: 1.0e-3, "
        "angle_deg: 0.0, roller: 11}\n",
        "band.yaml": "signals:\n  band_Hz: [1250.0, 500.0]\n",
        "waviness.yaml": "bearing:\n  waviness_orders: [2, 3]\n  waviness_amplitudes_m: [1.0e-6]\n",
        "tail.yaml": "sensor_comparison:\n  tail_false_alarm_rate: 0.2\n  tail_fraction: 0.1\n",
        "effect.yaml": CI + "model: {effects: [ringing]}\n",
    }
    for name, body in configs.items():
        (d / name).write_text(body)
    (d / "a_config_folder").mkdir()
    (d / "out_file").write_text("not a folder\n")
    signal = np.random.default_rng(2).standard_normal((12000, 1)) + 2.5
    savemat(d / "struct.mat", {"bearing": {"gs": signal, "sr": np.int32(12000), "rate": 29.95, "unit": "g"}})
    (d / "two_speeds.yaml").write_text("bearing: {designation: SKF 6203}\nshaft_speed_rpm: 1797\n"
                                       "shaft_speed_Hz: bearing.rate\n")
    return d


# --------------------------------------------------------------------------- the cases


@dataclass(frozen=True)
class Case:
    """One bad input: the command (CLI arguments or a snakemake call) and a fragment of its message."""

    name: str
    args: tuple[str, ...]
    expect: str
    kind: str = "cli"  # cli | workflow
    code: int = 1
    setup: Callable | None = None  # (monkeypatch) -> None, for cases that need a patched environment


def _unreadable(monkeypatch):
    from piezobearing.io import formats

    real = open

    def fake(path, *a, **k):
        if str(path).endswith("unreadable.csv"):
            raise PermissionError(13, "Permission denied", str(path))
        return real(path, *a, **k)

    (workdir() / "unreadable.csv").write_text((workdir() / "record.csv").read_text())
    monkeypatch.setattr(formats, "open", fake, raising=False)


def _bug(monkeypatch):
    import piezobearing.stages.calibration as stage

    def broken(*a, **k):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(stage, "load_record", broken)


W = "{w}"  # the cases' folder, filled in when run
V = ("validate",)
REC = f"{W}/record.csv"
CASES = [
    # the record: its file, encoding, separators, columns, cells and clock
    Case("record is a folder", (*V, f"{W}/a_folder"), "is a folder, not a file"),
    Case("record cannot be read", (*V, f"{W}/unreadable.csv"), "cannot be read", setup=_unreadable),
    Case("record missing", (*V, f"{W}/nope.csv"), "file not found"),
    Case("record empty", (*V, f"{W}/empty.csv"), "the file is empty"),
    Case("record in Latin-1", (*V, f"{W}/latin1.csv"), "save it as UTF-8"),
    Case("decimal commas (quoted cells)", (*V, f"{W}/decimal_comma.csv"), "use a dot as the decimal mark"),
    Case(
        "decimal commas (unquoted)", (*V, f"{W}/decimal_comma_unquoted.csv"), "use a dot as the decimal mark"
    ),
    Case("semicolon separator", (*V, f"{W}/semicolon.csv"), "separated by ';'"),
    Case("column misnamed", (*V, f"{W}/renamed.csv"), "column 'voltage_V' missing"),
    Case("non-numeric cell", (*V, f"{W}/cell.csv"), "line 12, column force_N"),
    Case("dead voltage channel (all 0 V)", (*V, f"{W}/dead_voltage.csv"), "dead channel"),
    Case("constant voltage channel", (*V, f"{W}/constant_voltage.csv"), "constant at 0.25"),
    Case("clipped voltage channel", (*V, f"{W}/clipped_voltage.csv"), "clipped"),
    Case("flat voltage channel (noise only)", (*V, f"{W}/flat_voltage.csv"), "flat"),
    Case("dead force channel", (*V, f"{W}/dead_force.csv"), "column force_N: every sample is 0"),
    Case("inverted polarity", (*V, f"{W}/inverted.csv"), "polarity inverted"),
    Case("one press only", (*V, f"{W}/one_press.csv"), "at least 2 are needed"),
    Case("time in milliseconds", (*V, f"{W}/milliseconds.csv"), "is time in milliseconds?"),
    Case("uneven clock", (*V, f"{W}/uneven.csv"), "resample_to_uniform: true"),
    Case("time going back", (*V, f"{W}/time_back.csv"), "time does not increase"),
    # the config (point 7, 8)
    Case("config: YAML syntax error", (*V, REC, "--config", f"{W}/syntax.yaml"), "YAML syntax error at line"),
    Case("config: top level is a list", (*V, REC, "--config", f"{W}/list.yaml"), "not a mapping of keys"),
    Case("config: a folder", (*V, REC, "--config", f"{W}/a_config_folder"), "is a folder, not a config file"),
    Case("config: missing", (*V, REC, "--config", f"{W}/none.yaml"), "config file not found"),
    Case("config: misspelt key", (*V, REC, "--config", f"{W}/unknown_key.yaml"), "did you mean"),
    Case("config: 50e6 (a string in YAML)", (*V, REC, "--config", f"{W}/string_number.yaml"), "50.0e+6"),
    Case("config: .nan", (*V, REC, "--config", f"{W}/nan.yaml"), ".nan is not a finite number"),
    Case("config: pitch below roller", (*V, REC, "--config", f"{W}/pitch.yaml"), "bearing.pitch_diameter_m"),
    Case("config: defect wider than roller", (*V, REC, "--config", f"{W}/defect.yaml"), "not narrower than"),
    Case("config: mesh level not listed", (*V, REC, "--config", f"{W}/mesh_level.yaml"), "listed levels"),
    Case("config: rollers do not fit", (*V, REC, "--config", f"{W}/rollers.yaml"), "do not fit"),
    Case("config: flat on a roller that does not exist", (*V, REC, "--config", f"{W}/flat_roller.yaml"),
         "does not exist"),
    Case("config: band decreasing", (*V, REC, "--config", f"{W}/band.yaml"), "write [low, high]"),
    Case("config: waviness amplitudes short", (*V, REC, "--config", f"{W}/waviness.yaml"),
         "one amplitude per order"),
    Case("config: tail rate above its fraction", (*V, REC, "--config", f"{W}/tail.yaml"), "below the fraction"),
    # diagnose --out (point 4)
    Case(
        "--out is a file", ("diagnose", REC, "--out", f"{W}/out_file", "--quiet"), "is a file, not a folder"
    ),
    Case("--out empty", ("diagnose", REC, "--out", "", "--quiet"), "--out is empty"),
    Case(
        "--out under a file", ("diagnose", REC, "--out", f"{W}/out_file/sub", "--quiet"), "is a file, so no"
    ),
    Case(
        "--out cannot be created",
        ("diagnose", REC, "--out", "/proc/piezobearing", "--quiet"),
        "cannot create",
    ),
    Case("--out inside data/", ("diagnose", REC, "--out", "data/diagnosis", "--quiet"), "never written"),
    Case(
        "unknown effect",
        ("diagnose", REC, "--out", f"{W}/o", "--config", f"{W}/effect.yaml", "--quiet"),
        "ringing",
    ),
    Case(
        "failed diagnosis (dead channel)",
        ("diagnose", f"{W}/dead_voltage.csv", "--out", f"{W}/never/made", "--quiet"),
        "dead channel",
    ),
    # usage and bugs (point 11)
    # a vibration record for fault detection (piezobearing detect)
    Case("detect: channel not in the struct", ("detect", f"{W}/struct.mat", "--bearing", "SKF 6203", "--fs",
                                                "bearing.sr", "--channel", "bearing.acc", "--out", f"{W}/det"),
         "channel 'bearing.acc' not found (the file holds channels bearing.gs [12000]; scalar fields"),
    Case("detect: rate field holds text", ("detect", f"{W}/struct.mat", "--bearing", "SKF 6203", "--fs",
                                           "bearing.unit", "--out", f"{W}/det"), "holds the text 'g', not a number"),
    Case("detect: both speed units in the rig file", ("detect", f"{W}/struct.mat", "--config",
                                                      f"{W}/two_speeds.yaml", "--out", f"{W}/det"),
         "both shaft_speed_rpm and shaft_speed_Hz given"),
    Case("detect: no --out", ("detect", f"{W}/struct.mat"), "--out is missing"),
    Case("usage: argument missing", ("validate",), "the following arguments are required", code=2),
    Case("internal error (a bug)", (*V, REC), "internal error (ZeroDivisionError", code=3, setup=_bug),
    # the workflow refuses the same inputs before any job (dry run in the checkout)
    Case("workflow: record is a folder", (f"{W}/a_folder",), "is a folder, not a file", kind="workflow"),
    Case("workflow: dead voltage channel", (f"{W}/dead_voltage.csv",), "dead channel", kind="workflow"),
    Case("workflow: pitch below roller", (f"{W}/pitch.yaml",), "bearing.pitch_diameter_m", kind="workflow"),
    Case("workflow: .nan in the config", (f"{W}/nan.yaml",), ".nan is not a finite number", kind="workflow"),
]


def _normalise(text: str, w: Path) -> str:
    text = text.replace(os.path.relpath(w, REPO), "<tmp>")  # the workflow names config files relative to it
    text = text.replace(str(w), "<tmp>").replace(str(REPO), "<repo>")
    text = re.sub(r"\bpid \d+|\bkill \d+", lambda m: m.group(0).split()[0] + " <pid>", text)
    return re.sub(r" at [\w./-]+\.py:\d+", " at <file>:<line>", text)


def run_case(case: Case, monkeypatch, capsys) -> tuple[int, str]:
    """Run one case; its exit status and its one stderr line (normalised for the table)."""
    w = workdir()
    args = [a.replace(W, str(w)) for a in case.args]
    if case.kind == "workflow":
        target = Path(args[0])
        conf = target if target.suffix == ".yaml" else w / f"measurement_{target.stem}.yaml"
        if conf != target:
            conf.write_text(f"calibration:\n  measurement: {target}\n")
        out = snakemake("-n", "--configfile", "config/ci.yaml", str(conf))
        assert "Traceback" not in out.stderr + out.stdout
        lines = [ln for ln in out.stderr.splitlines() if ln.startswith("piezobearing:")]
        assert len(lines) == 1, out.stderr[-3000:]
        return out.returncode, _normalise(lines[0], w)
    if case.setup:
        case.setup(monkeypatch)
    monkeypatch.chdir(REPO)
    capsys.readouterr()
    try:
        code = cli.main(args)
    except SystemExit as e:  # argparse's usage errors
        code = e.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    return code, _normalise(lines[-1] if lines else "", w)


MESSAGES: dict[str, tuple[int, str]] = {}


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_bad_input_gets_one_line(case, monkeypatch, capsys):
    code, line = run_case(case, monkeypatch, capsys)
    assert code == case.code, line
    assert case.expect in line, line
    assert line.startswith(("piezobearing:", "usage:", "piezobearing validate: error:")), line
    if case.name.startswith("failed diagnosis"):
        assert not (workdir() / "never").exists()  # no empty output folder left behind
    MESSAGES[case.name] = (code, line)


def render(messages: dict[str, tuple[int, str]]) -> str:
    rows = [
        "# Bad inputs and what they get",
        "",
        "Generated by `tests/test_bad_inputs.py` from what the code prints (regenerate with",
        "`PIEZOBEARING_WRITE_TABLE=1 pytest tests/test_bad_inputs.py`; the test fails when this table is out",
        "of date). `piezobearing validate` / `diagnose` run in the checkout; the workflow rows are",
        "`snakemake -n --configfile config/ci.yaml FILE`. `<tmp>` is the folder of the bad files. Exit",
        "status: 1 user error, 2 usage error, 3 internal error. No case prints a traceback, and data/ is",
        "unchanged after every one (checked).",
        "",
        "| case | command | exit | message |",
        "|---|---|---|---|",
    ]
    for c in CASES:
        code, line = messages[c.name]
        if c.kind == "workflow":
            target = c.args[0].replace(W, "<tmp>")
            given = f"config {target}" if target.endswith(".yaml") else f"calibration.measurement: {target}"
            cmd = f"snakemake -n ({given})"
        else:
            cmd = "piezobearing " + " ".join(a.replace(W, "<tmp>") if a else "''" for a in c.args)
        message = line.replace("|", "\\|")
        rows.append(f"| {c.name} | `{cmd}` | {code} | {message} |")
    return "\n".join(rows) + "\n"


def test_table_is_current(monkeypatch, capsys):
    for c in CASES:
        if c.name not in MESSAGES:  # deselected or run alone: run it here
            with monkeypatch.context() as mp:
                MESSAGES[c.name] = run_case(c, mp, capsys)
    text = render(MESSAGES)
    if os.environ.get("PIEZOBEARING_WRITE_TABLE"):
        TABLE.parent.mkdir(exist_ok=True)
        TABLE.write_text(text)
    assert TABLE.exists() and TABLE.read_text() == text, (
        "docs/reference/bad_inputs.md is out of date: PIEZOBEARING_WRITE_TABLE=1 pytest tests/test_bad_inputs.py"
    )


@pytest.mark.slow
def test_record_path_with_spaces_reaches_the_figure(tmp_path):
    """A record in 'my records/press test.csv' passes validation, the rules and the papermill figure job.

    A real run of the figure's two jobs (``extract_sensitivity``, a Python script, and ``fig05``, papermill and a
    kernel)."""
    work = copy_repo(tmp_path / "checkout")
    rec = tmp_path / "my records" / "press test.csv"
    rec.parent.mkdir()
    rec.write_text((workdir() / "record.csv").read_text())
    (tmp_path / "user config.yaml").write_text(f"calibration:\n  measurement: {rec}\n")
    out = snakemake(
        "--cores", "2", "results/figures/fig05.png", "--configfile", "config/ci.yaml",
        str(tmp_path / "user config.yaml"), cwd=work,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert (work / "results/figures/fig05.png").stat().st_size > 10_000
    nb = (work / "results/notebooks/fig05_calibration_impulses.ipynb").read_text()
    assert str(rec) in nb  # the notebook got the whole path, spaces and all
