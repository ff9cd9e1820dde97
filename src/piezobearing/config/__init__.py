"""Load, merge and validate the workflow configuration outside Snakemake.

The workflow (``workflow/rules/common.smk``), the CLI and the tests all validate
through :func:`validate` against ``config/schema.yaml``.

The default config and its schema ship inside the package (``piezobearing/defaults/``), so an
installed ``piezobearing`` finds them anywhere. In a checkout those two files are symbolic links to
``config/config.yaml`` and ``config/schema.yaml``: one file each, which a wheel or ``pip install .``
copies into the package.
"""

from __future__ import annotations

import copy
import difflib
import functools
import math
from pathlib import Path

import yaml

#: The default config (config.yaml) and its schema (schema.yaml), the package's own data.
CONFIG_DIR = Path(__file__).parents[1] / "defaults"
SCHEMA_PATH = CONFIG_DIR / "schema.yaml"
DEFAULT_CONFIG = CONFIG_DIR / "config.yaml"


def find_checkout(start: str | Path | None = None) -> Path | None:
    """The piezobearing checkout containing ``start`` (default: the current folder), or None.

    A checkout is a folder with a ``Snakefile`` and ``config/config.yaml``
    and ``config/schema.yaml``; the nearest one upwards wins.
    """
    here = Path.cwd() if start is None else Path(start)
    for d in (here.resolve(), *here.resolve().parents):
        if (
            (d / "Snakefile").is_file()
            and (d / "config" / "config.yaml").is_file()
            and (d / "config" / "schema.yaml").is_file()
        ):
            return d
    return None


def default_config_dir() -> Path:
    """The config folder the CLI uses: the current checkout's when run inside one, else the installed one."""
    root = find_checkout()
    return root / "config" if root is not None else CONFIG_DIR


class ConfigError(ValueError):
    """A configuration that does not satisfy the schema."""


#: The run name of the paper's case: its results go to :data:`RESULTS_ROOT` itself.
PAPER_RUN = "paper"
#: The folder of every run's results (relative to the checkout).
RESULTS_ROOT = "results"
#: The folders the paper's case writes under :data:`RESULTS_ROOT` (a stage's area, the figures, logs, ...): no
#: other run may take one of these names, or its results would mix with the paper's (a test holds this list
#: against the workflow's rules).
RESULTS_FOLDERS = frozenset(
    {
        "bearing",
        "benchmarks",
        "calibration",
        "detect_archive",
        "diagnostics",
        "diagnostics_bearing",
        "figures",
        "logs",
        "notebooks",
        "scorecard",
        "sensor",
        "sensor_comparison",
        "signals",
        "studies",
    }
)


def results_folder(config: dict) -> str:
    """The results folder of ``config``'s run: ``results`` for the paper's case (``run: paper``, the default),
    ``results/<run>`` for any other run."""
    run = config.get("run", PAPER_RUN)
    return RESULTS_ROOT if run == PAPER_RUN else f"{RESULTS_ROOT}/{run}"


def deep_merge(base: dict, override: dict) -> dict:
    """Return ``base`` updated recursively with ``override`` (as Snakemake merges --configfile)."""
    out = copy.deepcopy(base)
    for key, val in override.items():
        if isinstance(val, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], val)
        else:
            out[key] = copy.deepcopy(val)
    return out


#: Config and schema files are read with libyaml's safe loader where PyYAML has it (8-12x faster than the
#: pure-Python one: 2.5 against 29 ms for config/config.yaml, 6 against 50 ms for the schema, at every workflow
#: start and dry run; the same dict, tests/test_config.py).
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


@functools.lru_cache(maxsize=4)
def _validator(schema_path: str):
    """The schema's validator, built once per schema file (studies validate one config per case)."""
    # jsonschema costs 0.07 s of CPU to import: it loads where a config is validated, and a command that
    # validates none (``piezobearing detect``, ``--help``) goes without it
    import jsonschema

    return jsonschema.Draft202012Validator(yaml.load(Path(schema_path).read_text(), Loader=_LOADER))


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


