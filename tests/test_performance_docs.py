"""The performance page's numbers come from the snapshot, and no page quotes a run time the snapshot does not hold."""

import importlib.util
import json
import re
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SNAPSHOT = REPO / "docs" / "_data" / "performance.json"

#: a time in a performance context: "12.3 s wall", "8 s of CPU", "3 min 29 s wall", "takes 5 s", "about 2.5 min"
TIME = r"(\d+(?:\.\d+)?) ?(ms|s|min|h)(?: (\d+(?:\.\d+)?) ?s)?"
QUOTED = [
    re.compile(TIME + r" (?:of )?(?:wall|CPU|user|system)\b"),
    re.compile(r"\b(?:CPU|wall)(?: time)?:? " + TIME + r"\b"),
    re.compile(r"\b(?:takes|took|costs?|lasts?|runs? (?:in|for)|finishes in|about) " + TIME + r"\b"),
]

def _pages() -> list[Path]:
    pages = [REPO / "README.md", REPO / "data" / "README.md", *sorted((REPO / "docs").rglob("*.md"))]
    return [p for p in pages if "_build" not in p.parts and p.name != "changelog.md"]


def _snapshot_texts(snapshot: dict) -> str:
    return " ".join(r["value"] + " " + r["memory"] for r in snapshot["rows"])


def _quotes(text: str) -> list[str]:
    text = re.sub(r"\s+", " ", text)
    found = {}
    for pattern in QUOTED:
        for m in pattern.finditer(text):
            number, unit, extra = m.group(1), m.group(2), m.group(3)
            found[m.start(1)] = f"{number} {unit}" + (f" {extra} s" if extra else "")
    return [found[start] for start in sorted(found)]


def test_quote_finder_sees_run_times():
    """The finder is not vacuous: it finds the run times of a sentence and leaves physical durations alone."""
    text = "The study took 30 min 37 s wall and 1202 s of CPU; CPU 8.4 s. A 1 s record at 2550 Hz, 0.5 s apart."
    assert _quotes(text) == ["30 min 37 s", "1202 s", "8.4 s"]


def test_snapshot_rows_are_complete():
    snapshot = json.loads(SNAPSHOT.read_text())
    for row in snapshot["rows"]:
        for key in ("id", "what", "value", "memory", "quantities", "command", "source", "machine"):
            assert row.get(key) not in (None, ""), (row.get("id"), key)
        assert row["machine"] in snapshot["machines"], row["id"]
        assert row["source"].startswith("results/benchmarks/"), row["id"]
        for quantity in row["quantities"]:
            assert isinstance(quantity["value"], (int, float)) and quantity["unit"], (row["id"], quantity)
    if snapshot.get("rules"):
        assert snapshot["rules"]["machine"] in snapshot["machines"]
        assert snapshot["rules"]["rows"], "a rules table with no rule"


def test_every_row_of_the_generator_is_on_the_page():
    """Each row the generator knows is either measured in the snapshot or listed as not measured, with its command."""
    spec = importlib.util.spec_from_file_location("performance_snapshot", REPO / "scripts" / "performance_snapshot.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    snapshot = json.loads(SNAPSHOT.read_text())
    measured = {r["id"] for r in snapshot["rows"]}
    listed = {r["id"] for r in snapshot["not_measured"]}
    assert measured | listed == {r.id for r in module.ROWS}
    assert not measured & listed


def test_performance_page_types_no_number():
    text = (REPO / "docs" / "performance.md").read_text()
    body = re.sub(r"```bash.*?```", "", text, flags=re.DOTALL)
    assert "{performance-table}" in text and "{performance-rules}" in text
    assert not re.search(r"\d+(?:\.\d+)? ?(?:ms|s|min|GB|MB)\b", body), "a typed number on the performance page"


@pytest.mark.parametrize("page", _pages(), ids=lambda p: str(p.relative_to(REPO)))
def test_pages_quote_only_measured_times(page):
    rel = str(page.relative_to(REPO))
    held = _snapshot_texts(json.loads(SNAPSHOT.read_text()))
    missing = [q for q in _quotes(page.read_text()) if q not in held]
    assert not missing, f"{rel} quotes run times the performance snapshot does not hold: {missing}"
