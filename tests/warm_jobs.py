"""A real Snakemake run whose Python script jobs start warm: ``python tests/warm_jobs.py ARGS`` is ``snakemake ARGS``
(the same DAG, scheduling, job scripts, logs and outputs) except that each ``script:`` job, instead of a fresh
``python .snakemake/scripts/tmpXXXX.<rule>.py`` process, runs that same generated script in a child forked from a
server that has NumPy, SciPy, pandas, Snakemake's script preamble modules and every package module the workflow's
scripts import already imported. A job of this workflow spends most of its CPU time on those imports (0.5-1.4 s
each: benchmarks/bench_ci_tests.py); the forked child pays only the job's own work. One more difference: the
scheduler keeps at most one pending re-evaluation timer (:func:`one_reevaluation_timer`: the same jobs in the same
order, without Snakemake's multiplying timer rounds).

The child is the job as Snakemake would run it: the job's script file (preamble with its pickled ``snakemake``
object, then the rule's script), run as ``__main__`` in the job's working directory, with the thread variables
Snakemake sets for the job's ``threads`` (``OMP_NUM_THREADS``, ``MKL_NUM_THREADS``, ...; and a threadpoolctl limit
for the BLAS libraries the server loaded before them); an uncaught exception goes to the job's log as the real
process's would, and a non-zero exit fails the job. Every child starts from the same server state (one job cannot
leak into the next). The server is forked from the run's Snakemake process (:class:`JobServer`), so its hash seed
is that run's and differs from that of every process of another run.

Not the same as a fresh process: a module the job's script does not import itself but the server preloaded
(:data:`PRELOAD`: SciPy's signal, optimize and interpolate, sfepy, meshio and numba too) or Snakemake imported
before the server was forked is there anyway, so a job that forgot such an import (an attribute of a package whose
submodule it never imported; a missing ``import`` of a name fails here as anywhere) would pass here. The README's
first command (the whole
paper) runs every job as a fresh process. The CI workflow run and the reproducibility rerun (``ci_run``,
``ci_rerun``, tests/conftest.py) use this; the bad-input workflow cases (tests/test_bad_inputs.py) run theirs fresh.

The notebook jobs (``papermill ... -k python3``, shell jobs) run as Snakemake runs them, but their papermill and
kernel processes start warm too (tests/warm_kernel.py: a papermill stand-in first on the jobs' PATH and a
``python3`` kernel spec whose stubs have both forked from a server with papermill, ipykernel and the notebooks'
imports done). What that does not prove: that a notebook imports every module it uses (a submodule the server
preloaded is there anyway), and a fresh papermill's and kernel's own start (console script, launcher, imports,
the spec jupyter_client would find without ``JUPYTER_PATH``); papermill's run (found on the job's PATH as the
shell finds it), jupyter_client, the kernel's set-up, every cell, the executed notebook and the figure are the
real ones.
"""

from __future__ import annotations

import ast
import contextlib
import gc
import importlib
import itertools
import json
import os
import runpy
import select
import subprocess
import sys
import threading
import time
from pathlib import Path

#: What every job of this workflow imports, besides the package modules its script names; then the libraries that
#: the package's modules import inside their functions (to keep a fresh job's start light) and that several jobs of
#: a run import again each: scipy.signal (with scipy.stats, 0.49 CPU s a job: the calibration, voltage, envelope,
#: SNR and LPM jobs), sfepy with the polynomial-space table its first domain loads (about 0.35 s: the housing and
#: sensor FEM jobs), meshio, numba (benchmarks/bench_ci_jobs.py: 12 CPU s less per CI workflow run).
PRELOAD = (
    "numpy",
    "scipy.sparse.linalg",
    "pandas",
    "threadpoolctl",
    "snakemake.iocontainers",
    "snakemake.logging",
    "scipy.signal",
    "scipy.optimize",
    "scipy.interpolate",
    "sfepy.discrete",
    "sfepy.discrete.fem",
    "sfepy.terms",
    "sfepy.solvers.ts_solvers",
    "sfepy.discrete.fem.poly_spaces",
    "sfepy.discrete.dg.poly_spaces",
    "meshio",
    "numba",
)
#: What a job's script imports when it is a stand-in writing its outputs (tests/test_workflow_rerun.py): the modules
#: of Snakemake's script preamble (the pickled ``snakemake`` object, its logger) and the stand-in's own.
STAND_IN_PRELOAD = ("pathlib", "pickle", "snakemake.iocontainers", "snakemake.logging")
#: The variables Snakemake's shell() sets to a job's thread count (snakemake/shell.py).
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "GOTO_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
)


