"""An ordinary, non-editable install runs outside the checkout: the default config and schema are package data.

The package is built as a wheel from a clean copy of the checkout (``pip wheel --no-build-isolation``: the test
environment's pinned setuptools, nothing downloaded) and installed with ``pip --python`` into a new virtual
environment in a temporary folder (``--no-deps --no-index``). That environment then sees the test environment's
installed dependencies through one ``.pth`` line naming their site-packages folder (added after the install, so
pip never sees the test environment's own editable install). The console script runs in a folder outside the
checkout, with nothing of the checkout on ``PYTHONPATH``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
from conftest import CI_CONFIG, REPO, copy_repo

from piezobearing import config
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.io import write_measurement
from piezobearing.stages.calibration import nominal_circuit

pytestmark = pytest.mark.slow  # a wheel build, an install and a diagnosis in fresh processes


def run(*cmd, cwd: Path, env: dict | None = None, timeout: int = 600) -> subprocess.CompletedProcess:
    return subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path, dict]:
    """A new environment with the package installed from its wheel; its bin folder, a working folder outside
    the checkout and the environment to run in."""
    tmp = tmp_path_factory.mktemp("install")
    source = copy_repo(tmp / "source")
    build = run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
                "--wheel-dir", tmp / "dist", source, cwd=tmp)
    assert build.returncode == 0, build.stdout[-2000:] + build.stderr[-2000:]
    (wheel,) = (tmp / "dist").glob("piezobearing-*.whl")
    venv = tmp / "venv"
    made = run(sys.executable, "-m", "venv", "--without-pip", venv, cwd=tmp)
    assert made.returncode == 0, made.stderr[-2000:]
    python = venv / "bin" / "python"
    install = run(sys.executable, "-m", "pip", "--python", python, "install", "--no-deps", "--no-index", wheel,
                  cwd=tmp)
    assert install.returncode == 0, install.stdout[-2000:] + install.stderr[-2000:]
    site = Path(run(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])", cwd=tmp).stdout.strip())
    (site / "test_environment.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    work = tmp / "elsewhere"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return venv / "bin", work, env


def test_the_installed_package_is_the_wheels_not_the_checkouts(installed):
    bindir, work, env = installed
    out = run(bindir / "python", "-c",
              "from piezobearing import config; print(config.__file__); print(config.CONFIG_DIR)", cwd=work, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    module, defaults = (Path(line) for line in out.stdout.split())
    assert REPO not in module.parents and bindir.parent in module.parents
    for name in ("config.yaml", "schema.yaml"):  # real files, the same bytes as the checkout's config/
        assert not (defaults / name).is_symlink()
        assert (defaults / name).read_bytes() == (REPO / "config" / name).read_bytes(), name


def test_help_validate_and_diagnose_run_outside_the_checkout(installed, tmp_path):
    bindir, work, env = installed
    exe = bindir / "piezobearing"
    out = run(exe, "--help", cwd=work, env=env)
    assert out.returncode == 0 and "diagnose" in out.stdout, out.stderr[-2000:]

    c = config.load(CI_CONFIG)  # a short record (12 s at 500 Hz, 6 presses) keeps the diagnosis quick
    record = work / "press.csv"
    write_measurement(synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"]), record)
    out = run(exe, "validate", record.name, cwd=work, env=env)
    assert out.returncode == 0 and out.stdout.startswith("OK"), out.stdout[-2000:] + out.stderr[-2000:]

    out = run(exe, "diagnose", record.name, "--out", "diagnosis", cwd=work, env=env)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    assert (work / "diagnosis" / "diagnosis.json").stat().st_size > 0
    assert (work / "diagnosis" / "report.md").stat().st_size > 0
