"""The performance page's tables, generated at build time from ``docs/_data/performance.json``.

The snapshot is written by ``scripts/performance_snapshot.py`` from benchmark result files; no number on the page
is typed. Four directives:

``performance-table``
    every measured row: its id and what it measures, the value, memory, the command that measures it, the machine (a short id).
``performance-machines``
    the machines the rows were measured on.
``performance-rules``
    the workflow's rules as Snakemake's ``benchmark:`` files measured them, with the run's command.
``performance-unmeasured``
    the rows the snapshot does not hold yet, each with its command and no number.
"""

from __future__ import annotations

import json
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

SNAPSHOT = Path(__file__).resolve().parents[1] / "_data" / "performance.json"


def load() -> dict:
    return json.loads(SNAPSHOT.read_text())


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
    return lines


class _SnapshotDirective(SphinxDirective):
    has_content = False

    def lines(self, snapshot: dict) -> list[str]:
        raise NotImplementedError

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(str(SNAPSHOT))
        container = nodes.container(classes=["performance"])
        text = self.lines(load())
        self.state.nested_parse(StringList(text, source=str(SNAPSHOT)), self.content_offset, container)
        return container.children


class PerformanceTable(_SnapshotDirective):
    def lines(self, s: dict) -> list[str]:
        rows = [[f"`{r['id']}`: {r['what']}", r["value"], r["memory"], r["command"], f"`{r['machine']}`"]
                for r in s["rows"]]
        return _table(["what", "time", "memory", "command", "machine"], rows)


class PerformanceMachines(_SnapshotDirective):
    def lines(self, s: dict) -> list[str]:
        rows = [[f"`{k}`", m["cpu"], str(m["cores"]), f"{m['memory_GiB']} GiB", m["system"], m["python"]]
                for k, m in s["machines"].items()]
        return _table(["machine", "CPU", "cores", "memory", "system", "Python"], rows)


class PerformanceRules(_SnapshotDirective):
    def lines(self, s: dict) -> list[str]:
        rules = s.get("rules")
        if not rules:
            return ["No workflow run's per-rule files are in the snapshot."]
        head = [f"`{rules['command']}`, on machine `{rules['machine']}`:", ""]
        rows = [[f"`{r['rule']}`", str(r["jobs"]), f"{r['wall_s']:.1f}", f"{r['cpu_s']:.1f}", f"{r['peak_rss_MB']:.0f}"]
                for r in rules["rows"]]
        return head + _table(["rule", "jobs", "wall [s]", "Snakemake's cpu_time [s]", "peak RSS [MB]"], rows)


class PerformanceUnmeasured(_SnapshotDirective):
    def lines(self, s: dict) -> list[str]:
        if not s["not_measured"]:
            return ["Every row is measured."]
        return [f"- `{r['id']}`: {r['what']}: {r['command']}" for r in s["not_measured"]]


def setup(app):
    app.add_directive("performance-table", PerformanceTable)
    app.add_directive("performance-machines", PerformanceMachines)
    app.add_directive("performance-rules", PerformanceRules)
    app.add_directive("performance-unmeasured", PerformanceUnmeasured)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
