"""Shared fixtures: the validated configs and synthetic calibration records."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from piezobearing import config as cfg
from piezobearing.stages.calibration import nominal_circuit
from piezobearing.synthesis import PressProtocol, synthesize

os.environ.setdefault("OMP_NUM_THREADS", "1")


@pytest.fixture(scope="session")
def paper_config() -> dict:
    return cfg.load()


@pytest.fixture(scope="session")
def ci_config() -> dict:
    return cfg.load(cfg.CONFIG_DIR / "ci.yaml")


@pytest.fixture(scope="session")
def paper_record(paper_config):
    """The default synthetic calibration record (25 s, 1 kHz, 13 presses, R = 50 MOhm)."""
    c = paper_config
    return synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"])


# --------------------------------------------------------------------------- end-to-end workflow runs

REPO = Path(__file__).resolve().parents[1]


def _copy_repo(dest: Path) -> Path:
    """Copy the files a clean checkout has (tracked and untracked-but-not-ignored) to ``dest``."""
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"], cwd=REPO, capture_output=True, text=True, check=True
    ).stdout.split()
    for f in files:
        src = REPO / f
        if src.is_file():
            (dest / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / f)
    return dest


def run_workflow(
    workdir: Path, *args: str, configfiles: tuple[str, ...] = ("config/ci.yaml",), timeout: int = 1200
) -> subprocess.CompletedProcess:
    """Run snakemake (from this interpreter's environment) in ``workdir`` with the CI config."""
    exe = Path(sys.executable).with_name("snakemake")
    return subprocess.run(
        [str(exe), "--cores", "2", *args, "--configfile", *configfiles],
        cwd=workdir,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def dry_run_errors(configfile: Path) -> tuple[subprocess.CompletedProcess, list[str]]:
    """`snakemake -n --configfile FILE` in the repository; its result and its `piezobearing:` error lines."""
    exe = Path(sys.executable).with_name("snakemake")
    out = subprocess.run(
        [str(exe), "-n", "--configfile", str(configfile)], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    return out, [line for line in out.stderr.splitlines() if line.startswith("piezobearing:")]


@pytest.fixture(scope="session")
def ci_run(tmp_path_factory) -> Path:
    """A complete `snakemake --cores 2 --configfile config/ci.yaml` in a fresh copy; its folder."""
    work = _copy_repo(tmp_path_factory.mktemp("ci_run"))
    out = run_workflow(work)
    assert out.returncode == 0, out.stderr[-4000:]
    return work


@pytest.fixture(scope="session")
def ci_rerun(tmp_path_factory) -> Path:
    """A second, independent clean run of the same workflow, for reproducibility checks."""
    work = _copy_repo(tmp_path_factory.mktemp("ci_rerun"))
    out = run_workflow(work)
    assert out.returncode == 0, out.stderr[-4000:]
    return work
