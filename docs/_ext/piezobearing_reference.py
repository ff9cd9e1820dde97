"""Reference pages generated at build time from the sources they describe.

Two directives, so the reference never drifts from the code:

``.. config-reference::``
    Every key of ``config/schema.yaml`` (type, unit, bounds, description) with its
    default from ``config/config.yaml``, one section per top-level key.
``.. cli-reference::``
    Every command of ``piezobearing`` read from its argparse parser
    (``piezobearing.cli._parser``): usage, description and each argument.

Both build docutils nodes directly (no reST text is re-parsed), so a description's
``*``, ``|`` or trailing ``_`` is printed as written.
"""

import argparse
import json
import re
from pathlib import Path

import yaml
from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.util.nodes import make_id

from piezobearing import cli

REPO = Path(__file__).resolve().parents[2]
SCHEMA = REPO / "config" / "schema.yaml"
DEFAULTS = REPO / "config" / "config.yaml"
UNIT = re.compile(r"\s*\[([^\[\]]+)\]\.?\s*$")
MISSING = object()


# --------------------------------------------------------------------------- tables as nodes


def _cell(content) -> nodes.entry:
    entry = nodes.entry()
    if isinstance(content, nodes.Node):
        entry += content if isinstance(content, nodes.paragraph) else nodes.paragraph("", "", content)
    else:
        entry += nodes.paragraph("", str(content))
    return entry


def _table(header: list[str], rows: list[list], widths: list[int], classes: list[str]) -> nodes.table:
    table = nodes.table(classes=[*classes, "colwidths-given"])
    group = nodes.tgroup(cols=len(header))
    table += group
    for width in widths:
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    group += head
    head_row = nodes.row()
    for title in header:
        head_row += _cell(title)
    head += head_row
    body = nodes.tbody()
    group += body
    for cells in rows:
        row = nodes.row()
        for content in cells:
            row += _cell(content)
        body += row
    return table


def _section(document, title: str, anchor: str) -> nodes.section:
    section = nodes.section()
    section["ids"].append(make_id(document.settings.env, document, "", anchor))
    section["names"].append(nodes.fully_normalize_name(anchor))
    section += nodes.title("", title)
    document.note_implicit_target(section)
    return section


def _break_points(node: nodes.Element, text: str) -> nodes.Element:
    """``node`` holding ``text`` with a line-break opportunity (an HTML ``<wbr>``) after each ``.`` and ``_``."""
    for part in re.split(r"(?<=[._])", text):
        if node.children:
            node += nodes.raw("", "<wbr>", format="html")
        node += nodes.Text(part)
    return node


def _literal(text: str) -> nodes.literal:
    """``text`` as code that a narrow column may break after a ``.`` or ``_`` (an HTML ``<wbr>``), never inside a
    word: a key or a value such as ``apc850_paper`` stays readable and copies as written."""
    return _break_points(nodes.literal(text), text)


# --------------------------------------------------------------------------- configuration


