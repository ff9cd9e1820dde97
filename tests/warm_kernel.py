"""Notebook jobs started warm, for the tests' workflow runs (tests/warm_jobs.py): each figure rule still runs its
own command line, ``papermill NOTEBOOK OUT -k python3 -r ...``, through Snakemake's shell; papermill still reads
the notebook, injects the parameters, starts a kernel named ``python3`` through jupyter_client, talks to it over
ZeroMQ, executes every cell and writes the executed notebook and the figure. Only the two processes start
differently: each is a child forked from one server that has papermill, jupyter_client, nbclient, ipykernel,
IPython, debugpy and every module the notebooks' code cells import (pandas, matplotlib, piezobearing.plotting,
...) already imported.

The kernel: in the tests' environment ``JUPYTER_PATH`` names a folder whose ``kernels/python3/kernel.json`` (the
installed ``python3`` spec, its ``argv`` replaced) starts ``python -S tests/warm_kernel.py -f {connection_file}``,
a stub that passes its arguments, folder, environment and standard streams (the rule's log) over a Unix socket to
the server. The server forks a child that becomes the kernel: the stub's streams as its own, the stub's
environment and folder, then ``ipykernel_launcher``'s own start (``kernelapp.launch_new_instance()`` with the
stub's arguments, the current folder taken off ``sys.path`` as the launcher does). The stub waits for the child's
exit status and exits with it, and forwards the signals jupyter_client sends it (an interrupt, a terminate) to
the child; if the stub is killed, the server kills the child.

papermill: the jobs' PATH starts with a folder holding a stand-in ``papermill`` (:func:`papermill_stub`). It
looks papermill up on the rest of the job's PATH as the shell would have: none found, it answers as the shell
does (127, "command not found"), so a workflow that could not find its papermill still fails; another papermill
(a test's own stand-in) is executed as it is; this environment's papermill runs as a child of the server, in the
same way as a kernel, as its console script would (``papermill.cli.papermill()`` with the job's arguments).

A fresh kernel spends about 1.1 of its 1.3 CPU s on imports, a fresh papermill about 0.3 of its 0.5; the children
pay only the kernel's set-up, papermill's own work and the cells' (reading the results, drawing, saving). The
server starts at the first request of a run (the reproducibility rerun draws no figure and starts none).

Not the same as fresh processes (besides what tests/warm_jobs.py says of warm script jobs): a notebook that
forgot an import of a module the server preloaded (a submodule it uses as an attribute) would pass here; the
processes share the server's hash seed; matplotlib was imported before ipykernel set ``MPLBACKEND`` (the figures
are drawn with the Agg backend that ``piezobearing.plotting`` selects either way: the same PNG bytes, measured
for the ten notebooks); papermill's and the kernel's own start (their console script and launcher, their imports)
are not run. The README's first command and the bad-input workflow cases (one of them runs Fig. 5's notebook)
start every process fresh.

This file runs as the stubs without ``site`` (``python -S``): everything above :func:`serve` uses only the
standard library.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import sys

#: The environment variable that tells the stub where the server listens.
SOCKET_VARIABLE = "PIEZOBEARING_WARM_KERNEL_SOCKET"
#: What every kernel imports before it runs a cell (ipykernel's kernel, its shell, its debugger's debugpy).
KERNEL_PRELOAD = (
    "ipykernel.kernelapp",
    "ipykernel.ipkernel",
    "ipykernel.zmqshell",
    "ipykernel.debugger",
    "IPython.core.completer",
    "threadpoolctl",
)
#: What a papermill run imports (its command line, the execution engine, jupyter_client's kernel manager and
#: provisioner, ipykernel's kernel spec, which jupyter_client reads for ``python3``; black, where installed, which
#: papermill formats the parameters cell with: the test extras install it for snakefmt).
PAPERMILL_PRELOAD = (
    "papermill.cli",
    "papermill.engines",
    "papermill.translators",
    "nbclient",
    "jupyter_client.manager",
    "jupyter_client.provisioning.local_provisioner",
    "ipykernel.kernelspec",
    "tqdm.auto",
    "psutil",
    "black",
)
#: The largest request (arguments, folder, environment) a stub sends, bytes.
MAX_REQUEST = 1 << 20


def stub(argv: list[str], kind: str = "kernel", exe: str | None = None) -> int:
    """The process jupyter_client started as the kernel (``kind="kernel"``) or the shell as ``papermill``
    (``kind="papermill"``, ``exe`` the real papermill): have the server fork it with this process's arguments,
    folder, environment and standard streams; forward signals to it; its exit status."""
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    conn.connect(os.environ[SOCKET_VARIABLE])
    request = {"kind": kind, "exe": exe, "argv": argv, "cwd": os.getcwd(), "env": dict(os.environ)}
    socket.send_fds(conn, [json.dumps(request).encode()], [0, 1, 2])
    started = conn.recv(4096)
    if not started:
        return 1
    pid = json.loads(started)["pid"]

    def forward(signum, frame):
        try:
            os.kill(pid, signum)
        except ProcessLookupError:
            pass

    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT):
        signal.signal(signum, forward)
    answer = conn.recv(4096)  # retried after a forwarded signal (PEP 475)
    return json.loads(answer)["returncode"] if answer else 1


def papermill_stub(argv: list[str], stand_in_dir: str) -> int:
    """``papermill ARGV`` as the job's shell would run it: the papermill that the job's PATH without this stand-in's
    folder finds; this environment's own (beside this Python) runs in a child of the server, any other (a test's
    stand-in) is executed as it is; where the PATH finds none, the shell's own answer."""
    import shutil

    path = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep) if p and p != stand_in_dir)
    exe = shutil.which("papermill", path=path)
    if exe is None:
        print("papermill: command not found", file=sys.stderr)
        return 127
    if os.path.realpath(os.path.dirname(exe)) != os.path.realpath(os.path.dirname(sys.executable)):
        os.execv(exe, [exe, *argv])
    return stub(argv, "papermill", exe)


