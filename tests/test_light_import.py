"""``import piezobearing`` loads no heavy dependency and none of its own subpackages; ``piezobearing detect --help``
loads only the command line and the config; ``piezobearing detect`` on a MATLAB record loads no CSV table
reader, no other format's reader and no config validator; a public name is loaded on first use; writing results loads no
record reader (``piezobearing.io`` is lazy too). Each check runs a fresh
interpreter and reads ``sys.modules`` (what was loaded, never how long it took).

The code hash (:func:`piezobearing.workflow.registry.code_hash`) follows an entry's ``from piezobearing import name``
to the module that defines the name, and the face's own lazy table is not followed: editing a module reached only
through the face changes the hash of an entry that imports that name, and of no other (the same for the names of
``piezobearing.io``).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import piezobearing

SRC = Path(__file__).resolve().parents[1] / "src"

#: Dependencies that cost tenths of a second to seconds each; a bare import of the package loads none of them.
HEAVY = ("numpy", "scipy", "pandas", "matplotlib", "sfepy", "numba", "h5py", "pyuff", "nptdms", "meshio",
         "jsonschema", "snakemake", "tqdm")


def _loaded(code: str, pythonpath: Path = SRC) -> set[str]:
    """The top-level module names loaded by ``code`` in a fresh interpreter, plus this package's modules."""
    script = code + "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(pythonpath), "PATH": "/usr/bin:/bin"})
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


def test_import_piezobearing_loads_no_heavy_dependency_and_no_subpackage():
    loaded = _loaded("import piezobearing")
    assert not {m.split(".")[0] for m in loaded} & set(HEAVY)
    assert sorted(m for m in loaded if m.startswith("piezobearing")) == ["piezobearing"]


def test_detect_help_loads_the_command_line_and_the_config_only():
    code = "from piezobearing.cli import main\ntry:\n    main(['detect', '--help'])\nexcept SystemExit:\n    pass"
    loaded = _loaded(code)
    heavy = {m.split(".")[0] for m in loaded} & set(HEAVY)
    assert not heavy, heavy  # not even the config's schema validator: it loads where a config is validated
    assert sorted(m for m in loaded if m.startswith("piezobearing")) == [
        "piezobearing", "piezobearing.cli", "piezobearing.config",
    ]


#: What a detection on a record without a tachometer does without: filter design, distributions, splines,
#: optimisers (each 0.2-1 s of import).
NOT_FOR_DETECTION = ("scipy.signal", "scipy.stats", "scipy.interpolate", "scipy.optimize", "numba", "sfepy")


def test_detect_on_a_record_loads_no_filter_design_distribution_or_spline(tmp_path):
    """``piezobearing detect`` on a WAV record, with its report and figure written: the envelope detector's
    Butterworth gains are closed-form, its null's gamma quantiles come from scipy.special, and order tracking's
    splines load only for a tracked record."""
    code = (
        "import numpy as np\nfrom scipy.io import wavfile\n"
        "t = np.arange(24000) / 12000.0\n"
        "x = np.random.default_rng(0).normal(size=t.size) + np.sin(2 * np.pi * 3000.0 * t) * (np.sin(2 * np.pi * 107.4 * t) > 0.99)\n"
        f"wavfile.write({str(tmp_path / 'r.wav')!r}, 12000, x.astype(np.float32))\n"
        "from piezobearing.cli import main\n"
        f"assert main(['detect', {str(tmp_path / 'r.wav')!r}, '--bearing', 'SKF 6205', '--rpm', '1797', "
        f"'--out', {str(tmp_path / 'out')!r}]) == 0\n"
    )
    loaded = _loaded(code)
    assert (tmp_path / "out" / "detection.png").is_file() and (tmp_path / "out" / "report.md").is_file()
    assert not {m for m in loaded if m in NOT_FOR_DETECTION}, sorted(m for m in loaded if m in NOT_FOR_DETECTION)


#: What one record's detection from a MATLAB v5 file (as CWRU publishes them) does without: CSV tables (pandas),
#: the other formats' readers (h5py for v7.3, pyuff, npTDMS), the config's validator, a batch's progress bar.
NOT_FOR_A_MAT_RECORD = ("pandas", "h5py", "pyuff", "nptdms", "jsonschema", "tqdm")


