"""Every command the README, getting started and the guides show runs, in a copy of a fresh clone after the CI
workflow (the ``ci_run`` fixture: ``snakemake all study_all --configfile config/ci.yaml``).

Each command is of one kind: ``piezobearing`` and shell commands run as written; ``snakemake`` commands run as a
dry run (``-n``: the targets, the config files and the profile resolve); what rebuilds the paper, runs a study or
installs an environment (``install``, and every ``snakemake`` command again without ``-n``) runs only with
``PIEZOBEARING_EXPENSIVE=1``, under the marker ``expensive``. A synopsis with placeholders (``RECORD``, your
``data/my_...`` file) is listed, not run. A config file a page writes in a ``yaml`` block whose first line names it
(``# my.yaml``) is written before the page's commands run. A command of no known kind fails the test.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import BIN, REPO, workflow_env

PAGES = [REPO / "README.md", REPO / "docs" / "getting_started.md", *sorted((REPO / "docs" / "guides").glob("*.md"))]
EXPENSIVE = os.environ.get("PIEZOBEARING_EXPENSIVE") == "1"
PLACEHOLDERS = re.compile(r"(?<![\w/])(RECORD|DIR|RIG\.yaml)(?![\w])|\bdata/my_")


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.DOTALL)


def page_commands(page: Path) -> list[str]:
    """The shell commands of ``page``'s ``bash`` blocks: continuation lines joined, comments dropped."""
    out = []
    for block in _blocks(page.read_text(), "bash"):
        for line in re.sub(r"\\\n\s*", " ", block).splitlines():
            line = re.sub(r"\s+#\s.*$", "", line).strip()
            if line and not line.startswith("#"):
                out.append(line)
    return out


def page_files(page: Path) -> dict[str, str]:
    """The config files ``page`` writes: ``yaml`` blocks whose first line is ``# NAME.yaml`` (maybe ``: ...``)."""
    files = {}
    for block in _blocks(page.read_text(), "yaml"):
        m = re.match(r"#\s*([\w.-]+\.yaml)\b", block)
        if m:
            files[m.group(1)] = block
    return files


def kind(command: str) -> str:
    if PLACEHOLDERS.search(command):
        return "synopsis"
    if re.match(r"(python3\.11 -m venv|pip install)", command):
        return "install"
    first = command.split()[0]
    if first in ("piezobearing", "cat", "printf") or command.startswith("python -m json.tool"):
        return "run"
    if first == "snakemake":
        return "snakemake"
    if " && " in command and all(kind(part) in ("snakemake", "script") for part in command.split(" && ")):
        return "snakemake"
    if command.startswith(("python scripts/", "python validation/")):
        return "script"
    return "unknown"


CASES = [(page, command) for page in PAGES for command in page_commands(page)]
IDS = [f"{page.relative_to(REPO)}: {command[:60]}" for page, command in CASES]


def test_every_page_shows_commands_and_each_has_a_kind():
    assert len(CASES) > 30
    unknown = [c for (p, c) in CASES if kind(c) == "unknown"]
    assert not unknown, f"commands of no known kind (add one to tests/test_docs_commands.py): {unknown}"


def test_kinds():
    assert kind("piezobearing diagnose-bearing RECORD --config RIG.yaml --out DIR") == "synopsis"
    assert kind("piezobearing validate data/my_calibration.csv") == "synopsis"
    assert kind("piezobearing detect tests/data/cwru/fe44.mat --bearing 'SKF 6203' --out x") == "run"
    assert kind("snakemake --cores 2 study_sensor_design") == "snakemake"
    assert kind("pip install -e '.[docs]' && sphinx-build -W -b html docs docs/_build/html") == "install"
    assert kind("rm -rf /") == "unknown"


PYTHON_PAGES = [p for p in PAGES[1:] if "```python" in p.read_text()]


def test_a_guide_shows_python():
    assert PYTHON_PAGES, "no guide shows a Python example"


@pytest.mark.parametrize("page", PYTHON_PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_python_examples_run(page):
    """Every ``python`` block of getting started and the guides runs as written from the repository root and
    prints what its ``# comments`` say (the README's: tests/test_readme.py)."""
    for code in _blocks(page.read_text(), "python"):
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=300)
        assert run.returncode == 0, run.stderr[-2000:]
        for expected in re.findall(r"#\s*(.+)$", code, flags=re.MULTILINE):
            assert expected.strip() in run.stdout, (expected, run.stdout)


@pytest.fixture(scope="module")
def clone(ci_run, tmp_path_factory) -> Path:
    """A copy of the CI run's folder, so that the pages' commands never touch the run other tests read."""
    dest = tmp_path_factory.mktemp("docs_commands") / "repo"
    shutil.copytree(ci_run, dest, symlinks=True)
    return dest


def _run(command: str, cwd: Path, timeout: int) -> subprocess.CompletedProcess:
    env = {**workflow_env(), "PATH": os.pathsep.join([str(BIN), workflow_env()["PATH"]])}
    return subprocess.run(["bash", "-c", command], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)


def _prepare(page: Path, cwd: Path) -> None:
    for name, text in page_files(page).items():
        (cwd / name).write_text(text)


def _dry(command: str) -> str:
    """``command`` (one or more snakemake calls joined by ``&&``) with each snakemake call a dry run."""
    parts = []
    for part in command.split(" && "):
        if part.startswith("snakemake"):
            args = shlex.split(part)[1:]
            parts.append(shlex.join(["snakemake", "-n", *[a for a in args if a != "-n"]]))
    return " && ".join(parts)


def page_kind(page: Path, command: str) -> str:
    """:func:`kind`, and a synopsis where a config file the page writes names a placeholder (your record)."""
    files = page_files(page)
    names = re.findall(r"--configfile\s+(\S+)", command)
    if any(PLACEHOLDERS.search(files.get(name, "")) for name in names):
        return "synopsis"
    return kind(command)


@pytest.mark.slow
@pytest.mark.parametrize("page, command", CASES, ids=IDS)
def test_command_runs(page, command, clone):
    k = page_kind(page, command)
    if k in ("synopsis", "install", "script"):
        pytest.skip(f"{k}: run by test_expensive_command_runs with PIEZOBEARING_EXPENSIVE=1" if k != "synopsis"
                    else "a synopsis with placeholders")
    _prepare(page, clone)
    run = _run(_dry(command) if k == "snakemake" else command, clone, timeout=900)
    assert run.returncode == 0, f"{command}\n{(run.stdout + run.stderr)[-3000:]}"


@pytest.mark.expensive
@pytest.mark.skipif(not EXPENSIVE, reason="rebuilds the paper, runs studies, installs: PIEZOBEARING_EXPENSIVE=1")
@pytest.mark.parametrize("page, command", CASES, ids=IDS)
def test_expensive_command_runs(page, command, clone):
    if page_kind(page, command) not in ("snakemake", "install", "script"):
        pytest.skip("run by test_command_runs, or a synopsis")
    _prepare(page, clone)
    run = _run(command, clone, timeout=4 * 3600)
    assert run.returncode == 0, f"{command}\n{(run.stdout + run.stderr)[-3000:]}"