def notebook_imports(notebooks) -> list[str]:
    """Every module the notebooks' code cells import (``from a.b import c``: ``a.b`` and, if it is one, ``a.b.c``)."""
    import ast

    out: set[str] = set()
    for nb in sorted(notebooks.glob("*.ipynb")):
        for cell in json.loads(nb.read_text())["cells"]:
            if cell["cell_type"] != "code":
                continue
            try:
                tree = ast.parse("".join(cell["source"]))
            except SyntaxError:  # a magic: the kernel imports what it needs
                continue
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.module and not node.level:
                    out.add(node.module)
                    out.update(f"{node.module}.{a.name}" for a in node.names)
                elif isinstance(node, ast.Import):
                    out.update(a.name for a in node.names)
    return sorted(out)


def _child(request: dict, fds: list[int]) -> None:
    """In the forked child: become ``python -m ipykernel_launcher ARGV`` (a kernel) or ``papermill ARGV`` as the
    stub would have; never return."""
    code = 1
    try:
        for target, fd in enumerate(fds[:3]):
            os.dup2(fd, target)
        for fd in fds:
            os.close(fd)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        threads = os.environ.get("OMP_NUM_THREADS")
        if threads:  # the libraries the server loaded before this job's thread variables
            from threadpoolctl import threadpool_limits

            threadpool_limits(int(threads))
        if request["kind"] == "papermill":  # as its console script: its folder first on sys.path, its argv
            sys.path[0] = os.path.dirname(request["exe"])
            sys.argv = [request["exe"], *request["argv"]]
            from papermill.cli import papermill

            papermill()  # click's main: exits
        else:
            del sys.path[0]  # this file's folder; ipykernel_launcher takes the kernel's folder off sys.path likewise
            sys.argv = ["ipykernel_launcher", *request["argv"]]
            from ipykernel import kernelapp

            kernelapp.launch_new_instance(  # two defaults the class took from the environment at its import (the server's)
                parent_handle=int(os.environ.get("JPY_PARENT_PID") or 0),
                interrupt=int(os.environ.get("JPY_INTERRUPT_EVENT") or 0),
            )
        code = 0
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    except BaseException:  # noqa: BLE001 - to the kernel's stderr, the rule's log
        import traceback

        traceback.print_exc()
    finally:
        try:
            import atexit

            atexit._run_exitfuncs()  # as the interpreter's exit would (IPython's history, ipykernel's clean-up)
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(code)


def serve(listen_fd: int, notebooks) -> None:
    """Import :data:`KERNEL_PRELOAD` and the notebooks' modules, then accept stubs on the listening socket
    ``listen_fd`` and fork a kernel for each at once; answer each stub its kernel's pid, then its exit status;
    kill a kernel whose stub went away. Stops accepting when stdin closes, and returns when every kernel ended,
    writing {"kernel": {"n", "cpu_s", "cpu_s_each"}, "papermill": {...}} (in the order they ended) to stdout."""
    import gc
    import importlib
    import select

    os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # debugpy's note on frozen modules, at its import
    for name in [*PAPERMILL_PRELOAD, *KERNEL_PRELOAD, *notebook_imports(notebooks)]:
        try:
            importlib.import_module(name)
        except ImportError:  # ``from a import name`` of a name that is no module: imported with ``a``
            pass
    listener = socket.socket(fileno=listen_fd)
    gc.freeze()  # as tests/warm_jobs.py's server: the children's collections do not touch the preloaded objects
    running: dict[int, socket.socket] = {}
    done: dict[str, list[float]] = {"kernel": [], "papermill": []}
    kinds: dict[int, str] = {}
    open_ = True
    while open_ or running:
        watch = [*running.values(), *([listener, sys.stdin] if open_ else [])]
        for ready in select.select(watch, [], [], 0.02)[0]:
            if ready is sys.stdin:
                open_ = bool(os.read(0, 4096))
                if not open_:
                    listener.close()
            elif ready is listener:
                conn, _ = listener.accept()
                msg, fds, _, _ = socket.recv_fds(conn, MAX_REQUEST, 3)
                pid = os.fork()
                if pid == 0:
                    listener.close()
                    for other in (conn, *running.values()):
                        other.close()
                    _child(json.loads(msg), fds)
                for fd in fds:
                    os.close(fd)
                conn.send(json.dumps({"pid": pid}).encode())
                running[pid] = conn
                kinds[pid] = json.loads(msg)["kind"]
            elif not ready.recv(4096):  # the stub is gone (killed): so goes its kernel
                pid = next(p for p, c in running.items() if c is ready)
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
        while running:
            pid, status, usage = os.wait4(-1, os.WNOHANG)
            if pid == 0:
                break
            done[kinds.pop(pid)].append(usage.ru_utime + usage.ru_stime)
            conn = running.pop(pid)
            try:
                conn.send(json.dumps({"returncode": os.waitstatus_to_exitcode(status)}).encode())
            except OSError:  # the stub is gone
                pass
            conn.close()
    print(json.dumps({k: {"n": len(v), "cpu_s": sum(v), "cpu_s_each": v} for k, v in done.items()}), flush=True)


