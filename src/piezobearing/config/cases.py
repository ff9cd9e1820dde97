"""Parameter studies: a table of cases, each column a config key.

A study table (``config/studies/*.tsv``) has one row per case; each column
names a config key by its path with ``__`` between levels
(``synthesis__resistance_ohm`` is ``config["synthesis"]["resistance_ohm"]``);
a number indexes a list (``bearing__defects__0__width_m`` is the first
defect's width).
A case's config is the workflow's config with the row's values merged in and
validated against the schema, so a study can vary any key the workflow has.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd

from . import ConfigError, validate

SEP = "__"


def _child(node, key: str):
    """node[key] for a dict, node[int(key)] for a list; KeyError if there is none."""
    if isinstance(node, dict) and key in node:
        return node[key]
    if isinstance(node, list) and key.isdigit() and int(key) < len(node):
        return node[int(key)]
    raise KeyError(key)


def read_table(path: str | Path, config: dict) -> pd.DataFrame:
    """Read a study table and check that every column is a config key."""
    path = Path(path)
    if not path.exists():
        raise ConfigError(f"{path}: study table not found; fix the path under studies in the config")
    df = pd.read_csv(path, sep="\t", comment="#")
    if df.empty:
        raise ConfigError(f"{path}: the study table has no cases")
    for col in df.columns:
        node = config
        for key in col.split(SEP):
            try:
                node = _child(node, key)
            except KeyError:
                raise ConfigError(
                    f"{path}: column '{col}' is not a config key; name columns by their config path with "
                    f"'{SEP}' between levels (a number for a list item), e.g. synthesis{SEP}resistance_ohm"
                ) from None
    return df


def check_studies(config: dict) -> dict[str, pd.DataFrame]:
    """Read every configured study table and validate each case's config; the tables by study name.

    Raises :class:`ConfigError` naming the table, the case (its row, 1-based) and the key.
    """
    tables = {}
    for s in config["studies"]:
        df = read_table(s["table"], config)
        for i, row in enumerate(df.to_dict("records")):
            case_config(config, row, source=f"{s['table']}, case {i + 1} (study {s['name']})")
        tables[s["name"]] = df
    return tables


def _plain(value):
    """numpy scalars to Python scalars (YAML/JSON-friendly, schema-valid)."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and value.is_integer() and abs(value) < 2**53:
        return value  # keep floats floats: the schema types integers separately
    return value


def case_config(config: dict, overrides: dict, source: str = "study case") -> dict:
    """The workflow's config with one case's overrides merged in, validated.

    ``config`` is a config that passed :func:`~piezobearing.config.validate` (the workflow's); the sections the
    overrides change are checked against the schema, and the whole by the cross-field checks
    (``validate``'s ``base``).
    """
    out = copy.deepcopy(config)
    for col, value in overrides.items():
        keys = col.split(SEP)
        node = out
        for key in keys[:-1]:
            node = _child(node, key)
        last = int(keys[-1]) if isinstance(node, list) else keys[-1]
        old = node[last]
        value = _plain(value)
        if (
            isinstance(old, int)
            and not isinstance(old, bool)
            and isinstance(value, float)
            and value.is_integer()
        ):
            value = int(value)
        node[last] = value
    return validate(out, source=source, base=config)