def test_detect_on_a_matlab_record_loads_no_table_reader_or_other_format(tmp_path):
    """``piezobearing detect`` on a MATLAB v5 record (a channel and its ``*RPM`` variable, CWRU's layout), with
    its detection.json, report and figure written."""
    code = (
        "import numpy as np\nfrom scipy.io import savemat\n"
        "t = np.arange(24000) / 12000.0\n"
        "x = np.random.default_rng(0).normal(size=t.size) + np.sin(2 * np.pi * 3000.0 * t) * (np.sin(2 * np.pi * 107.4 * t) > 0.99)\n"
        f"savemat({str(tmp_path / 'r.mat')!r}, {{'X100_FE_time': x[:, None], 'X100RPM': np.array([[1797.0]])}})\n"
        "from piezobearing.cli import main\n"
        f"assert main(['detect', {str(tmp_path / 'r.mat')!r}, '--bearing', 'SKF 6205', '--fs', '12000', "
        f"'--out', {str(tmp_path / 'out')!r}]) == 0\n"
    )
    loaded = _loaded(code)
    assert all((tmp_path / "out" / name).is_file() for name in ("detection.json", "report.md", "detection.png"))
    heavy = {m.split(".")[0] for m in loaded} & set(NOT_FOR_A_MAT_RECORD)
    assert not heavy, sorted(heavy)
    assert not {m for m in loaded if m in NOT_FOR_DETECTION}, sorted(m for m in loaded if m in NOT_FOR_DETECTION)


@pytest.mark.parametrize("stage", ["signals", "scorecard", "calibration", "bearing", "sensor_fem"])
def test_a_workflow_stage_that_filters_nothing_loads_no_filter_design_or_distribution(stage):
    """The stages of most workflow jobs import the sensor's circuit types, the fit machinery and the effect
    catalogue; scipy.signal and scipy.stats (about a second of import together) load only where a function
    that needs them runs (a diagnosis, the calibration's impulses, the housing's peak check)."""
    loaded = _loaded(f"import piezobearing.stages.{stage}")
    assert not {m for m in loaded if m in ("scipy.signal", "scipy.stats")}


def test_a_public_name_is_loaded_on_first_use_and_stays():
    loaded = _loaded("import piezobearing\npiezobearing.Kinematics")
    assert "piezobearing.bearing.kinematics" in loaded and "piezobearing.api" not in loaded
    assert piezobearing.detect is piezobearing.api.detect
    assert "detect" in dir(piezobearing) and "signals" in dir(piezobearing)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        piezobearing.nothing  # noqa: B018


def test_the_face_names_every_subpackage_and_each_export_exists():
    package = SRC / "piezobearing"
    children = {p.stem for p in package.glob("*.py") if p.stem != "__init__"}
    children |= {p.parent.name for p in package.glob("*/__init__.py")}
    assert piezobearing._SUBMODULES == children
    for name, module in piezobearing._EXPORTS.items():
        assert getattr(__import__(module, fromlist=[name]), name) is getattr(piezobearing, name)


_HASH = (
    "import sys\nfrom piezobearing.workflow.registry import code_hash\nprint(code_hash(sys.argv[1]))"
)


def _hash(entry: Path, src: Path) -> str:
    out = subprocess.run([sys.executable, "-c", _HASH, str(entry)], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin"})
    return out.stdout.strip()


def _hashes_around_an_edit(tmp_path: Path, entries: list[str], module: str) -> tuple[list[str], list[str]]:
    """The code hash of each entry (a one-line script of ``entries``) in a copy of the package, before and after an
    edit of ``module`` (a path in the package)."""
    src = tmp_path / "src"
    shutil.copytree(SRC / "piezobearing", src / "piezobearing", ignore=shutil.ignore_patterns("__pycache__"))
    scripts = []
    for k, line in enumerate(entries):
        scripts.append(tmp_path / f"entry{k}.py")
        scripts[-1].write_text(line + "\n")
    before = [_hash(e, src) for e in scripts]
    edited = src / "piezobearing" / module
    edited.write_text(edited.read_text() + "\n# an edit\n")
    return before, [_hash(e, src) for e in scripts]


def test_the_code_hash_follows_a_name_imported_from_the_face(tmp_path):
    before, after = _hashes_around_an_edit(
        tmp_path, ["from piezobearing import Kinematics", "from piezobearing.sensor import materials"],
        "bearing/kinematics.py")
    assert after[0] != before[0]  # the rule that reaches kinematics through the face reruns
    assert after[1] == before[1]  # the face's other names are not followed: no other rule does


def test_writing_results_loads_no_record_reader():
    loaded = _loaded("from piezobearing.io import write_json, read_json")
    assert not {m.split(".")[0] for m in loaded} & {"h5py", "pyuff", "nptdms", "pandas"}  # pandas: where a CSV is read
    assert "scipy.io" not in loaded and "piezobearing.io.formats" not in loaded


def test_the_code_hash_follows_a_name_imported_from_the_lazy_io_package(tmp_path):
    before, after = _hashes_around_an_edit(
        tmp_path, ["from piezobearing.io import read_measurement", "from piezobearing.io import write_json"],
        "io/records.py")
    assert after[0] != before[0] and after[1] == before[1]
