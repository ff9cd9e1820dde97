"""What every rule's stage reads from the config, and the package code it runs: one registry for both.

:data:`READS` maps each rule to the config keys (dotted paths; a section name means the whole section) its stage
reads. The rules take their ``params`` from :func:`rule_params`, so the values Snakemake records (and compares
to decide a rerun) are exactly the values the stage receives: the stage gets :func:`declared_config`, a sub-config
of the declared keys only, in which reading any other key raises :class:`UndeclaredKeyError` naming the rule and
the fix. A rule missing here reads nothing from the config.

:func:`code_hash` is the hash of every module of this package a stage's script (or a figure's notebook) imports,
directly or through other modules (the import graph read with ``ast``, lazy imports inside functions included;
``from piezobearing import name`` follows a lazy package's table to the module that defines ``name``),
computed once per workflow start: a change to the physics reruns exactly the rules whose code it is.

:func:`record_checksum` tracks a user's calibration record by content (SHA-256), so a replaced record with an older
modification time (``cp -p``, unzip, ``rsync -a``) still reruns what reads it.
"""

from __future__ import annotations

import ast
import atexit
import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path

from ..config.paper import CASE

PACKAGE_DIR = Path(__file__).resolve().parents[1]

#: The sensor circuit of Eq. 6 (SensorCircuit.from_config) without R.
_CIRCUIT = [
    "sensor.material",
    "sensor.daq_resistance_ohm",
    "sensor.daq_capacitance_F",
    "sensor.pzt_diameter_m",
    "sensor.pzt_height_m",
    "sensor.d33_C_per_N",
    "sensor.eps33_T_rel",
    "sensor.pzt_density_kg_per_m3",
    "sensor.c66_rule",
    "sensor.cable_length_m",
    "sensor.cable_capacitance_F_per_m",
]
#: The PZT disk as a material and a spring (materials.pzt_from_config and the disk's size); no cable.
_PZT = [
    "sensor.material",
    "sensor.pzt_diameter_m",
    "sensor.pzt_height_m",
    "sensor.d33_C_per_N",
    "sensor.eps33_T_rel",
    "sensor.pzt_density_kg_per_m3",
    "sensor.c66_rule",
]
#: The alumina disk on the outer ring (materials.alumina_from_config and its size).
_ALUMINA_DISK = [
    "sensor_fem.bottom_disk_diameter_m",
    "sensor_fem.bottom_disk_height_m",
    "sensor_fem.alumina_young_Pa",
    "sensor_fem.alumina_poisson",
    "sensor_fem.alumina_density_kg_per_m3",
    "sensor_fem.adhesive_height_m",
    "sensor_fem.adhesive_young_Pa",
    "sensor_fem.adhesive_poisson",
    "sensor_fem.adhesive_density_kg_per_m3",
]
#: The sensor stack's geometry and mesh density (sensor.analysis.mesh_inputs).
_STACK_MESH = [
    "sensor.pzt_diameter_m",
    "sensor.pzt_height_m",
    "sensor_fem.bottom_disk_diameter_m",
    "sensor_fem.bottom_disk_height_m",
    "sensor_fem.top_disk_diameter_m",
    "sensor_fem.adhesive_height_m",
    "sensor_fem.top_disk_height_m",
    "sensor_fem.mesh_n_core",
    "sensor_fem.mesh_n_rings",
    "sensor_fem.mesh_n_layers",
    "sensor_fem.mesh_grading_ratio",
    "sensor_fem.refinement_multipliers",
    "sensor_fem.mesh_level",
]
#: The bearing's and housing's geometry (HousingGeometry.from_config). The healthy mesh reads the defect too:
#: both meshes share one node layout, graded towards the defect, so that they differ by the groove alone.
_HOUSING_GEOMETRY = [
    "bearing.pitch_diameter_m",
    "bearing.roller_diameter_m",
    "bearing.roller_length_m",
    "bearing.outer_diameter_m",
    "bearing.width_m",
    "bearing.defects",
    "housing.centre_height_m",
    "housing.body_half_width_m",
    "housing.body_top_m",
    "housing.body_bottom_m",
    "housing.foot_length_m",
    "housing.axial_width_m",
    "housing.hole_diameter_m",
    "sensor_fem.bottom_disk_diameter_m",
]

