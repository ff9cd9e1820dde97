"""The product speaks of itself only: no project history in what users read and run.

README, docs, code, comments, docstrings, tests, the workflow, the configuration,
notebooks and benchmarks describe the software as it is. What changed goes to
CHANGELOG.md; how a number was measured goes beside it as the command that
reproduces it. This test greps for the marks history leaves and names each
file:line it finds.
"""

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

# what users read and run; CHANGELOG.md and CITATION.cff hold history and dates on purpose
ROOTS = (
    "README.md",
    "CONTRIBUTING.md",
    "Snakefile",
    "docs",
    "src",
    "tests",
    "workflow",
    "config",
    "notebooks",
    "benchmarks",
)
SUFFIXES = {
    ".py",
    ".md",
    ".rst",
    ".smk",
    ".yaml",
    ".yml",
    ".tsv",
    ".ipynb",
    ".txt",
    ".toml",
    ".cfg",
    ".css",
    ".mplstyle",
    "",
}
SKIP_PARTS = {"_build", "__pycache__", ".ipynb_checkpoints", "data"}
SKIP_SUFFIX = ".egg-info"
THIS = Path(__file__).resolve()

PATTERNS = {
    "an issue number": re.compile(r"\bissues?\s+#?\d+", re.IGNORECASE),
    "a session": re.compile(r"\bsessions?\b", re.IGNORECASE),
    # 7 to 40 hex digits with at least one letter and one digit, as a word: a commit id
    "a commit id": re.compile(r"(?<![\w./-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}(?![\w-])"),
    "a date": re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b"),
    # a machine's load figure in prose (a number after "load" or "load average", in brackets or after "at"); not a
    # force ("a radial load of 500 N", "load 100-2000 N") or a count ("load 7")
    "a machine load": re.compile(
        r"\bat (?:a )?load(?: of)? ~?\d+(?:\.\d+)?(?:\s*[-–]\s*\d+)?(?![\d.])(?!\s*(?:k?N\b|N/|%))|\bload ~\d|\bload average\b|\(load ~?\d+(?:[-–]\d+)?\)|, load ~?\d+\)"
        r"|\bload \d+(?:\.\d+)?\s*[-–]\s*\d+(?:\.\d+)?(?![\d.])(?!\s*(?:k?N\b|N/|%|µ|um\b|mm\b|m\b))"
    ),
}


# "session" in pytest's sense (a test session, its fixtures and hooks) is not history
PYTEST_SESSION = re.compile(
    r"pytest|fixture|scope=|xdist|worker|test session|session(?:start|finish)|\(session\)"
)
# a notebook's cell ids are random hex, not commit ids
NOTEBOOK_ID = re.compile(r'^\s*"id": "[0-9a-f-]+",?$')


def _files():
    for root in ROOTS:
        path = REPO / root
        if path.is_file():
            yield path
            continue
        for file in sorted(path.rglob("*")):
            if (
                file.is_file()
                and file.suffix in SUFFIXES
                and not SKIP_PARTS & set(file.relative_to(REPO).parts)
            ):
                if file.resolve() != THIS and not any(part.endswith(SKIP_SUFFIX) for part in file.parts):
                    yield file


def findings() -> list[str]:
    """Every ``file:line: what`` the history patterns match."""
    found = []
    for file in _files():
        try:
            text = file.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for number, line in enumerate(text.splitlines(), start=1):
            if file.suffix == ".ipynb" and NOTEBOOK_ID.match(line):
                continue
            hits = []
            for what, pattern in PATTERNS.items():
                match = pattern.search(line)
                if match and not (what == "a session" and PYTEST_SESSION.search(line)):
                    hits.append(f"{what} ({match.group(0)!r})")
            if hits:
                found.append(f"{file.relative_to(REPO)}:{number}: " + ", ".join(hits))
    return found


def test_no_history_in_the_product():
    found = findings()
    assert not found, (
        f"{len(found)} lines carry project history; describe the software as it is, move what changed to "
        "CHANGELOG.md and put the command that reproduces a number beside it:\n" + "\n".join(found)
    )
