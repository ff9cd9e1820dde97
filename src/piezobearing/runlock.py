"""One workflow run per folder, told apart from a stale lock.

Snakemake locks a working folder while it runs, but a second ``snakemake``
started meanwhile is told to remove the lock with ``--unlock`` or to rerun
with ``--rerun-incomplete``: advice that breaks the run still going. The
workflow (``workflow/rules/common.smk``) therefore records the process id of
a running ``snakemake`` in ``.snakemake/piezobearing-run.pid`` and, at every
start, checks whether that process is still alive: if it is, a second run
stops with one line naming it; a pid file left by a killed run is ignored
(Snakemake's own ``--unlock`` advice is then right).
"""

from __future__ import annotations

import atexit
import os
from pathlib import Path

PID_FILE = Path(".snakemake") / "piezobearing-run.pid"

#: Snakemake options that only inspect the workflow (no jobs run): they neither claim the folder nor
#: are refused while another run is active.
INSPECTING = frozenset(
    {
        "--dry-run",
        "--dryrun",
        "--lint",
        "--dag",
        "--rulegraph",
        "--filegraph",
        "--list",
        "--list-rules",
        "--list-target-rules",
        "--summary",
        "--detailed-summary",
        "--report",
        "--help",
        "--version",
    }
)


def inspecting(argv: list[str]) -> bool:
    """Whether a snakemake command line only inspects (``-n``, ``-np``, ``--lint``, ...)."""
    for a in argv[1:]:
        if a.split("=", 1)[0] in INSPECTING or a in ("-l", "-S", "-D", "-h"):
            return True
        if a.startswith("-") and not a.startswith("--") and a[1:].isalpha() and "n" in a[1:]:
            return True
    return False


def _ancestors() -> set[int]:
    """This process and its parents (a job's own snakemake subprocess must not see its parent as 'another')."""
    out, pid = set(), os.getpid()
    while pid > 1 and pid not in out:
        out.add(pid)
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
            pid = int(stat.rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            break
    return out


def _is_snakemake(pid: int) -> bool:
    """Whether ``pid`` is alive and runs snakemake (a recycled pid of another program does not count)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # alive, owned by another user
    try:
        return b"snakemake" in Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return True  # no /proc (macOS): trust the signal check


def active_run(folder: str | Path = ".") -> int | None:
    """The pid of another live snakemake run in ``folder``, else None."""
    try:
        pid = int((Path(folder) / PID_FILE).read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None
    if pid in _ancestors() or not _is_snakemake(pid):
        return None
    return pid


def claim(folder: str | Path = ".") -> None:
    """Record this process as the folder's running snakemake; released at exit."""
    p = Path(folder) / PID_FILE
    pid = os.getpid()
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(f"{pid}\n")
    except OSError:
        return
    atexit.register(release, folder, pid)


def release(folder: str | Path = ".", pid: int | None = None) -> None:
    """Remove the pid file if it still names ``pid`` (default: this process)."""
    p = Path(folder) / PID_FILE
    try:
        if int(p.read_text().split()[0]) == (os.getpid() if pid is None else pid):
            p.unlink()
    except (OSError, ValueError, IndexError):
        pass


def message(pid: int) -> str:
    """The one line a second run gets."""
    return (
        f"another snakemake run is active in this folder (pid {pid}); wait for it to finish or stop it "
        f"(kill {pid}) before starting another; do not use --unlock or --rerun-incomplete while it runs "
        "(a dry run, -n, is safe)"
    )
