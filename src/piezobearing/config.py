"""Load, merge and validate the workflow configuration outside Snakemake.

Snakemake validates with the same schema (``config/schema.yaml``) through
``snakemake.utils.validate``; the CLI and the tests come through here.
"""

from __future__ import annotations

import copy
from pathlib import Path

import yaml

#: The repository's config folder (the package is installed editable from it).
CONFIG_DIR = Path(__file__).resolve().parents[2] / "config"
SCHEMA_PATH = CONFIG_DIR / "schema.yaml"
DEFAULT_CONFIG = CONFIG_DIR / "config.yaml"


class ConfigError(ValueError):
    """A configuration that does not satisfy the schema."""


def deep_merge(base: dict, override: dict) -> dict:
    """Return ``base`` updated recursively with ``override`` (as Snakemake merges --configfile)."""
    out = copy.deepcopy(base)
    for key, val in override.items():
        if isinstance(val, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], val)
        else:
            out[key] = copy.deepcopy(val)
    return out


def validate(config: dict, source: str = "config") -> dict:
    """Validate against the schema; raise :class:`ConfigError` naming the key."""
    import jsonschema

    schema = yaml.safe_load(SCHEMA_PATH.read_text())
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(config), key=lambda e: list(e.path))
    if errors:
        e = errors[0]
        key = ".".join(str(p) for p in e.path) or "(top level)"
        raise ConfigError(
            f"{source}: key '{key}': {e.message}; see config/schema.yaml for the allowed values"
        )
    return config


def load(*override_paths: str | Path) -> dict:
    """The default config, merged with each override file in turn, validated."""
    config = yaml.safe_load(DEFAULT_CONFIG.read_text())
    for p in override_paths:
        p = Path(p)
        if not p.exists():
            raise ConfigError(f"{p}: config file not found")
        config = deep_merge(config, yaml.safe_load(p.read_text()) or {})
    return validate(config, source=", ".join(map(str, override_paths)) or str(DEFAULT_CONFIG))