#: The bearing's geometry (BearingGeometry.from_config).
_GEOMETRY = [
    "bearing.n_rollers",
    "bearing.roller_diameter_m",
    "bearing.pitch_diameter_m",
    "bearing.roller_length_m",
    "bearing.radial_clearance_m",
    "bearing.outer_diameter_m",
    "bearing.width_m",
    "bearing.contact_angle_deg",
]
#: The bearing model (geometry, operation, LPM and its record), without the running-bearing record's keys
#: (bearing.measurement, channels, wav_full_scale_V: the diagnosis reads those).
_BEARING = [
    *_GEOMETRY,
    "bearing.shaft_speed_rpm",
    "bearing.radial_load_N",
    "bearing.shaft_mass_kg",
    "bearing.pedestal_mass_kg",
    "bearing.pedestal_stiffness_N_per_m",
    "bearing.bearing_damping_N_s_per_m",
    "bearing.pedestal_damping_N_s_per_m",
    "bearing.defects",
    "bearing.cage_slip",
    "bearing.slip_jitter",
    "bearing.speed_ramp_rpm_per_s",
    "bearing.tachometer_pulses_per_rev",
    "bearing.roller_diameter_scatter_m",
    "bearing.roughness_rms_m",
    "bearing.roughness_correlation_length_m",
    "bearing.waviness_orders",
    "bearing.waviness_amplitudes_m",
    "bearing.unbalance_kg_m",
    "bearing.start_angle_deg",
    "bearing.time_step_s",
    "bearing.duration_s",
    "bearing.settle_s",
    "bearing.substeps",
    "bearing.resample",
]
#: The sensor force's period (chain.signals.sensor_force_period_s: the bearing's geometry, speed, mean slip and
#: whether the rollers differ), for which the sensor circuit starts in its periodic steady state.
_PASSAGE = [
    *_GEOMETRY,
    "bearing.shaft_speed_rpm",
    "bearing.cage_slip",
    "bearing.roller_diameter_scatter_m",
]

#: The config keys of the paper's case (piezobearing.config.paper.CASE), against which the scorecard compares the run's.
_CASE = list(CASE)

