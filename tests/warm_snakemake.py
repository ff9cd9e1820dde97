"""Dry runs of Snakemake without paying its start-up each time: a server process imports Snakemake and the
modules the Snakefile imports once, then forks a child for every request, which runs ``snakemake ARGS`` (the
command-line entry point, ``sys.argv`` and all) in the requested folder, its output to files.

A dry run of this workflow spends about 2 of its 3 CPU seconds importing Snakemake, SciPy and the package; a
forked child starts with them imported and computes the rest as a fresh ``snakemake`` process would: it parses
the Snakefile, validates the config, hashes the package code from the files on disk (so an edited module is
seen) and builds the DAG against the folder's metadata. Every child starts from the same parent state: one
request cannot leak into the next.

Used by the tests for the many dry runs they ask (tests/test_workflow_rerun.py); run with
``python tests/warm_snakemake.py`` in the environment (PYTHONPATH, PATH) the dry runs need.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

from warm_jobs import ForkServer, serve_forks

#: Imported once in the server: Snakemake's command line and what the Snakefile imports, and what Snakemake imports
#: on the way of every dry run (its report, storage and profile modules, smart_open, jsonschema, platformdirs, ...:
#: 280 modules, 0.13 of a child's 0.61 CPU s when each child imported them). Not SciPy's signal package: no module
#: the Snakefile imports needs it any more (stages import it where they filter), and it was 0.7 CPU s of each
#: server's start.
PRELOAD = (
    "snakemake.cli",
    "snakemake.api",
    "snakemake.dag",
    "snakemake.scheduling.job_scheduler",
    "snakemake.report.html_reporter",
    "snakemake.storage",
    "snakemake.profiles",
    "smart_open",
    "jsonschema",
    "platformdirs",
    "argparse_dataclass",
    "graphlib",
    "packaging.version",
    "pandas",
    "pandas.core.methods.to_dict",
    "piezobearing.config",
    "piezobearing.registry",
    "piezobearing.runlock",
    "piezobearing.signals.outputs",
    "piezobearing.studies",
    "piezobearing.diagnosis.calibration.effects",
    "piezobearing.diagnosis.calibration.report",
    "piezobearing.stages.diagnostics",
    "piezobearing.diagnosis.bearing.report",
    "piezobearing.diagnosis.bearing.subject",
)


def _child(request: dict) -> None:
    """In the forked child: become ``snakemake ARGS`` in ``cwd`` with stdout/stderr to the given files; with the
    request's ``env`` as its environment where given (what its jobs inherit), and with ``warm_jobs`` (a list of
    modules, or true for the job server's default: tests/warm_jobs.py's PRELOAD and the scripts' package modules)
    its Python script jobs forked from a job server that imported those (tests/warm_jobs.py)."""
    os.chdir(request["cwd"])
    if request.get("env") is not None:
        os.environ.clear()
        os.environ.update(request["env"])
    for fd, path in ((1, request["stdout"]), (2, request["stderr"])):
        f = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(f, fd)
        os.close(f)
    sys.argv = ["snakemake", *request["args"]]
    code = 1
    try:
        if request.get("warm_jobs") is not None:
            from warm_jobs import main as warm_main

            preload = request["warm_jobs"]
            code = warm_main(request["args"], None if preload is True else tuple(preload))
        else:
            from snakemake.cli import main

            main(request["args"])
            code = 0
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    except BaseException:  # noqa: BLE001 - a traceback to stderr, as the real process would print it
        import traceback

        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def _remember_parsed_imports() -> None:
    """Parse every package module's imports once here, keyed by the module's text: a child hashes the package code
    from the files on disk as before (every file read again), and parses only a file whose text is not one of
    these (an edited module), instead of all of them (0.3 of its 1.1 CPU s)."""
    try:
        from piezobearing import registry
    except ImportError:
        return
    parse = registry._imports
    memo: dict = {}

    def _imports(source: str, module, is_package: bool) -> set[str]:
        key = (source, module, is_package)
        if key not in memo:
            memo[key] = frozenset(parse(source, module, is_package))
        return set(memo[key])

    registry._imports = _imports
    for f in sorted(registry.PACKAGE_DIR.rglob("*.py")):
        registry._module_imports(f)
    registry._module_imports.cache_clear()  # path-keyed: a child must read the files again
    if hasattr(registry._module_file, "cache_clear"):
        registry._module_file.cache_clear()  # and look up which files exist


def _collect_plugins() -> None:
    """Build Snakemake's argument parser once here: its plugin registries (executors, storage, loggers, ...; each a
    singleton that scans the installed packages at its first use) are then collected in every child (0.06 of its
    0.3 CPU s), as a fresh process would collect them: the installed plugins do not change while the server runs."""
    try:
        from snakemake.cli import get_argument_parser
    except ImportError:
        return
    get_argument_parser()


def serve() -> None:
    """Read one JSON request a line ({"id", "args", "cwd", "stdout", "stderr", ...}) and fork a child for it at once;
    answer {"id", "returncode", "cpu_s"} a line as each child ends (children of several requests run side by side,
    so one server serves two threads: a second server cost 2.4 CPU s to start)."""
    import importlib

    for name in PRELOAD:
        try:
            importlib.import_module(name)
        except ImportError:  # a module another branch does not have: the child imports what it needs
            pass
    _remember_parsed_imports()
    _collect_plugins()
    # tests/warm_jobs.py's fork loop, which first freezes the server's objects (gc.freeze: 0.29 instead of 0.39-0.42
    # CPU s a dry run)
    serve_forks(_child, poll_s=0.01)


class WarmSnakemake(ForkServer):
    """A server (see the module's docstring) and ``run(args, cwd)`` like ``subprocess.run`` of snakemake; ``run``
    may be called from several threads at once (each call a child of its own)."""

    def __init__(self, env: dict | None = None):
        super().__init__([sys.executable, __file__], "warm snakemake server", env)

    def run(
        self, args: list[str], cwd: str | Path, env: dict | None = None,
        warm_jobs: tuple[str, ...] | bool | None = None,
    ) -> subprocess.CompletedProcess:
        """``snakemake ARGS`` in ``cwd``; ``env``: the child's environment (default: the server's); ``warm_jobs``:
        run the script jobs warm from a job server importing these modules (``True``: the job server's default,
        as ``python tests/warm_jobs.py ARGS`` runs them), not as fresh processes. The result's ``cpu_s``: the
        child's CPU seconds (with its jobs')."""
        with tempfile.TemporaryDirectory() as tmp:
            out, err = Path(tmp, "stdout"), Path(tmp, "stderr")
            answer = self.request({"args": list(args), "cwd": str(cwd), "stdout": str(out), "stderr": str(err),
                                   "env": env, "warm_jobs": warm_jobs if warm_jobs in (None, True) else list(warm_jobs)})
            self.last_cpu_s = answer["cpu_s"]  # the last call's (benchmarks/bench_startup.py calls one at a time)
            result = subprocess.CompletedProcess(
                ["snakemake", *args], answer["returncode"], out.read_text(), err.read_text()
            )
            result.cpu_s = answer["cpu_s"]
            return result


if __name__ == "__main__":
    serve()
