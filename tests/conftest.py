"""Shared fixtures: the validated configs and synthetic calibration records."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from piezobearing import config as cfg
from piezobearing.stages.calibration import nominal_circuit
from piezobearing.synthesis import PressProtocol, synthesize

os.environ.setdefault("OMP_NUM_THREADS", "1")
# Bytecode caches on for every Python process of the suite: the xdist workers, the Snakemake runs and their jobs,
# papermill and its kernels, the warm servers. The test command installs with --no-compile (pip would compile all
# 2.3 GB of the environment, about 23 s more), and where the environment sets PYTHONDONTWRITEBYTECODE=1 (this
# project's machine does) no process would ever write the bytecode it compiles: each would compile NumPy, SciPy,
# pandas and Snakemake from source again (`snakemake -n` on the CI config: 6.6 s of CPU, 3.0 s with the caches).
# Only what the suite imports is compiled, once.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False


#: Fixtures that run the whole CI workflow (once per test process each).
WORKFLOW_FIXTURES = ("ci_run", "ci_rerun")
#: Modules whose module fixtures take seconds and whose tests take minutes: spread over both workers anyway.
SPREAD = ("tests/test_diagnosis_bearing.py",)


def pytest_collection_modifyitems(config, items):
    """Group the tests for pytest-xdist's ``--dist loadgroup`` and put the long ones first.

    Every test that uses a CI workflow run (:data:`WORKFLOW_FIXTURES`, directly or through another fixture) is in
    one group, ``ci_workflow``, so the session runs the workflow once on one worker, not once on each; tests
    marked ``@pytest.mark.xdist_group("name")`` (xdist's own mark) share a group of their module (they share a
    computation cached in the module, such as one diagnosis asserted by several tests); a test that uses a
    module- or class-scoped fixture is grouped with its module, so the fixture is built once; every other test
    goes to whichever worker is free. The workflow group, then the rerun test's scratch workflow, go
    first: the other worker takes the rest meanwhile. Without xdist only the order changes.
    """
    def group(item) -> str:
        if any(f in getattr(item, "fixturenames", ()) for f in WORKFLOW_FIXTURES):
            return "ci_workflow"
        mark = item.get_closest_marker("xdist_group")  # tests sharing a cached computation: one worker computes it
        if mark is not None:
            return f"{item.nodeid.split('::')[0]}::{mark.kwargs.get('name', mark.args[0] if mark.args else '')}"
        info = getattr(item, "_fixtureinfo", None)
        defs = info.name2fixturedefs.values() if info is not None else ()
        module = item.nodeid.split("::")[0]
        if module not in SPREAD and any(d.scope in ("module", "class", "package") for fd in defs for d in fd):
            return module
        return item.nodeid

    rank = {"ci_workflow": 0, "tests/test_workflow_rerun.py": 1}
    groups = {item.nodeid: group(item) for item in items}
    items.sort(key=lambda item: rank.get(groups[item.nodeid], 2))  # stable: the collection order within each rank
    worker = getattr(config, "workerinput", {})
    if worker.get("workerid") == "gw0":  # xdist: tell the controller's scheduler (every worker collects the same)
        Path(worker[GROUPS_KEY]).write_text(json.dumps({nodeid: g for nodeid, g in groups.items() if g != nodeid}))


#: The workers' input key naming the file of the test groups (see pytest_collection_modifyitems).
GROUPS_KEY = "piezobearing_test_groups"


@pytest.hookimpl(optionalhook=True)  # an xdist hook: no error where xdist is not installed
def pytest_configure_node(node):
    """xdist controller: each worker writes the test groups to this session's file (the same for all)."""
    node.workerinput[GROUPS_KEY] = str(Path(node.config.option.basetemp or tempfile.gettempdir()) / _groups_name())


def _groups_name() -> str:
    return f"piezobearing-test-groups-{os.getpid()}.json"


