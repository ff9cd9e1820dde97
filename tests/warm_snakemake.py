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

import json
import os
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

#: Imported once in the server: Snakemake's command line and what the Snakefile imports.
PRELOAD = (
    "snakemake.cli",
    "snakemake.api",
    "snakemake.dag",
    "snakemake.scheduling.job_scheduler",
    "pandas",
    "scipy.signal",
    "piezobearing.config",
    "piezobearing.registry",
    "piezobearing.studies",
    "piezobearing.diagnosis.calibration.effects",
    "piezobearing.diagnosis.calibration.report",
    "piezobearing.stages.diagnostics",
    "piezobearing.diagnosis.bearing.report",
    "piezobearing.diagnosis.bearing.subject",
)


def _child(request: dict) -> None:
    """In the forked child: become ``snakemake ARGS`` in ``cwd`` with stdout/stderr to the given files."""
    os.chdir(request["cwd"])
    for fd, path in ((1, request["stdout"]), (2, request["stderr"])):
        f = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(f, fd)
        os.close(f)
    sys.argv = ["snakemake", *request["args"]]
    code = 1
    try:
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


def serve() -> None:
    """Read one JSON request a line ({"args", "cwd", "stdout", "stderr"}), answer {"returncode"} a line."""
    import importlib

    for name in PRELOAD:
        try:
            importlib.import_module(name)
        except ImportError:  # a module another branch does not have: the child imports what it needs
            pass
    _remember_parsed_imports()
    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        request = json.loads(line)
        pid = os.fork()
        if pid == 0:
            _child(request)
        _, status, usage = os.wait4(pid, 0)
        cpu = usage.ru_utime + usage.ru_stime
        print(json.dumps({"returncode": os.waitstatus_to_exitcode(status), "cpu_s": cpu}), flush=True)


class WarmSnakemake:
    """A server (see the module's docstring) and ``run(args, cwd)`` like ``subprocess.run`` of snakemake."""

    def __init__(self, env: dict | None = None):
        self._proc = subprocess.Popen(
            [sys.executable, __file__],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
        )
        self._lock = threading.Lock()
        assert json.loads(self._proc.stdout.readline()).get("ready"), "the warm snakemake server did not start"

    def run(self, args: list[str], cwd: str | Path) -> subprocess.CompletedProcess:
        with tempfile.TemporaryDirectory() as tmp, self._lock:
            out, err = Path(tmp, "stdout"), Path(tmp, "stderr")
            request = {"args": list(args), "cwd": str(cwd), "stdout": str(out), "stderr": str(err)}
            self._proc.stdin.write(json.dumps(request) + "\n")
            self._proc.stdin.flush()
            answer = json.loads(self._proc.stdout.readline())
            self.last_cpu_s = answer["cpu_s"]  # the child's CPU seconds (benchmarks/bench_startup.py)
            return subprocess.CompletedProcess(
                ["snakemake", *args], answer["returncode"], out.read_text(), err.read_text()
            )

    def close(self) -> None:
        self._proc.stdin.close()
        self._proc.wait(timeout=60)


if __name__ == "__main__":
    serve()