def script_imports(scripts: Path) -> list[str]:
    """The package modules the workflow's scripts import (``from piezobearing.x import y`` gives both names)."""
    out: set[str] = set()
    for s in sorted(scripts.glob("*.py")):
        for node in ast.walk(ast.parse(s.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("piezobearing"):
                out.add(node.module)
            elif isinstance(node, ast.Import):
                out.update(a.name for a in node.names if a.name.startswith("piezobearing"))
    return sorted(out)


def _child(request: dict) -> None:
    """In the forked child: run the job's script as ``python SCRIPT`` would, in the job's folder; never return."""
    code = 1
    try:
        os.chdir(request["cwd"])
        threads = str(request["threads"])
        for name in THREAD_VARIABLES:
            os.environ[name] = threads
        devnull = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1):  # the job's stdout as Snakemake leaves it (not captured); stderr stays the server's
            os.dup2(devnull, fd)
        from threadpoolctl import threadpool_limits

        threadpool_limits(int(threads))  # libraries loaded before the variables were set
        sys.argv = [request["script"]]
        runpy.run_path(request["script"], run_name="__main__")
        code = 0
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    except BaseException:  # noqa: BLE001 - to sys.stderr, which the job's script pointed at its log
        import traceback

        traceback.print_exc()
    finally:
        _flushed_exit(code)


def _flushed_exit(code: int) -> None:
    """Flush a forked child's streams and end it with ``code``, without the parent's exit handlers."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code)


def serve(scripts: Path, preload: tuple[str, ...] | None = None) -> None:
    """Read one JSON request a line ({"id", "script", "cwd", "threads"}) and fork a child for it at once; answer
    {"id", "returncode", "cpu_s"} a line as each child ends (children run side by side). Imports :data:`PRELOAD`
    and the package modules the ``scripts`` import first, or only ``preload`` where given."""
    for name in preload if preload is not None else [*PRELOAD, *script_imports(scripts)]:
        try:
            with contextlib.redirect_stdout(sys.stderr):  # sfepy prints at its import; stdout is the answers'
                importlib.import_module(name)
        except ImportError:  # a module another branch does not have: the job imports what it needs
            pass
    serve_forks(_child)


def serve_forks(child, poll_s: float = 0.02) -> None:
    """Say ready, then read one JSON request a line (with its ``"id"``) and fork ``child(request)`` (which never
    returns) for it at once; answer {"id", "returncode", "cpu_s", "max_rss_MB"} a line as each child ends (children
    run side by side). The server of tests/warm_snakemake.py serves its dry runs with this too.

    First the server's objects go into the permanent generation (``gc.freeze``): a child's garbage collections no
    longer traverse them, nor touch their pages, which the fork shares until written. While no child runs, the
    server sleeps until a request comes (it polled every ``poll_s`` before: 4.5 ms of CPU a second, about 0.7 s over
    a test session for each worker's Snakemake server)."""
    gc.freeze()
    print(json.dumps({"ready": True}), flush=True)
    running: dict[int, int] = {}
    pending, open_ = b"", True
    while open_ or running:
        if open_ and select.select([0], [], [], poll_s if running else None)[0]:
            chunk = os.read(0, 65536)
            open_ = bool(chunk)
            pending += chunk
            *lines, pending = pending.split(b"\n")
            for line in lines:
                request = json.loads(line)
                pid = os.fork()
                if pid == 0:
                    child(request)
                running[pid] = request["id"]
        elif not open_:
            select.select([], [], [], poll_s)
        while running:
            pid, status, usage = os.wait4(-1, os.WNOHANG)
            if pid == 0:
                break
            answer = {"id": running.pop(pid), "returncode": os.waitstatus_to_exitcode(status),
                      "cpu_s": usage.ru_utime + usage.ru_stime, "max_rss_MB": usage.ru_maxrss / 1024}
            print(json.dumps(answer), flush=True)


class ForkServer:
    """The client of a server process that runs :func:`serve_forks`: ``request(fields)`` sends one request and
    blocks until its child ends, returning the answer; safe to call from several threads at once. ``cpu_s``: the
    children's CPU seconds so far. :class:`JobServer` here and ``warm_snakemake.WarmSnakemake`` are its two kinds."""

    def __init__(self, cmd: list[str] | None, name: str, env: dict | None = None, target=None):
        """Start the server: ``cmd`` as a fresh process, or (``cmd`` None) ``target()`` in a child forked from this
        process (:class:`Forked`)."""
        self._proc = (Forked(target) if cmd is None else
                      subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env))
        assert json.loads(self._proc.stdout.readline()).get("ready"), f"the {name} did not start"
        self._ids = itertools.count()
        self._lock = threading.Lock()
        self._done: dict[int, dict] = {}
        self._events: dict[int, threading.Event] = {}
        self.cpu_s = 0.0
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self._proc.stdout:
            answer = json.loads(line)
            with self._lock:
                self._done[answer["id"]] = answer
                self.cpu_s += answer["cpu_s"]
                self._events.pop(answer["id"]).set()

    def request(self, fields: dict) -> dict:
        """Send ``fields`` (with an ``id`` added) and wait for the child's answer."""
        event = threading.Event()
        with self._lock:
            i = next(self._ids)
            self._events[i] = event
            self._proc.stdin.write(json.dumps({"id": i, **fields}) + "\n")
            self._proc.stdin.flush()
        event.wait()
        with self._lock:
            return self._done.pop(i)

    def close(self) -> None:
        self._proc.stdin.close()
        self._proc.wait(timeout=60)


class Forked:
    """``target()`` in a child forked from this process, its stdin and stdout pipes to this one (``stdin``,
    ``stdout``: text files, as ``subprocess.Popen``'s), ``wait()`` for its end. The child exits when ``target``
    returns (its exit status 0; 1 after an exception, printed to stderr)."""

    def __init__(self, target):
        sys.stdout.flush()
        sys.stderr.flush()
        down, up = os.pipe(), os.pipe()  # (read, write): requests to the child, answers from it
        self.pid = os.fork()
        if self.pid == 0:
            code = 1
            try:
                os.dup2(down[0], 0)
                os.dup2(up[1], 1)
                for fd in (*down, *up):
                    os.close(fd)
                target()
                code = 0
            except BaseException:  # noqa: BLE001 - to stderr, as a fresh server process would print it
                import traceback

                traceback.print_exc()
            finally:
                _flushed_exit(code)
        os.close(down[0])
        os.close(up[1])
        self.stdin, self.stdout = os.fdopen(down[1], "w"), os.fdopen(up[0])

    def wait(self, timeout: float | None = None) -> int:
        return os.waitstatus_to_exitcode(os.waitpid(self.pid, 0)[1])


class JobServer(ForkServer):
    """The job server's client: ``run(script, cwd, threads)`` blocks until the forked job ends and returns its exit
    status; safe to call from Snakemake's job threads at once.

    The server is a child forked from this process (a Snakemake run's, before its Snakefile is read: Snakemake and
    what it imports are there already), not a fresh interpreter: it imports only what this process has not (0.3
    instead of 0.6 CPU s a start for the CI workflow's). Its hash seed is this process's, which is the run's own:
    the two CI runs' Snakemake processes differ (tests/conftest.py)."""

    def __init__(self, scripts: Path, preload: tuple[str, ...] | None = None):
        super().__init__(None, "warm job server", target=lambda: serve(scripts, preload))

    def run(self, script: str, cwd: str, threads: int) -> dict:
        """Run the job; {"returncode", "cpu_s", "max_rss_MB"} of its child."""
        return self.request({"script": script, "cwd": cwd, "threads": threads})


def one_reevaluation_timer() -> None:
    """Snakemake's job scheduler with at most one pending re-evaluation timer, not one more per scheduling round.

    With Snakemake's default ``--max-jobs-per-timespan 100/1s`` (9.27), every scheduling round that finds jobs
    ready, whether or not a core is free for one, starts a 1 s ``threading.Timer`` whose round starts another:
    each job's end adds a chain of rounds that lasts while jobs wait for a core, so the rounds multiply with the
    jobs (3987 timer rounds in one CI workflow run, ``all study_all``, each reading the input sizes of every
    waiting job: its Snakemake process took 6.3 s of CPU, 3.8 s with this; one pair, load 10). Here a round asked
    for while a timer is pending is left to that timer, which fires sooner; its round, if jobs still wait, starts
    the next. The rounds at job ends are Snakemake's own, and a core is only freed at a job's end, so the timer
    rounds start no job here: the jobs and their order are Snakemake's. Used by the tests' real runs (``ci_run``,
    ``ci_rerun``, the rerun test's stand-in runs); a user's ``snakemake`` keeps Snakemake's own."""
    from snakemake.scheduling.job_scheduler import JobScheduler

    lock = threading.Lock()
    pending: set[int] = set()

    def schedule_reevaluation(self, delay) -> None:
        with lock:
            if id(self) in pending:
                return
            pending.add(id(self))

        def fire() -> None:
            with lock:
                pending.discard(id(self))
            self._open_jobs.release()

        threading.Timer(delay, fire).start()

    JobScheduler._schedule_reevalutation = schedule_reevaluation


def main(args: list[str], preload: tuple[str, ...] | None = None) -> int:
    """``snakemake ARGS`` in the current folder with warm script jobs; its exit status. ``preload``: the modules the
    job server imports instead of :data:`PRELOAD` and the scripts' package modules (the rerun test's stand-in
    scripts import nothing but Snakemake's preamble modules, :data:`STAND_IN_PRELOAD`)."""
    from snakemake.cli import main as snakemake_main
    from snakemake.script import PythonScript
    from warm_kernel import WarmKernels

    server = JobServer(Path("workflow/scripts").resolve(), preload)
    # notebooks run warm too, unless the run's scripts are stand-ins (their papermill is one as well)
    kernels = WarmKernels(Path("notebooks")) if preload is None and Path("notebooks").is_dir() else None

    def execute_script(self, fname, edit=False):
        start = time.time()
        done = server.run(os.path.abspath(fname), os.getcwd(), self.threads)
        if self.bench_record is not None:  # the rule's benchmark: file, from the child's resource usage
            b = self.bench_record
            b.running_time, b.cpu_time, b.max_rss = time.time() - start, done["cpu_s"], done["max_rss_MB"]
            b.cpu_usage, b.data_collected = done["cpu_s"], True
        if done["returncode"]:
            raise subprocess.CalledProcessError(done["returncode"], f"python {fname} (warm job)")

    PythonScript.execute_script = execute_script
    one_reevaluation_timer()
    try:
        snakemake_main(args)
        return 0
    except SystemExit as e:
        return e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    finally:
        server.close()
        print(f"warm jobs: {server.cpu_s:.2f} s of CPU in the jobs", file=sys.stderr)
        if kernels is not None:
            k = kernels.close()
            print(f"warm notebooks: {k['papermill']['cpu_s']:.2f} s of CPU in {k['papermill']['n']} papermill runs, "
                  f"{k['kernel']['cpu_s']:.2f} s in {k['kernel']['n']} kernels", file=sys.stderr)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--serve"]:  # a job server as a fresh process: --serve SCRIPTS [--preload a,b]
        only = sys.argv[sys.argv.index("--preload") + 1].split(",") if "--preload" in sys.argv else None
        serve(Path(sys.argv[2]), None if only is None else tuple(only))
    else:
        sys.exit(main(sys.argv[1:]))