def _number(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _split_unit(description: str) -> tuple[str, str]:
    """Split ``"Text [unit]."`` into the text and the unit ("–" for dimensionless)."""
    match = UNIT.search(description)
    if not match:
        return description, ""
    unit = match.group(1).strip()
    return description[: match.start()].rstrip(" .") + ".", "–" if unit == "-" else unit


def _type(spec: dict) -> str:
    if "enum" in spec:
        return "one of " + ", ".join(str(v) for v in spec["enum"])
    kinds = spec.get("type", "")
    kinds = kinds if isinstance(kinds, list) else [kinds]
    names = []
    for kind in kinds:
        if kind == "array":
            item = spec.get("items", {})
            names.append("list of " + ("objects" if item.get("type") == "object" else _type(item)))
        elif kind == "null":
            names.append("null")
        elif kind:
            names.append(kind)
    return " or ".join(names) or "any"


def _bounds(spec: dict) -> str:
    parts = []
    for key, sign in (
        ("minimum", "≥"),
        ("exclusiveMinimum", ">"),
        ("maximum", "≤"),
        ("exclusiveMaximum", "<"),
    ):
        if key in spec:
            parts.append(f"{sign} {_number(spec[key])}")
    if "minItems" in spec or "maxItems" in spec:
        low, high = spec.get("minItems"), spec.get("maxItems")
        count = f"{low} items" if low == high else f"{low or 0}–{high if high is not None else '…'} items"
        parts.append(count)
    item = spec.get("items")
    if item and item.get("type") != "object" and "enum" not in item:
        inner = _bounds(item)
        if inner:
            parts.append("each " + inner)
    return ", ".join(parts)


def _default(value) -> str:
    if value is MISSING:
        return ""
    text = json.dumps(value, ensure_ascii=False)
    return text if len(text) <= 120 else text[:117] + "…"


def _rows(spec: dict, path: str, defaults, required: bool) -> list[list]:
    """One row per key below ``spec`` (depth first), objects of lists as ``key[].child``."""
    description, unit = _split_unit(spec.get("description", ""))
    children = spec.get("properties")
    item = spec.get("items", {})
    rows = []
    if not children:  # a leaf (or a list): one row
        rows.append(
            [
                _literal(path),
                _break_points(nodes.paragraph(), _type(spec)),
                unit,
                _bounds(spec),
                _literal(_default(defaults)) if defaults is not MISSING else "",
                _break_points(nodes.paragraph(), description + ("" if required else " Optional.")),
            ]
        )
    else:
        rows.append([_literal(path), "object", "", "", "", description])
    child_specs = children or (item.get("properties") if item.get("type") == "object" else None) or {}
    prefix = path if children else path + "[]"
    needed = set((spec if children else item).get("required", []))
    for key, child in child_specs.items():
        value = defaults.get(key, MISSING) if children and isinstance(defaults, dict) else MISSING
        rows += _rows(child, f"{prefix}.{key}", value, key in needed)
    return rows


class ConfigReference(Directive):
    """Every configuration key, from the schema, with the default configuration's value."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        document = self.state.document
        env = document.settings.env
        env.note_dependency(str(SCHEMA))
        env.note_dependency(str(DEFAULTS))
        schema = yaml.safe_load(SCHEMA.read_text())
        defaults = yaml.safe_load(DEFAULTS.read_text())
        required = set(schema.get("required", []))
        sections = []
        for key, spec in schema["properties"].items():
            section = _section(document, key, f"config-{key}")
            description, _ = _split_unit(spec.get("description", ""))
            section += nodes.paragraph("", description + ("" if key in required else " Optional section."))
            rows = _rows(spec, key, defaults.get(key, MISSING), key in required)
            if spec.get("properties"):
                rows = rows[1:]  # the section's own row is its title and paragraph
            section += _table(
                ["key", "type", "unit", "bounds", "default", "meaning"],
                rows,
                [24, 14, 7, 10, 13, 32],
                ["config-reference"],
            )
            sections.append(section)
        return sections


# --------------------------------------------------------------------------- command line


def _argument_rows(parser: argparse.ArgumentParser) -> list[list]:
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction | argparse._HelpAction):
            continue
        name = ", ".join(action.option_strings) if action.option_strings else action.dest
        if action.option_strings and action.nargs != 0:
            name += " " + (action.metavar or action.dest.upper())
        default = (
            ""
            if action.default in (None, False, argparse.SUPPRESS) or action.nargs == 0
            else str(action.default)
        )
        required = not action.option_strings or action.required
        rows.append([_literal(name), "yes" if required else "", default, action.help or ""])
    return rows


class CliReference(Directive):
    """Every ``piezobearing`` command, read from the argparse parser."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        document = self.state.document
        document.settings.env.note_dependency(cli.__file__)
        parser = cli._parser()
        out = [nodes.paragraph("", (parser.description or "").replace("``", ""))]
        out.append(nodes.literal_block("", parser.format_usage().strip()))
        if parser.epilog:
            out.append(nodes.paragraph("", parser.epilog))
        out.append(
            _table(
                ["argument", "required", "default", "meaning"],
                _argument_rows(parser),
                [24, 10, 10, 56],
                ["cli-reference"],
            )
        )
        commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        summaries = {choice.dest: choice.help for choice in commands._choices_actions}
        for name, sub in commands.choices.items():
            section = _section(document, f"piezobearing {name}", f"cli-{name}")
            section += nodes.paragraph("", sub.description or summaries.get(name) or "")
            section += nodes.literal_block("", sub.format_usage().strip())
            section += _table(
                ["argument", "required", "default", "meaning"],
                _argument_rows(sub),
                [24, 10, 10, 56],
                ["cli-reference"],
            )
            out.append(section)
        return out


def setup(app):
    app.add_directive("config-reference", ConfigReference)
    app.add_directive("cli-reference", CliReference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
