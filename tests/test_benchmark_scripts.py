"""Every benchmark script imports against the package as it is and its argument parser works.

The benchmarks time methods and are run by hand (benchmarks/README.md), so a renamed function or a changed
signature would otherwise go unseen until someone measures. This runs each ``benchmarks/bench_*.py`` and
``benchmarks/run.py`` with ``--help`` (no timing, no work: argparse prints the usage and exits), all in one
fresh process so that the package's modules are imported once.
"""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "benchmarks").glob("bench_*.py")) + [ROOT / "benchmarks" / "run.py"]

# Runs each script as ``python benchmarks/<script> --help`` would (its folder first on sys.path, run as
# __main__) and reports, per script, the exit code and whether argparse printed a usage line.
HARNESS = r"""
import contextlib, io, json, runpy, sys, traceback
out = {}
for path in sys.argv[1:]:
    sys.argv = [path, "--help"]
    sys.path.insert(0, path.rsplit("/", 1)[0])
    buf = io.StringIO()
    try:
        with contextlib.redirect_stdout(buf):
            runpy.run_path(path, run_name="__main__")
        code = 0
    except SystemExit as e:
        code = e.code or 0
    except BaseException:
        code = traceback.format_exc(limit=-3)
    finally:
        sys.path.pop(0)
    out[path] = {"code": code, "usage": buf.getvalue().lstrip().startswith("usage:")}
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def helped() -> dict:
    r = subprocess.run([sys.executable, "-c", HARNESS, *map(str, SCRIPTS)], cwd=ROOT, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_benchmark_imports_and_parses(script: Path, helped: dict) -> None:
    result = helped[str(script)]
    assert result["code"] == 0, f"{script.name} --help: {result['code']}"
    assert result["usage"], f"{script.name} --help printed no usage line: it has no argument parser"


def test_every_benchmark_is_listed_in_the_readme() -> None:
    readme = (ROOT / "benchmarks" / "README.md").read_text()
    missing = [p.stem.removeprefix("bench_") for p in SCRIPTS if p.name != "run.py"
               and f"| `{p.stem.removeprefix('bench_')}` |" not in readme]
    assert not missing, f"benchmarks/README.md's table leaves out {missing}"


def _bench_command():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import bench_command
    finally:
        sys.path.pop(0)
    return bench_command


def test_bench_command_parses_the_commands_the_performance_page_names() -> None:
    """Each ``bench_command.py`` command of the snapshot's rows parses to its name, its options and the whole
    command after ``--`` (an option before ``--`` once made argparse refuse the command)."""
    snapshot = json.loads((ROOT / "docs" / "_data" / "performance.json").read_text())
    listed = [r["command"].strip("`") for r in [*snapshot["rows"], *snapshot["not_measured"]]]
    commands = [c for c in listed if c.startswith("python benchmarks/bench_command.py ")]
    assert any("--size" in c for c in commands), "no command with an option before --: nothing tested"
    bench_command = _bench_command()
    for text in commands:
        argv = shlex.split(text)[2:]
        _, a = bench_command.parse_args(argv)
        assert a.name == argv[0], text
        assert a.command == argv[argv.index("--") + 1:], text
        if "--size" in argv:
            assert str(a.size) == argv[argv.index("--size") + 1], text
