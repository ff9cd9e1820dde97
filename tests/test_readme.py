"""The README's and the getting-started page's commands are the ones that run.

The test command is the one `.ci/run` runs; every `piezobearing` command parses
with the real parser (its subcommand and options exist); the cheap commands run
as written (`piezobearing --help`, `snakemake -n`).
"""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from piezobearing import cli

REPO = Path(__file__).resolve().parents[1]
PAGES = [REPO / "README.md", REPO / "docs" / "getting_started.md"]


def _commands(page: Path) -> list[str]:
    """Every command line of the page's ``bash`` blocks (comments and continuations joined)."""
    text = page.read_text()
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.DOTALL):
        block = block.replace("\\\n", " ")
        lines += [
            line.split("  #")[0].strip()
            for line in block.splitlines()
            if line.strip() and not line.startswith("#")
        ]
    return lines


def test_readme_is_short():
    assert len((REPO / "README.md").read_text().splitlines()) <= 250


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_test_command_is_the_one_ci_runs(page):
    ci = (REPO / ".ci" / "run").read_text().strip().splitlines()[-1]
    assert ci in _commands(page), f"{page.name} must show .ci/run's command exactly: {ci}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_piezobearing_commands_parse(page):
    parser = cli._parser()
    found = 0
    for line in _commands(page):
        for part in line.split("&&"):
            words = shlex.split(part)
            if not words or words[0] != "piezobearing" or "--help" in words or "--version" in words:
                continue
            found += 1
            args = parser.parse_args(words[1:])  # exits (status 2) on an unknown command or option
            assert args.command == words[1]
    assert found or page.name != "README.md", "the README shows no piezobearing command"


def test_help_runs():
    run = subprocess.run(
        [sys.executable, "-m", "piezobearing.cli", "--help"], capture_output=True, text=True, cwd=REPO
    )
    assert run.returncode == 0, run.stderr
    commands = next(a for a in cli._parser()._actions if a.__class__.__name__ == "_SubParsersAction").choices
    for name in commands:
        assert name in run.stdout


def test_python_examples_run():
    """Every ``python`` block of the README runs as written from the repository root."""
    blocks = re.findall(r"```python\n(.*?)```", (REPO / "README.md").read_text(), flags=re.DOTALL)
    assert blocks, "the README shows no Python example"
    for code in blocks:
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
        assert run.returncode == 0, run.stderr[-2000:]
        for expected in re.findall(r"#\s*(.+)$", code, flags=re.MULTILINE):
            assert expected.strip() in run.stdout, (expected, run.stdout)
