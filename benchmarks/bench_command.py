"""One command's wall and CPU seconds and peak memory under GNU time, and optionally the size of a folder it made.

For what no method benchmark measures: the whole paper, a study, the CI workflow, the test suite, the install.
Writes ``results/benchmarks/command_<name>.json``, which ``scripts/performance_snapshot.py`` reads for the
performance page, with the keys ``name``, ``command`` (as run), ``wall_s``, ``user_s``, ``system_s``,
``cpu_s``, ``peak_rss_MB``, ``exit_ok`` and ``size_MB`` (null without ``--size``).

``cpu_s`` is the user and system CPU of the command and every process it waited for; ``peak_rss_MB`` the peak
resident memory of its largest single process; ``size_MB`` (``--size DIR``) the disk use of ``DIR`` after the
command (``du``). ``--parse LOG`` writes the same record from a GNU time -v report of a run made by hand.

Usage (from the repository root, the package's environment active; a fresh clone for the paper)::

    python benchmarks/bench_command.py paper -- snakemake --cores 2
    python benchmarks/bench_command.py study_all -- snakemake --cores 2 study_all
    python benchmarks/bench_command.py tests -- pytest -n 2
    python benchmarks/bench_command.py install --size /tmp/pb-venv -- \\
        sh -c 'python3.11 -m venv /tmp/pb-venv && /tmp/pb-venv/bin/pip install .'
    python benchmarks/bench_command.py ci --command "snakemake --cores 1 --configfile config/ci.yaml" --parse time.log
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_workflow import parse_time_log

ROOT = Path(__file__).resolve().parents[1]


def folder_size_MB(path: Path) -> float:
    """Disk use of ``path`` in MB (10^6 bytes), as ``du -sb`` counts it."""
    out = subprocess.run(["du", "-sb", str(path)], capture_output=True, text=True, check=True).stdout
    return int(out.split()[0]) / 1e6


def measure(command: list[str]) -> dict:
    """Run ``command`` from the repository root under ``/usr/bin/time -v``; its report as a dict."""
    with tempfile.NamedTemporaryFile("r", suffix=".log") as log:
        run = subprocess.run(["/usr/bin/time", "-v", "-o", log.name, *command], cwd=ROOT)
        record = parse_time_log(Path(log.name).read_text())
    record["exit_ok"] = run.returncode == 0
    return record


def split_command(argv: list[str]) -> tuple[list[str], list[str]]:
    """``argv`` cut at its first ``--``: the options, and the command to time.

    Cut by hand because argparse gives a ``nargs="*"`` positional its (empty) value at the name, before
    an option such as ``--size``, and then refuses the command after it.
    """
    if "--" not in argv:
        return argv, []
    cut = argv.index("--")
    return argv[:cut], argv[cut + 1:]


def parse_args(argv: list[str]) -> tuple[argparse.ArgumentParser, argparse.Namespace]:
    """The parser and ``argv`` parsed by it, ``command`` the command to time (after ``--``)."""
    options, command = split_command(argv)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("name", help="the record's name: results/benchmarks/command_NAME.json")
    ap.add_argument("command", nargs="*", help="the command to time (after --)")
    ap.add_argument("--size", type=Path, help="a folder whose disk use to record after the command")
    ap.add_argument("--parse", type=Path, help="a GNU time -v report of a run made by hand, instead of running")
    ap.add_argument("--command", dest="command_text", help="with --parse: the command that report timed")
    a = ap.parse_args(options)
    a.command = [*a.command, *command]
    return ap, a


def main(argv: list[str] | None = None) -> int:
    ap, a = parse_args(sys.argv[1:] if argv is None else list(argv))
    if a.parse:
        if not a.command_text:
            ap.error("--parse needs --command, the command the report timed")
        record, text = parse_time_log(a.parse.read_text()), a.command_text
    else:
        if not a.command:
            ap.error("give the command to time after --")
        record, text = measure(a.command), shlex.join(a.command)
    record = {"name": a.name, "command": text, **record, "size_MB": folder_size_MB(a.size) if a.size else None}
    out = ROOT / "results" / "benchmarks" / f"command_{a.name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record, indent=1))
    return 0 if record["exit_ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