def _non_finite(obj, path=()) -> tuple[str, float] | None:
    """The dotted key and value of the first NaN or infinite number in ``obj``, else None."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return ".".join(path) or "(top level)", obj
    items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, list) else ()
    for k, v in items:
        found = _non_finite(v, (*path, f"[{k}]") if isinstance(k, int) else (*path, str(k)))
        if found:
            return found
    return None


#: [low, high] pairs that must increase.
_PAIRS = (
    ("synthesis", "peak_force_N"),
    ("synthesis", "rise_time_s"),
    ("synthesis", "fall_time_s"),
    ("signals", "band_Hz"),
    ("housing", "damping_band_Hz"),
)


def _bearing_defects(b: dict) -> list[tuple[str, float]]:
    """(key, width [m]) of every configured outer-race defect: the list ``bearing.defects`` where
    the config has one, else the single ``bearing.defect_width_m``."""
    if isinstance(b.get("defects"), list):
        return [
            (f"bearing.defects[{i}].width_m", d["width_m"])
            for i, d in enumerate(b["defects"])
            if "width_m" in d
        ]
    return [("bearing.defect_width_m", b["defect_width_m"])] if "defect_width_m" in b else []


def _defect_defaults(config: dict, schema: dict) -> None:
    """Fill each ``bearing.defects`` item's keys that the schema gives a ``default`` (``depth_m``: the paper's
    1 mm) where the config leaves them out, in place (Snakemake's ``validate`` fills them the same way)."""
    try:
        props = schema["properties"]["bearing"]["properties"]["defects"]["items"]["properties"]
    except KeyError:
        return
    for d in (config.get("bearing") or {}).get("defects") or []:
        for key, spec in props.items():
            if "default" in spec:
                d.setdefault(key, spec["default"])


def physical_problems(config: dict) -> list[str]:
    """Cross-field checks the schema cannot express: each problem as 'key ...: what; fix'."""
    out = []
    if config.get("run") in RESULTS_FOLDERS:
        out.append(
            f"key 'run': '{config['run']}' is a results folder of the paper's case ({RESULTS_ROOT}/{config['run']}/); "
            "a run of that name would mix its results with the paper's; choose another name (e.g. "
            f"'{config['run']}_variant')"
        )
    b = config.get("bearing", {})
    dr, dp, do = b.get("roller_diameter_m"), b.get("pitch_diameter_m"), b.get("outer_diameter_m")
    if dr is not None and dp is not None:
        if dp <= dr:
            out.append(
                f"key 'bearing.pitch_diameter_m': {dp:g} m is not larger than bearing.roller_diameter_m ({dr:g} m); "
                "the pitch circle runs through the roller centres, so it must exceed the roller diameter "
                "(the paper's bearing: 44.0e-3 with 10.0e-3)"
            )
        elif "n_rollers" in b and b["n_rollers"] * dr >= math.pi * dp:
            out.append(
                f"key 'bearing.n_rollers': {b['n_rollers']} rollers of {dr:g} m do not fit on a pitch circle of "
                f"{dp:g} m (need n D_r < pi D_p); fewer rollers or a larger bearing.pitch_diameter_m"
            )
        elif do is not None and do <= dp + dr:
            out.append(
                f"key 'bearing.outer_diameter_m': {do:g} m leaves no outer ring around rollers of {dr:g} m on a "
                f"{dp:g} m pitch circle (need D > D_p + D_r = {dp + dr:g} m)"
            )
        for key, w in _bearing_defects(b):
            if w >= dr:
                out.append(
                    f"key '{key}': a defect {w:g} m wide is not narrower than the roller ({dr:g} m); a roller would "
                    "drop into it completely, outside what the model describes; use a width below "
                    "bearing.roller_diameter_m"
                )
    for i, d in enumerate(b.get("defects") or []):
        if isinstance(d, dict) and "roller" in d and "n_rollers" in b and d["roller"] >= b["n_rollers"]:
            out.append(
                f"key 'bearing.defects[{i}].roller': roller {d['roller']} does not exist in a bearing of "
                f"{b['n_rollers']} rollers; use 0 to {b['n_rollers'] - 1}"
            )
    c = config.get("sensor_comparison", {})
    for sec, node in (("bearing", b), ("sensor_comparison.bearing_floor", c.get("bearing_floor", {}))):
        orders, amps = node.get("waviness_orders"), node.get("waviness_amplitudes_m")
        if isinstance(orders, list) and isinstance(amps, list) and len(orders) != len(amps):
            out.append(
                f"key '{sec}.waviness_amplitudes_m': {len(amps)} amplitudes for {len(orders)} waviness_orders; give "
                "one amplitude per order"
            )
    if "tail_false_alarm_rate" in c and "tail_fraction" in c and c["tail_false_alarm_rate"] >= c["tail_fraction"]:
        out.append(
            f"key 'sensor_comparison.tail_false_alarm_rate': {c['tail_false_alarm_rate']:g} is not below "
            f"sensor_comparison.tail_fraction ({c['tail_fraction']:g}); the tail fit extrapolates beyond the seeds "
            "it takes: use a rate below the fraction (0.01 with 0.2)"
        )
    f = config.get("sensor_fem", {})
    if "mesh_level" in f and "refinement_multipliers" in f:
        n = len(f["refinement_multipliers"])
        if not 1 <= f["mesh_level"] <= n:
            out.append(
                f"key 'sensor_fem.mesh_level': {f['mesh_level']} is not one of the {n} listed levels; use 1 to {n} "
                "(an index into sensor_fem.refinement_multipliers)"
            )
    for sec, key in _PAIRS:
        v = config.get(sec, {}).get(key)
        if isinstance(v, list) and len(v) == 2 and v[0] > v[1]:
            out.append(f"key '{sec}.{key}': [{v[0]:g}, {v[1]:g}] decreases; write [low, high]")
    return out


def validate(config: dict, source: str = "config", schema_path: str | Path = SCHEMA_PATH,
             base: dict | None = None) -> dict:
    """Validate against the schema and the cross-field checks; raise :class:`ConfigError` with one
    line naming the key and the fix.

    ``base``: a config that passed :func:`validate`, of which ``config`` is a copy with some values changed (a
    study case). Only the top-level sections that differ from ``base``'s are checked against the schema, with the
    same result and the same one-line error: the schema has no keyword across sections (no ``$ref``, no
    conditional at its top level), so each section is valid on its own, and a section equal to ``base``'s passes
    as it did there. The cross-field checks still see the whole config. A study's parse validates one config per
    case, and most of a whole-config check is the sections a case does not touch.
    """
    if not isinstance(config, dict):
        raise ConfigError(
            f"{source}: the top level is a {type(config).__name__}, not a mapping of keys; write 'key: value' "
            "lines as in config/config.yaml"
        )
    bad = _non_finite(config)
    if bad:
        written = ".nan" if math.isnan(bad[1]) else f"{'-' if bad[1] < 0 else ''}.inf"
        raise ConfigError(f"{source}: key '{bad[0]}': {written} is not a finite number; write a finite value")
    validator = _validator(str(schema_path))
    errors = sorted(_schema_errors(validator, config, base), key=lambda e: list(map(str, e.path)))
    if errors:
        raise ConfigError(f"{source}: {_message(errors[0])}")
    _defect_defaults(config, validator.schema)
    problems = physical_problems(config)
    if problems:
        raise ConfigError(f"{source}: {problems[0]}")
    return config


def _schema_errors(validator, config: dict, base: dict | None) -> list:
    """The schema's errors of ``config``: of the whole, or where ``base`` (a valid config with the same
    sections) is given, of the sections that differ from it (their paths from the top)."""
    sections = validator.schema.get("properties", {})
    if base is not None and set(config) == set(base):
        changed = [k for k in config if config[k] != base[k]]
        if all(k in sections for k in changed):
            errors = []
            for key in changed:
                for e in validator.evolve(schema=sections[key]).iter_errors(config[key]):
                    e.path.appendleft(key)
                    errors.append(e)
            return errors
    return list(validator.iter_errors(config))


def read_yaml(path: str | Path) -> dict:
    """A config file as a dict; one-line :class:`ConfigError` for a missing, unreadable or invalid file."""
    p = Path(path)
    if not p.exists():
        raise ConfigError(f"{p}: config file not found")
    if not p.is_file():
        raise ConfigError(f"{p}: is a folder, not a config file; give the path of a .yaml file")
    try:
        data = yaml.load(p.read_text(encoding="utf-8"), Loader=_LOADER)
    except OSError as e:
        raise ConfigError(f"{p}: cannot be read ({e.strerror}); give yourself read permission") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{p}: not UTF-8 text; save it as UTF-8") from None
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "somewhere"
        what = getattr(e, "problem", None) or type(e).__name__
        raise ConfigError(
            f"{p}: YAML syntax error at {where} ({what}); fix the brackets, quotes or indentation there"
        ) from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(
            f"{p}: the top level is a {type(data).__name__}, not a mapping of keys; write 'key: value' lines "
            "as in config/config.yaml"
        )
    return data


def load(*override_paths: str | Path, config_dir: str | Path | None = None) -> dict:
    """The default config (``config_dir``/config.yaml, default: the installed checkout's), merged with
    each override file in turn, validated against ``config_dir``/schema.yaml."""
    d = Path(config_dir) if config_dir is not None else CONFIG_DIR
    config = read_yaml(d / "config.yaml")
    for p in override_paths:
        config = deep_merge(config, read_yaml(p))
    return validate(
        config,
        source=", ".join(map(str, override_paths)) or str(d / "config.yaml"),
        schema_path=d / "schema.yaml",
    )
