"""The workflow's figures on the site: checked against the current code and config, and a gallery.

``scripts/docs_figures.py`` copies the figures of a workflow run to ``docs/_static/figures/`` with
``provenance.json`` (per figure its rule, the code hash of the rule's notebook or script, the digest of the
config values the rule declares, the PNG's SHA-256 and its scorecard rows). When the build starts, this
extension recomputes each code hash and config digest and each PNG's SHA-256, and stops the build when one
differs: the site never shows a figure the current code or config would not make.

``figure-gallery``
    every figure with its title, the scorecard rows beside it, and where it came from.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.errors import ExtensionError
from sphinx.util.docutils import SphinxDirective

from piezobearing import config as config_loader
from piezobearing.workflow.registry import code_hash, reads_digest

DOCS = Path(__file__).resolve().parents[1]
REPO = DOCS.parent
FIGURES = DOCS / "_static" / "figures"
PROVENANCE = FIGURES / "provenance.json"
REMEDY = "rerun the workflow and then `python scripts/docs_figures.py --configfile ...`"


def stale_figures(record: dict) -> list[str]:
    """Each figure of ``record`` that the current code, the current config or its own file contradicts."""
    configs: dict[tuple[str, ...], dict] = {}
    problems = []
    for name, fig in record["figures"].items():
        files = tuple(fig.get("configfiles", record["configfiles"]))  # a figure of another run names its own
        if files not in configs:
            configs[files] = config_loader.load(*[REPO / c for c in files])
        cfg = configs[files]
        png = FIGURES / name
        if not png.exists():
            problems.append(f"{name}: missing from docs/_static/figures/")
            continue
        if hashlib.sha256(png.read_bytes()).hexdigest() != fig["sha256"]:
            problems.append(f"{name}: not the file provenance.json records")
        if code_hash(str(REPO / fig["entry"])) != fig["code_hash"]:
            problems.append(f"{name}: made by other code than the current {fig['entry']} and its imports")
        if reads_digest(cfg, fig["rule"]) != fig["config_digest"]:
            problems.append(f"{name}: made with other config values than rule {fig['rule']} now reads")
    return problems


def check(app) -> None:
    record = json.loads(PROVENANCE.read_text())
    problems = stale_figures(record)
    if problems:
        raise ExtensionError("figures on the site are not the current ones (" + REMEDY + "):\n  " + "\n  ".join(problems))


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _number(text: str) -> str:
    try:
        return f"{float(text):.4g}"
    except ValueError:
        return text


class FigureGallery(SphinxDirective):
    has_content = False

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(str(PROVENANCE))
        record = json.loads(PROVENANCE.read_text())
        configs = ", ".join(f"`{c}`" for c in record["configfiles"]) or "`config/config.yaml`"
        intro = [f"These come from a workflow run on {configs}, copied here by `{record['made_by']}`."]
        lines = []
        for name, fig in record["figures"].items():
            if "configfiles" in fig:  # a guide's figure of another run (its guide shows it), not the paper's
                continue
            lines += [f"## {fig['title']}", "", f"```{{figure}} /_static/figures/{name}", ":width: 100%",
                      f":alt: {fig['title']}", "",
                      f"`{fig['source']}`, rule `{fig['rule']}` (`{fig['entry']}`); code `{fig['code_hash'][:12]}`, "
                      f"config `{fig['config_digest']}`.", "```", ""]
            if fig["scorecard"]:
                lines += ["| quantity | paper | ours | unit |", "|---|---|---|---|"]
                lines += [f"| {_cell(r['quantity'])} | {_number(r['paper'])} | {_number(r['ours'])} | {_cell(r['unit'])} |"
                          for r in fig["scorecard"]]
                lines += ["", "From `results/scorecard.csv` of the same run (its notes say where the paper's "
                          "numbers cannot hold).", ""]
        head = nodes.container()
        self.state.nested_parse(StringList(intro, source=str(PROVENANCE)), self.content_offset, head)
        container = nodes.section()
        self.state.nested_parse(StringList(lines, source=str(PROVENANCE)), self.content_offset, container,
                                match_titles=True)
        return [*head.children, *container.children]


def setup(app):
    app.connect("builder-inited", check)
    app.add_directive("figure-gallery", FigureGallery)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