#: Config keys each rule's stage reads, by rule.
READS: dict[str, list[str]] = {
    # calibration.smk
    "synthesize_calibration": ["seed", "synthesis", *_CIRCUIT],
    "extract_sensitivity": ["calibration", *_CIRCUIT],
    "fit_resistance": ["sensor", "calibration", "synthesis.resistance_ohm", "diagnostics.quiet_settle_s"],
    "lowfreq_sensitivity": ["sensor", "lowfreq"],
    "scorecard_calibration": ["calibration.measurement", "synthesis.resistance_ohm", *_CIRCUIT],
    # sensor_fem.smk
    "sensor_mesh": _STACK_MESH,
    "sensor_convergence": ["sensor", "sensor_fem"],
    "sensor_modal": ["sensor", "sensor_fem"],
    "sensor_harmonic": ["sensor", "sensor_fem"],
    # bearing.smk
    "bearing_lpm": ["seed", *_BEARING],
    "housing_mesh": [*_HOUSING_GEOMETRY, "housing.mesh_level"],
    "housing_transient": [
        "seed", "bearing.time_step_s", "housing", *_PZT, *_ALUMINA_DISK,
    ],
    "housing_convergence": [
        *_BEARING, *_HOUSING_GEOMETRY, "housing", *_PZT, *_ALUMINA_DISK,
    ],
    "bearing_sampling": ["seed", *_BEARING],
    "scorecard_bearing": _BEARING,
    # signals.smk
    "sensor_voltage": ["signals.skip_s", "signals.sensor_fem_correction", *_CIRCUIT, *_PASSAGE],
    "noisy": ["seed", "signals"],  # the DAQ model: sampling, noise (relative at snr_dB, or absolute), ADC
    "envelope": ["signals"],
    "fault_indicator": ["seed", "signals"],
    "snr_study": ["seed", "signals"],
    "fault_classification": ["seed", "signals", "bearing.defects"],
    "fault_type_voltage": [
        "seed", *_BEARING, *_HOUSING_GEOMETRY, "housing", *_PZT, *_ALUMINA_DISK,
        "signals.skip_s", "signals.sensor_fem_correction", *_CIRCUIT,
    ],
    # sensor_comparison.smk
    "sensor_comparison_housing": [  # the housing's reduced model (piezobearing.comparison.rig.build_housing)
        "seed", *_HOUSING_GEOMETRY, "housing.mesh_level", "housing.n_modes", "housing.damping_ratio",
        "housing.damping_band_Hz", "housing.patch_width_m", "housing.sensor_electrical", *_PZT, *_ALUMINA_DISK,
        "sensor_comparison.mode_cutoff_ratio", "accelerometer.daq.sample_rate_Hz",
    ],
    "sensor_comparison": [
        "seed", *_BEARING, *_HOUSING_GEOMETRY, "housing", *_PZT, *_ALUMINA_DISK, *_CIRCUIT, "signals",
        "base_motion", "accelerometer", "sensor_comparison",
    ],
    # studies.smk: the sensor comparison's calibrated figures (from its cases' files alone)
    "sensor_comparison_calibrated_figures": [],
    # diagnostics.smk
    "diagnose": ["seed", "sensor", "synthesis", "calibration", "model", "diagnostics"],
    # diagnostics_bearing.smk
    "synthesize_bearing_record": ["seed", "sensor", "signals.sensor_fem_correction", "bearing", "bearing_diagnosis"],
    "diagnose_bearing": ["seed", "sensor", "signals.sensor_fem_correction", "bearing", "bearing_diagnosis", "diagnostics"],
    # scorecard.smk: the run's conditions against the paper's case (piezobearing.config.paper.CASE)
    "scorecard": _CASE,
    # detect_archive.smk: piezobearing detect over an archive of recordings (outside rule all)
    "detect_record": ["detect_archive"],
    "detect_archive": ["detect_archive"],
    # running_bearing_guide.smk: the running-bearing guide's example, without then with the dynamic rung (outside
    # rule all)
    "running_bearing_guide": [
        "seed", "sensor", "sensor_fem", "signals", "bearing", "housing", "bearing_diagnosis", "diagnostics",
    ],
}


class UndeclaredKeyError(KeyError):
    """A stage read a config key its rule does not declare (a programming error, named with its fix)."""

    def __str__(self) -> str:
        return str(self.args[0])


class DeclaredConfig(dict):
    """A (nested) sub-config: reading a key that is not there raises :class:`UndeclaredKeyError`."""

    def __init__(self, data: dict, rule: str, prefix: str = ""):
        super().__init__(
            (k, DeclaredConfig(v, rule, f"{prefix}{k}.") if isinstance(v, dict) else v) for k, v in data.items()
        )
        self._rule, self._prefix = rule, prefix

    def get(self, key, default=None):
        """As dict.get for a declared key; an undeclared key raises (a default would hide the missing declaration)."""
        return self[key]

    def __missing__(self, key):
        raise UndeclaredKeyError(
            f"the stage of rule {self._rule} read config key {self._prefix}{key}, which the rule does not "
            f"declare; add it to piezobearing.workflow.registry.READS['{self._rule}']"
        )


