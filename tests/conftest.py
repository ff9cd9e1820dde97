"""Shared fixtures: the validated configs, synthetic calibration records and real workflow runs.

Workflow tests start the environment's ``snakemake`` as a subprocess, exactly as a user does; its jobs
(Python scripts, papermill and the notebooks' kernels) are the ordinary processes Snakemake starts.
One complete run of the CI config (:func:`ci_run`) is shared by every test that reads its results: under
``pytest -n 2`` the first worker that needs it runs it while holding a file lock, and the other waits for it
and reads the same folder.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from piezobearing import config
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.stages.calibration import nominal_circuit

REPO = Path(__file__).resolve().parents[1]
CI_CONFIG = REPO / "config" / "ci.yaml"
#: The environment's bin folder: its ``snakemake``, ``ruff`` and ``snakefmt``.
BIN = Path(sys.executable).parent

os.environ.setdefault("OMP_NUM_THREADS", "1")
# The test command installs with `pip install --no-compile`; where the environment also sets
# PYTHONDONTWRITEBYTECODE=1, every Snakemake process and job of the suite would compile NumPy, SciPy, pandas and
# Snakemake from source again (`snakemake -n` on the CI config: 6.6 s of CPU, 3.0 s with the bytecode written).
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False


@pytest.fixture(scope="session")
def paper_config() -> dict:
    return config.load()


@pytest.fixture(scope="session")
def ci_config() -> dict:
    return config.load(CI_CONFIG)


@pytest.fixture(scope="session")
def ci_influence(ci_config):
    """The CI config's healthy housing solved once per test process for its influence line: the running-bearing
    tests' rig (their configs change the record and the search, not the housing)."""
    from piezobearing.stages.bearing_diagnosis import influence_from_config

    return influence_from_config(ci_config)


@pytest.fixture(scope="session")
def paper_influence(paper_config):
    """The paper config's influence line, solved once per test process."""
    from piezobearing.stages.bearing_diagnosis import influence_from_config

    return influence_from_config(paper_config)


@pytest.fixture(scope="session")
def paper_record(paper_config):
    """The default synthetic calibration record (25 s, 1 kHz, 13 presses, R = 50 MOhm)."""
    c = paper_config
    return synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"])


# --------------------------------------------------------------------------- workflow runs


def copy_repo(dest: Path) -> Path:
    """Copy the files a clean checkout has (tracked and untracked-but-not-ignored) to ``dest``; links stay links."""
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"], cwd=REPO, capture_output=True, text=True, check=True
    ).stdout.split()
    for f in files:
        src = REPO / f
        if src.is_file():
            (dest / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / f, follow_symlinks=False)
    return dest


def workflow_env() -> dict:
    """This environment without the environment's bin folder on PATH, as for a user who calls
    ``.venv/bin/snakemake`` without activating the venv: the workflow must find its own tools (papermill, the
    notebooks' kernel)."""
    path = [p for p in os.environ.get("PATH", "").split(os.pathsep) if p and Path(p) != BIN]
    return {**os.environ, "PATH": os.pathsep.join(path)}


def snakemake(*args: str, cwd: Path = REPO, env: dict | None = None, timeout: int = 3600) -> subprocess.CompletedProcess:
    """``snakemake ARGS`` in ``cwd``: the environment's own executable in a fresh process, with ``env``
    (default: :func:`workflow_env`)."""
    return subprocess.run(
        [str(BIN / "snakemake"), *args],
        cwd=cwd,
        env=workflow_env() if env is None else env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def dry_run_errors(configfile: Path) -> tuple[subprocess.CompletedProcess, list[str]]:
    """`snakemake -n --configfile FILE` in the repository; its result and its `piezobearing:` error lines."""
    out = snakemake("-n", "--configfile", str(configfile))
    return out, [line for line in out.stderr.splitlines() if line.startswith("piezobearing:")]


#: What the reproducibility check compares: every JSON and CSV result of `all`, not the logs, timings or notebooks,
#: nor the studies' (`study_all`, built in the same run as `all` for the tests that read them; not rebuilt by the rerun).
NUMBERS_SKIP = ("results/logs", "results/benchmarks", "results/notebooks", "results/studies")
#: The number files of the first run as it finished (in its folder, outside results/).
NUMBERS_LIST = ".result_numbers"


def result_numbers(root: Path) -> list[str]:
    """The result files of a run that hold its numbers (JSON and CSV), relative to ``root``, sorted."""
    return sorted(
        rel
        for p in (root / "results").rglob("*")
        if p.suffix in {".json", ".csv"} and not (rel := p.relative_to(root).as_posix()).startswith(NUMBERS_SKIP)
    )


def shared_run(tmp_path_factory, name: str, build: Callable[[Path], None]) -> Path:
    """The folder ``name`` built once per test session by ``build(folder)``, whichever process asks first.

    Under pytest-xdist each worker is a process of its own with its own session fixtures; the folder lives in the
    workers' common temporary folder and is built under an exclusive file lock, so a second worker waits for the
    first's build and then reads it. A failed build leaves no ``.done`` mark: the next asker builds it again and
    reports its own failure."""
    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # pytest's base temporary folder, above the worker's own
    work, done = shared / name, shared / f"{name}.done"
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            shutil.rmtree(work, ignore_errors=True)
            work.mkdir()
            build(work)
            done.touch()
    return work


@pytest.fixture(scope="session")
def ci_run(tmp_path_factory) -> Path:
    """A complete `snakemake --cores 2 all study_all --configfile config/ci.yaml` in a fresh copy; its folder.

    The studies run in the same Snakemake call as the paper's targets: one DAG, and their jobs fill the cores
    while the paper's critical path runs."""

    def build(work: Path) -> None:
        copy_repo(work)
        out = snakemake("--cores", "2", "all", "study_all", "--configfile", "config/ci.yaml", cwd=work)
        assert out.returncode == 0, out.stderr[-4000:]
        (work / NUMBERS_LIST).write_text("\n".join(result_numbers(work)))  # before other tests add files

    return shared_run(tmp_path_factory, "ci_run", build)


@pytest.fixture(scope="session")
def ci_rerun(tmp_path_factory, ci_run) -> Path:
    """A second, independent clean run in a fresh copy, for reproducibility checks: a Snakemake run of its own
    (its own DAG, params, code hashes and job scripts) that builds every number file of the first run (and every
    job they need) from nothing; the figures, which the check does not compare, are not drawn again."""

    def build(work: Path) -> None:
        copy_repo(work)
        targets = (ci_run / NUMBERS_LIST).read_text().split("\n")
        out = snakemake("--cores", "2", *targets, "--configfile", "config/ci.yaml", cwd=work)
        assert out.returncode == 0, out.stderr[-4000:]

    return shared_run(tmp_path_factory, "ci_rerun", build)
