"""The scorecard: every number of the paper beside ours.

Each stage writes a fragment (``RESULTS/scorecard/<stage>.csv``) with :func:`write_part`; the ``scorecard`` rule
gathers them with :func:`assemble`. A row names the conditions of the paper's case it depends on
(:data:`piezobearing.config.paper.CASE`); it is compared with the paper only where the run's config holds them all, and
marked "not the paper's case" otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ..config.paper import CASE, case_value, differs

#: Columns of a stage's fragment.
PART_COLUMNS = ["section", "quantity", "paper", "ours", "unit", "rel_error", "note", "conditions"]
#: Columns of scorecard.csv: a fragment's, and whether the row is compared with the paper (its conditions hold).
COLUMNS = [*PART_COLUMNS, "compared"]
#: What the rel. error column says of a row whose conditions are not the paper's.
NOT_THE_PAPERS_CASE = "not the paper's case"


@dataclass(frozen=True)
class Row:
    """One paper number and ours.

    ``paper`` may be None for a quantity the paper does not state; ``note`` says where they differ and why (with
    the arithmetic); ``conditions`` are the keys of :data:`piezobearing.config.paper.CASE` the comparison needs.
    """

    section: str
    quantity: str
    paper: float | None
    ours: float
    unit: str
    note: str = ""
    conditions: tuple[str, ...] = ()

    def __post_init__(self):
        unknown = [k for k in self.conditions if k not in CASE]
        if unknown:
            raise KeyError(f"scorecard row {self.quantity!r}: {unknown[0]} is not a key of piezobearing.config.paper.CASE")

    @property
    def rel_error(self) -> float:
        return _rel_error(self.paper, self.ours)


def _rel_error(paper, ours) -> float:
    if paper is None or pd.isna(paper) or paper == 0 or not math.isfinite(ours):
        return float("nan")
    return (ours - paper) / abs(paper)


def write_part(rows: list[Row], path: str | Path) -> None:
    """Write one stage's rows."""
    records = [
        {
            "section": r.section,
            "quantity": r.quantity,
            "paper": r.paper,
            "ours": r.ours,
            "unit": r.unit,
            "rel_error": r.rel_error,
            "note": r.note,
            "conditions": " ".join(r.conditions),
        }
        for r in rows
    ]
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(records, columns=PART_COLUMNS).to_csv(path, index=False)


def changed_conditions(config: dict) -> list[str]:
    """The keys of :data:`piezobearing.config.paper.CASE` where ``config`` leaves the paper's case, in table order."""
    return [k for k in CASE if differs(config, k)]


def compare(df: pd.DataFrame, config: dict) -> pd.DataFrame:
    """``df`` (fragments' rows) with ``compared`` set and ``rel_error`` kept only where every condition holds."""
    changed = set(changed_conditions(config))
    out = df.copy()
    conditions = out["conditions"].fillna("").astype(str).str.split()
    holds = conditions.map(lambda keys: not changed.intersection(keys))
    out["compared"] = holds & out["paper"].notna()
    pairs = zip(out["paper"], out["ours"], out["compared"], strict=True)
    out["rel_error"] = [_rel_error(p, o) if c else float("nan") for p, o, c in pairs]
    return out[COLUMNS]


def assemble(parts: list[str | Path], csv_out: str | Path, md_out: str | Path, config: dict) -> pd.DataFrame:
    """Concatenate the fragments into ``scorecard.csv`` and a Markdown table, compared with the paper where
    ``config`` (the run's, with the keys of :data:`piezobearing.config.paper.CASE`) holds the rows' conditions."""
    df = compare(pd.concat([pd.read_csv(p) for p in parts], ignore_index=True)[PART_COLUMNS], config)
    df.to_csv(csv_out, index=False)
    Path(md_out).write_text(to_markdown(df, config, str(md_out)))
    return df


def _fmt(x) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float):
        return f"{x:.4g}"
    return str(x)


def _condition_text(value) -> str:
    """A condition's value as the scorecard shows it."""
    if value is None:
        return "null"
    if isinstance(value, tuple):
        return "; ".join(", ".join(_fmt(v) for v in item) for item in value) if value else "none"
    return _fmt(float(value)) if isinstance(value, (int, float)) and not isinstance(value, bool) else str(value)


def conditions_table(config: dict) -> list[str]:
    """The Markdown lines listing the run's conditions beside the paper's case."""
    lines = [
        "| condition | config key | this run | the paper's case | |",
        "|---|---|---|---|---|",
    ]
    for key, cond in CASE.items():
        mark = "**differs**" if differs(config, key) else "same"
        lines.append(
            f"| {cond.label} | `{key}` | {_condition_text(case_value(config, key))} | "
            f"{_condition_text(cond.value)} | {mark} |"
        )
    return lines


def to_markdown(df: pd.DataFrame, config: dict, path: str = "results/scorecard.md") -> str:
    """The scorecard as Markdown: the run's conditions, then every row (``df`` as :func:`compare` returns it)."""
    changed = changed_conditions(config)
    verdict = (
        "This run is the paper's case: every row the paper states a number for is compared with it."
        if not changed
        else f"This run leaves the paper's case in {len(changed)} condition(s) ("
        + ", ".join(f"`{k}`" for k in changed)
        + f"): rows that depend on them are marked \"{NOT_THE_PAPERS_CASE}\" and not compared."
    )
    lines = [
        "# Scorecard: the paper's numbers beside ours",
        "",
        f"Generated by the workflow (`{path}`); rel. error = (ours - paper) / |paper|, given where the "
        "row's conditions are the paper's.",
        "",
        verdict,
        "",
        "## Conditions",
        "",
        *conditions_table(config),
        "",
        "## Numbers",
        "",
        "| section | quantity | paper | ours | unit | rel. error | note |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in df.itertuples(index=False):
        if not pd.isna(r.paper) and not r.compared:
            keys = [k for k in str(r.conditions).split() if k in changed]
            rel = f"{NOT_THE_PAPERS_CASE} ({', '.join(f'`{k}`' for k in keys)})"
        else:
            rel = "–" if pd.isna(r.rel_error) else f"{100 * r.rel_error:+.1f}%"
        note = "" if pd.isna(r.note) else str(r.note).replace("|", "\\|")
        lines.append(
            f"| {r.section} | {r.quantity} | {_fmt(r.paper)} | {_fmt(r.ours)} | {r.unit} | {rel} | {note} |"
        )
    return "\n".join(lines) + "\n"