def _get(config: dict, path: str):
    node = config
    for k in path.split("."):
        node = node[k]
    return node


def declared(config: dict, rule: str) -> dict:
    """The declared keys of ``rule`` with their values from ``config``, as a nested plain dict (JSON-ready)."""
    out: dict = {}
    for path in READS.get(rule, []):
        keys = path.split(".")
        node = out
        for k in keys[:-1]:
            node = node.setdefault(k, {})
        node[keys[-1]] = json.loads(json.dumps(_get(config, path)))
    return out


def reads_digest(config: dict, rule: str) -> str:
    """The first 12 hex digits of the SHA-256 of ``rule``'s declared config values (:func:`declared`, as sorted
    JSON): a name for an output that depends on those values alone, one file per distinct set."""
    text = json.dumps(declared(config, rule), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def declared_config(reads: dict, rule: str) -> DeclaredConfig:
    """What the stage of ``rule`` receives: its rule's ``params.reads``, strict on undeclared keys."""
    return DeclaredConfig(reads, rule)


# --------------------------------------------------------------------------- code


@lru_cache(maxsize=None)
def _module_file(name: str) -> Path | None:
    """The file of module ``piezobearing.x.y`` in this package (None outside the package or not found); looked up
    once per process (every module file names its imports again: 2200 lookups, two ``stat`` calls each, a start)."""
    parts = name.split(".")
    if parts[0] != "piezobearing":
        return None
    base = PACKAGE_DIR.joinpath(*parts[1:])
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.is_file():
            return p
    package = _module_file(".".join(parts[:-1])) if len(parts) > 1 else None
    if package is not None and package.name == "__init__.py" and parts[-1] in _lazy_exports(package):
        return _module_file(_lazy_exports(package)[parts[-1]])  # `from piezobearing import detect`: its module
    return None


@lru_cache(maxsize=None)
def _lazy_exports(init: Path) -> dict[str, str]:
    """A lazy package's table of names and their modules (``_EXPORTS`` in its ``__init__.py``: the package's face,
    ``piezobearing.io``), read from its source: an entry that imports a name from such a package runs that name's
    module, and its code is hashed with it; the table's other modules are not followed."""
    for node in ast.parse(init.read_text()).body:
        target = node.target if isinstance(node, ast.AnnAssign) else (node.targets[0] if isinstance(node, ast.Assign) else None)
        if isinstance(target, ast.Name) and target.id == "_EXPORTS":
            return ast.literal_eval(node.value)
    return {}


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE_DIR.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


#: The fields of a statement that hold statements (an import is a statement: it is never inside an expression).
_BODIES = ("body", "orelse", "finalbody", "handlers", "cases")


def _statements(tree: ast.AST):
    """Every statement of ``tree`` at any depth (function, class, if, try, with, loop and match bodies), without
    visiting expressions: the same imports as ``ast.walk`` finds, at a tenth of the nodes visited."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        for field in _BODIES:
            todo.extend(getattr(node, field, ()))


def _imports(source: str, module: str | None, is_package: bool) -> set[str]:
    """Absolute names of the modules ``source`` imports (relative imports resolved against ``module``)."""
    out = set()
    for node in _statements(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if module is None:
                    continue
                pkg = module.split(".") if is_package else module.split(".")[:-1]
                pkg = pkg[: len(pkg) - (node.level - 1)]
                base = ".".join(pkg + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            out.add(base)
            out.update(f"{base}.{a.name}" for a in node.names)  # `from pkg import module`
    # a module's import also runs its parent packages' __init__
    for name in list(out):
        parts = name.split(".")
        out.update(".".join(parts[:i]) for i in range(1, len(parts)))
    return out


def _source_text(path: Path) -> str:
    """Python source of a script, or the code cells of a notebook."""
    text = path.read_text()
    if path.suffix == ".ipynb":
        cells = json.loads(text)["cells"]
        return "\n".join(
            "".join(c["source"]) if isinstance(c["source"], list) else c["source"]
            for c in cells
            if c["cell_type"] == "code"
        )
    return text


def user_cache_dir() -> Path:
    """Where a workflow start leaves what the next start (of any checkout of this user) can reuse, every entry
    keyed by content: ``$PIEZOBEARING_CACHE_DIR``, else ``$XDG_CACHE_HOME/piezobearing``, else
    ``~/.cache/piezobearing``. Deleting it costs the next start a second or two, nothing else."""
    if os.environ.get("PIEZOBEARING_CACHE_DIR"):
        return Path(os.environ["PIEZOBEARING_CACHE_DIR"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "piezobearing"


#: Each module's imports by the SHA-256 of its bytes and its name, across workflow starts (:func:`use_imports_cache`).
_IMPORTS_CACHE: dict[str, list[str]] = {}
_IMPORTS_USED: dict[str, list[str]] = {}
_IMPORTS_CACHE_FILE: Path | None = None
#: Entries the cache file holds at most (about 150 bytes each).
_IMPORTS_CACHE_MAX = 20000


def use_imports_cache(path: str | Path) -> None:
    """Remember every module's imports in ``path`` (JSON) from one start to the next: parsing the package's 220
    modules is half of the code hash's and a third of a warm dry run's time, and between starts few of them change.
    Keyed by each module's bytes (SHA-256) and name, so an edited module is parsed again; written at exit with
    the entries this start used and those another start wrote meanwhile. The workflow calls it at its parse
    (``imports.json`` in :func:`user_cache_dir`)."""
    global _IMPORTS_CACHE_FILE
    try:
        _IMPORTS_CACHE.update(json.loads(Path(path).read_text()))
    except (OSError, ValueError):
        pass  # none yet, or unreadable: parse every module this time
    if _IMPORTS_CACHE_FILE is None:
        atexit.register(_save_imports_cache)
    _IMPORTS_CACHE_FILE = Path(path)


def _save_imports_cache() -> None:
    path = _IMPORTS_CACHE_FILE
    if not _IMPORTS_USED or _IMPORTS_USED.keys() <= _IMPORTS_CACHE.keys():
        return
    try:
        latest = json.loads(path.read_text())  # what other starts wrote since this one read it
    except (OSError, ValueError):
        latest = {}
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.{os.getpid()}")
        merged = {**latest, **_IMPORTS_USED}
        if len(merged) > _IMPORTS_CACHE_MAX:  # edits of many starts: keep this start's
            merged = dict(_IMPORTS_USED)
        tmp.write_text(json.dumps(merged, sort_keys=True))
        os.replace(tmp, path)  # whole, even with another start writing beside it
    except OSError:
        pass  # a read-only folder only costs the next start the parse


@lru_cache(maxsize=None)
def _module_imports(f: Path) -> tuple[Path, ...]:
    """The package files module file ``f`` imports directly, parsed once per process (every rule's entry
    reaches the same modules: parsing them once per entry was most of a dry run's time), or read from the
    imports cache (:func:`use_imports_cache`)."""
    data = f.read_bytes()
    name = _module_name(f)
    key = f"{hashlib.sha256(data).hexdigest()} {name}"
    names = _IMPORTS_CACHE.get(key) if _IMPORTS_CACHE_FILE is not None else None
    if names is None:
        names = sorted(_imports(data.decode(), name, f.name == "__init__.py"))
    if _IMPORTS_CACHE_FILE is not None:
        _IMPORTS_USED[key] = names
    return tuple(p for p in map(_module_file, names) if p is not None)


@lru_cache(maxsize=None)
def package_modules(entry: str) -> tuple[Path, ...]:
    """Every file of this package that ``entry`` (a script or notebook path) imports, transitively, sorted."""
    return _closure([f for f in map(_module_file, sorted(_imports(_source_text(Path(entry)), None, False)))
                     if f is not None])


def _closure(todo: list[Path]) -> tuple[Path, ...]:
    """The module files ``todo`` and every package file they import, transitively, sorted."""
    seen: set[Path] = set()
    while todo:
        f = todo.pop()
        if f not in seen:
            seen.add(f)
            todo.extend(_module_imports(f))
    return tuple(sorted(seen))


#: This module's file: the registry acts on a rule through its params (``reads``), not as code the stage runs.
_REGISTRY_FILE = Path(__file__).resolve()


@lru_cache(maxsize=None)
def _hashed_part(f: Path) -> bytes:
    """What :func:`code_hash` hashes of module file ``f``: its path in the package and its bytes, read once per
    process (the 42 rule entries of a workflow start reach the same modules: reading and resolving each file once
    per entry, 1300 times, was a fifth of a warm dry run's time)."""
    return str(f.relative_to(PACKAGE_DIR)).encode() + b"\0" + f.read_bytes() + b"\0"


@lru_cache(maxsize=None)
def code_hash(entry: str) -> str:
    """SHA-256 over the package modules ``entry`` imports (their paths in the package and their bytes)."""
    h = hashlib.sha256()
    for f in package_modules(entry):
        if f != _REGISTRY_FILE:
            h.update(_hashed_part(f))
    return h.hexdigest()


@lru_cache(maxsize=None)
def module_code_hash(name: str) -> str:
    """SHA-256 over package module ``name`` (``piezobearing.x.y``) and the package modules it imports, as
    :func:`code_hash` of an entry."""
    f = _module_file(name)
    if f is None:
        raise ValueError(f"{name} is not a module of this package")
    h = hashlib.sha256()
    for g in _closure([f]):
        if g != _REGISTRY_FILE:
            h.update(_hashed_part(g))
    return h.hexdigest()


@lru_cache(maxsize=None)
def record_checksum(path: str | None) -> str | None:
    """SHA-256 of a user's record (None for the synthetic one, a workflow output tracked by Snakemake itself)."""
    if not path:
        return None
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


class ShortParam(dict):
    """A rule param holding config values (a dict, as the stage receives it) that Snakemake records and prints by
    its top-level keys and a digest of every value, not as the whole dictionary.

    Snakemake decides a rerun by comparing ``repr`` of each param with the one it recorded
    (``snakemake.persistence``: a builtin type's repr; a dict subclass is one), and prints that repr in a rerun's
    reason. The repr here is ``{key, key, ...} sha256:<16 hex>``, the digest over the values' canonical JSON: a
    change of any value changes it (a rerun, as with the whole dictionary), an unchanged config keeps it (none)."""

    @property
    def digest(self) -> str:
        """The first 16 hex digits of SHA-256 over the values as canonical JSON (sorted keys)."""
        text = json.dumps(self, sort_keys=True, separators=(",", ":"), default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def __repr__(self) -> str:
        return "{" + ", ".join(map(str, self)) + "} sha256:" + self.digest

    __str__ = __repr__


def short_param(values: dict) -> ShortParam:
    """``values`` as a :class:`ShortParam` (a rule param Snakemake prints by its keys and digest)."""
    return ShortParam(values)


def rule_params(rule: str, config: dict, entry: str, record: str | None = None) -> dict:
    """The ``params`` of ``rule``: ``reads`` (its declared config values, a :class:`ShortParam`), ``code`` (the
    hash of the package code its ``entry`` script or notebook runs) and, for a rule reading a user's record,
    ``record`` (its checksum)."""
    out = {"reads": ShortParam(declared(config, rule)), "code": code_hash(entry)}
    if record is not None or rule in RECORD_RULES:
        out["record"] = record_checksum(record)
    return out


#: Rules that read the calibration record (a user's file when calibration.measurement is set).
RECORD_RULES = frozenset({"extract_sensitivity", "fit_resistance", "diagnose", "fig05"})