class WarmKernels:
    """In the process that runs Snakemake (tests/warm_jobs.py): make the jobs' ``python3`` kernel the warm one
    (``JUPYTER_PATH``, the socket's variable), start the server at the first kernel asked for; ``close()`` ends it
    and returns what the server's children took: {"kernel": {"n", "cpu_s", "cpu_s_each"}, "papermill": {...}}."""

    def __init__(self, notebooks, kernel_name: str = "python3", papermill: bool = True):
        import shutil
        import subprocess
        import tempfile
        import threading
        from pathlib import Path

        from jupyter_core.paths import jupyter_path

        self._dir = Path(tempfile.mkdtemp(prefix="pbkernel"))
        self._rmtree, self._popen = shutil.rmtree, subprocess.Popen
        found = [p for p in (Path(d, kernel_name, "kernel.json") for d in jupyter_path("kernels")) if p.is_file()]
        if found:  # the spec jupyter_client would pick: the first on its path
            spec = json.loads(found[0].read_text())
        else:  # ipykernel's built-in spec (0.13 CPU s to import jupyter_client's kernelspec; rarely needed)
            from jupyter_client.kernelspec import KernelSpecManager

            spec = KernelSpecManager().get_kernel_spec(kernel_name).to_dict()
        spec["argv"] = ["python", "-S", os.path.abspath(__file__), *spec["argv"][spec["argv"].index("-f"):]]
        (self._dir / "kernels" / kernel_name).mkdir(parents=True)
        (self._dir / "kernels" / kernel_name / "kernel.json").write_text(json.dumps(spec, indent=1))
        self._listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._listener.bind(str(self._dir / "socket"))
        self._listener.listen(64)
        self._notebooks = str(Path(notebooks).resolve())
        self._server = None
        self._stop_r, self._stop_w = os.pipe()
        self._thread = threading.Thread(target=self._start_when_asked, daemon=True)
        self._thread.start()
        os.environ["JUPYTER_PATH"] = os.pathsep.join(filter(None, [str(self._dir), os.environ.get("JUPYTER_PATH")]))
        os.environ[SOCKET_VARIABLE] = str(self._dir / "socket")
        if papermill:  # the stand-in first on the jobs' PATH
            (self._dir / "bin").mkdir()
            stand_in = self._dir / "bin/papermill"
            stand_in.write_text(
                f"#!{sys.executable} -S\nimport sys\n\nsys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r})\n"
                f"from warm_kernel import papermill_stub\n\nsys.exit(papermill_stub(sys.argv[1:], {str(stand_in.parent)!r}))\n"
            )
            stand_in.chmod(0o755)
            os.environ["PATH"] = os.pathsep.join([str(stand_in.parent), os.environ.get("PATH", "")])

    def _start_when_asked(self) -> None:
        import select

        if self._listener in select.select([self._listener, self._stop_r], [], [])[0]:
            fd = self._listener.fileno()
            self._server = self._popen(
                [sys.executable, os.path.abspath(__file__), "--serve", str(fd), self._notebooks],
                stdin=-1, stdout=-1, text=True, pass_fds=[fd],
            )

    def close(self) -> dict:
        os.write(self._stop_w, b"x")
        self._thread.join()
        self._listener.close()
        done = {k: {"n": 0, "cpu_s": 0.0, "cpu_s_each": []} for k in ("kernel", "papermill")}
        if self._server is not None:
            out, _ = self._server.communicate(timeout=120)
            done = json.loads(out.strip().splitlines()[-1])
        os.close(self._stop_r)
        os.close(self._stop_w)
        self._rmtree(self._dir, ignore_errors=True)
        return done


if __name__ == "__main__":
    if sys.argv[1:2] == ["--serve"]:
        from pathlib import Path

        serve(int(sys.argv[2]), Path(sys.argv[3]))
    else:
        sys.exit(stub(sys.argv[1:]))
