"""Load, merge and validate the workflow configuration outside Snakemake.

Snakemake validates with the same schema (``config/schema.yaml``) through
``snakemake.utils.validate``; the CLI and the tests come through here.
"""

from __future__ import annotations

import copy
import difflib
import functools
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


@functools.lru_cache(maxsize=4)
def _validator(schema_path: str):
    """The schema's validator, built once per schema file (studies validate one config per case)."""
    import jsonschema

    return jsonschema.Draft202012Validator(yaml.safe_load(Path(schema_path).read_text()))


def _message(e) -> str:
    """One line for a jsonschema error: the key by its dotted path, what is wrong, the fix."""
    path = [str(p) for p in e.path]
    see = "see config/schema.yaml for the allowed values"
    if e.validator == "additionalProperties" and isinstance(e.instance, dict):
        allowed = list(e.schema.get("properties", {}))
        unknown = sorted(k for k in e.instance if k not in allowed)
        if unknown:
            close = difflib.get_close_matches(str(unknown[0]), allowed, n=1)
            hint = f"did you mean '{'.'.join([*path, close[0]])}'? " if close else ""
            return f"key '{'.'.join([*path, str(unknown[0])])}' is not a config key; {hint}{see}"
    key = ".".join(path) or "(top level)"
    if e.validator == "type" and isinstance(e.instance, str):
        try:
            float(e.instance)
        except ValueError:
            pass
        else:
            return (
                f"key '{key}': {e.message}; write numbers with a dot or a signed exponent "
                f"(50.0e+6, not 50e6: YAML reads 50e6 as a string)"
            )
    return f"key '{key}': {e.message}; {see}"


def validate(config: dict, source: str = "config", schema_path: str | Path = SCHEMA_PATH) -> dict:
    """Validate against the schema; raise :class:`ConfigError` with one line naming the key and the fix."""
    errors = sorted(_validator(str(schema_path)).iter_errors(config), key=lambda e: list(map(str, e.path)))
    if errors:
        raise ConfigError(f"{source}: {_message(errors[0])}")
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