@pytest.hookimpl(tryfirst=True, optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup`` with the groups of pytest_collection_modifyitems.

    xdist's own loadgroup reads ``xdist_group`` marks into the node ids through ``item._nodeid``, which pytest 9
    no longer reads (``nodeid`` comes from ``item._id``): every test would be its own group and each worker
    would run the CI workflow. This scheduler reads the groups the workers wrote instead.
    """
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    path = Path(config.option.basetemp or tempfile.gettempdir()) / _groups_name()

    class GroupScheduling(LoadScopeScheduling):
        _groups: dict | None = None

        def _split_scope(self, nodeid: str) -> str:
            if self._groups is None:
                self._groups = json.loads(path.read_text()) if path.exists() else {}
            return self._groups.get(nodeid, nodeid)

    config.option.loadscopereorder = False  # keep the collection order: the long groups first, one a worker
    return GroupScheduling(config, log)


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
    workdir: Path,
    *args: str,
    configfiles: tuple[str, ...] = ("config/ci.yaml",),
    timeout: int = 1200,
    warm_jobs: bool = False,
) -> subprocess.CompletedProcess:
    """Run snakemake (from this interpreter's environment) in ``workdir`` with the CI config; ``warm_jobs``: its
    Python script jobs forked from a server with the imports done (tests/warm_jobs.py), not fresh processes.

    The environment's bin folder is left out of PATH, as for a user who calls ``.venv/bin/snakemake`` without
    activating the venv: the workflow must find its own tools (papermill, the notebooks' kernel)."""
    bindir = Path(sys.executable).parent
    exe = [sys.executable, str(Path(__file__).with_name("warm_jobs.py"))] if warm_jobs else [str(bindir / "snakemake")]
    return subprocess.run(
        [*exe, "--cores", "2", *args, "--configfile", *configfiles],
        cwd=workdir,
        env=workflow_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def workflow_env() -> dict:
    """The environment of a workflow run in the tests: this one without the environment's bin folder on PATH."""
    bindir = Path(sys.executable).parent
    path = [p for p in os.environ.get("PATH", "").split(os.pathsep) if p and Path(p) != bindir]
    return {**os.environ, "PATH": os.pathsep.join(path)}


_WARM = None


def snakemake_warm(
    *args: str, cwd: Path = REPO, env: dict | None = None, warm_jobs: bool = False
) -> subprocess.CompletedProcess:
    """``snakemake ARGS`` in ``cwd`` (a dry run, a lint, a report, a run refused before any job, a small run, the
    CI workflow run) as a child forked from this test process's warm server (tests/warm_snakemake.py, started at
    the first call: about 1.1 CPU s a call instead of 3.5; the child parses the Snakefile, validates the config and
    hashes the code as a fresh process does; its jobs are fresh processes, or with ``warm_jobs`` its Python script
    jobs forked from a job server of its own, as :func:`run_workflow` runs them); ``env``: the child's environment
    (default: this one)."""
    global _WARM
    if _WARM is None:
        from warm_snakemake import WarmSnakemake

        _WARM = WarmSnakemake()
    return _WARM.run(list(args), cwd, env=env, warm_jobs=True if warm_jobs else None)


def pytest_sessionfinish(session):
    if _WARM is not None:
        _WARM.close()


def dry_run_errors(configfile: Path) -> tuple[subprocess.CompletedProcess, list[str]]:
    """`snakemake -n --configfile FILE` in the repository; its result and its `piezobearing:` error lines."""
    out = snakemake_warm("-n", "--configfile", str(configfile))
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


@pytest.fixture(scope="session")
def ci_run(tmp_path_factory) -> Path:
    """A complete `snakemake --cores 2 all study_all --configfile config/ci.yaml` in a fresh copy; its folder.

    The studies run in the same Snakemake call as the paper's targets: one DAG, and their jobs fill the cores
    while the paper's critical path runs (a second call after it took about 45 CPU s and ran alone). Its Python
    script jobs run warm (tests/warm_jobs.py: each the job's own generated script, forked from a server with the
    imports done): 73 against 112 s of CPU for this run, its 67 number files byte-identical to those of a run with
    every job a fresh process (measured side by side). Its notebooks are executed by papermill from their rules'
    command lines, papermill and each kernel forked from a server with papermill, ipykernel and the notebooks'
    imports done (tests/warm_kernel.py): the same figures, byte for byte, and the same executed notebooks as with
    fresh processes (benchmarks/bench_notebooks.py). A user's run, the README's first command, starts every job and kernel fresh;
    what only a fresh process would catch is said in tests/warm_jobs.py and tests/warm_kernel.py.

    Snakemake itself is a child forked from this worker's warm server (:func:`snakemake_warm`, with the environment
    of :func:`run_workflow`), not a fresh process: its imports are done (about 2 CPU s less; the server is
    started anyway for the workflow tests of this group). The rerun (``ci_rerun``) starts Snakemake fresh, so
    the two runs' Snakemake processes differ in hash seed as their job servers do."""
    work = _copy_repo(tmp_path_factory.mktemp("ci_run"))
    out = snakemake_warm("--cores", "2", "all", "study_all", "--configfile", "config/ci.yaml", cwd=work,
                         env=workflow_env(), warm_jobs=True)
    assert out.returncode == 0, out.stderr[-4000:]
    (work / NUMBERS_LIST).write_text("\n".join(result_numbers(work)))  # before other tests add files
    return work


@pytest.fixture(scope="session")
def ci_rerun(tmp_path_factory, ci_run) -> Path:
    """A second, independent clean run in a fresh copy, for reproducibility checks: a Snakemake run of its own
    (its own DAG, params, code hashes and job scripts) that builds every number file of the first run (and every
    job they need) from nothing; the figures, which the check does not compare, are not drawn again. Its Python
    script jobs run warm as the first run's do, from a server of their own (another process, another hash seed,
    another folder), so each number is compared between two independent runs of its job."""
    work = _copy_repo(tmp_path_factory.mktemp("ci_rerun"))
    out = run_workflow(work, *(ci_run / NUMBERS_LIST).read_text().split("\n"), warm_jobs=True)
    assert out.returncode == 0, out.stderr[-4000:]
    return work
