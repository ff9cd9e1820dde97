"""Nothing stale: every rule reruns when a config key its stage reads changes, when the package code it runs
changes, and when the user's record changes content (even with an older modification time); no other rule does.

A scratch copy of the workflow is built once with stand-in scripts that only create their outputs (keeping the
real scripts' imports, unexecuted, for the code hash) and a stand-in papermill; then ``snakemake -n`` is asked,
for each rule, after a change to the config keys its stage reads (piezobearing.workflow.registry.READS), after an edit of
a package module in the scratch copy, and after the record is replaced. The rules it lists must be exactly the
changed rules and the rules downstream of them in the rule graph (``snakemake --rulegraph``). Every Snakemake call
(the build, the rule graph, the dry runs, the record case's run) is the environment's ``snakemake`` in a process of
its own, with the scratch copy's package first on PYTHONPATH; the dry runs go two at a time.
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml
from conftest import shared_run, snakemake

import piezobearing.config
from piezobearing.workflow.registry import READS, RECORD_RULES

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
#: The scratch copy's rule graph (each rule's children), written by its build.
RULE_GRAPH = "rulegraph.json"

STUB = """from pathlib import Path

for p in [*snakemake.output, *snakemake.log]:
    Path(p).parent.mkdir(parents=True, exist_ok=True)
    Path(p).write_text("stand-in")
if False:  # the real script's imports: read (never run) for the rule's code hash
{imports}
"""

PAPERMILL = """#!{python}
import sys
from pathlib import Path

a = sys.argv[1:]
for p in [a[1]] + [a[i + 2] for i, x in enumerate(a[:-2]) if x in ("-p", "-r") and a[i + 1] == "figure"]:
    Path(p).parent.mkdir(parents=True, exist_ok=True)
    Path(p).write_text("stand-in")
"""

#: Keys left out of the perturbation: a path (the record has its own test) and a list of effect names.
SKIP = {"calibration.measurement", "synthesis.hidden_effects"}
#: String choices: another valid value.
OTHER = {"type": "inner_race", "band_rule": "kurtogram", "method": "direct", "sensor_electrical": "short", "resample": "sample",
         "c66_rule": "paper", "material": "pzt5h", "model": "absolute", "window": "rectangular",
         "classification_types": "rolling_element", "statistic": "envelope", "position": "side",
         "dynamic_rung": "off", "joint_search": "auto", "shaft_mass_scan": "off",
         "interval_correlation": "off"}


def _stub(script: Path) -> str:
    imports = [
        "    " + ast.unparse(n)
        for n in ast.walk(ast.parse(script.read_text()))
        if isinstance(n, (ast.Import, ast.ImportFrom))
        and (n.module if isinstance(n, ast.ImportFrom) else n.names[0].name or "").startswith("piezobearing")
    ]
    return STUB.format(imports="\n".join(imports) or "    pass")


def _jobs(out: str) -> set[str]:
    """Rules of the 'Job stats' table of a dry run (without the target rule all)."""
    if "Job stats:" not in out:
        return set()
    table = out.split("Job stats:")[1].split("total")[0]
    return {m.group(1) for m in re.finditer(r"^(\w+)\s+\d+\s*$", table, re.M)} - {"all", "job"}


def build_scratch(d: Path) -> None:
    """Build a scratch copy of the workflow in ``d`` (stand-in stages) and write its rule graph to
    ``d / RULE_GRAPH`` (each rule's children).

    The build is a real ``snakemake --cores 2`` run: every job of the CI targets, their metadata recorded."""
    for name in ("Snakefile", "workflow", "config", "notebooks", "src"):
        src = ROOT / name
        (shutil.copytree if src.is_dir() else shutil.copy)(src, d / name)
    (d / "data").mkdir()
    for s in (d / "workflow/scripts").glob("*.py"):
        s.write_text(_stub(s))
    (d / "bin").mkdir()
    pm = d / "bin/papermill"
    pm.write_text(PAPERMILL.format(python=sys.executable))
    pm.chmod(0o755)
    env = scratch_env(d)
    out = snakemake("--cores", "2", "--configfile", "config/ci.yaml", cwd=d, env=env)
    assert out.returncode == 0, out.stderr[-3000:]
    graph = snakemake("--rulegraph", "--configfile", "config/ci.yaml", cwd=d, env=env)
    assert graph.returncode == 0, graph.stderr[-3000:]
    names = dict(re.findall(r'^\s*(\d+)\[label = "(\w+)"', graph.stdout, re.M))
    children: dict[str, list[str]] = {n: [] for n in names.values()}
    for a, b in re.findall(r"^\s*(\d+) -> (\d+)", graph.stdout, re.M):
        children[names[a]].append(names[b])
    (d / RULE_GRAPH).write_text(json.dumps(children))


def scratch_env(d: Path) -> dict:
    """The environment of the scratch copy ``d``: its package from the copy's ``src``, the stand-in papermill
    first on PATH."""
    return {**os.environ, "PATH": f"{d / 'bin'}:{os.environ['PATH']}", "PYTHONPATH": str(d / "src")}


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    """A built scratch copy of the workflow (stand-in stages), its environment and its rule graph.

    It is built once per pytest run (``conftest.shared_run``) and copied, modification times and Snakemake's
    metadata with it, into a folder of this module's own: the tests edit their copy."""
    built = shared_run(tmp_path_factory, "rerun_scratch", build_scratch)
    d = tmp_path_factory.mktemp("rerun")
    shutil.copytree(built, d, symlinks=True, dirs_exist_ok=True)
    children = {rule: set(c) for rule, c in json.loads((d / RULE_GRAPH).read_text()).items()}
    return d, scratch_env(d), children


@pytest.fixture(scope="module")
def dry(scratch):
    """``dry(args)``: ``snakemake ARGS`` in the scratch copy, in its environment (threads may call it at once)."""
    d, env = scratch[0], scratch[1]
    return lambda args: snakemake(*args, cwd=d, env=env)


def _downstream(rules: set[str], children: dict[str, set[str]]) -> set[str]:
    out, todo = set(rules), list(rules)
    while todo:
        for c in children.get(todo.pop(), ()):
            if c not in out:
                out.add(c)
                todo.append(c)
    return out - {"all"}


def _value(config: dict, path: str):
    for k in path.split("."):
        config = config[k]
    return config


def _leaves(config: dict, path: str) -> list[str]:
    node = config
    for k in path.split("."):
        node = node[k]
    if isinstance(node, dict):
        return [leaf for k in node for leaf in _leaves(config, f"{path}.{k}")]
    return [path]


def _changed(value, key: str, up: bool = False):
    """Another value of a config key: numbers 1% down (or up), integers by one, flags flipped, choices swapped."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return value + 1 if up or value <= 1 else value - 1
    if isinstance(value, float):
        return value * (1.01 if up else 0.99) if value else (1e-6 if up else 1e-3)
    if isinstance(value, list):
        return [_changed(v, key, up) for v in value]
    if isinstance(value, dict):  # an entry of a list of tables (bearing.defects)
        # an effect's name stays (its params are its own); every other entry changes
        return {k: v if k == "name" else _changed(v, f"{key}.{k}", up) for k, v in value.items()}
    if isinstance(value, str):
        return OTHER[key.rsplit(".", 1)[-1]]
    raise AssertionError(f"no change rule for {key} = {value!r}")


def _override(config: dict, keys: list[str], directions: dict[str, bool] | None = None) -> dict:
    """The changed values of ``keys`` as a config override; each change is one the schema accepts.

    Each key is changed the way (down, else up) in which it is valid alone in ``config`` (``directions``: those
    found so far, shared by the calls of one test, since the rules share most of their keys: 152 keys instead of
    758 validations), then the whole override is validated once. Should the changes conflict (each valid alone,
    not together), the keys are taken one at a time, each checked with the changes before it. On the CI config
    both ways give the same override for every rule."""
    directions = {} if directions is None else directions
    for path in keys:
        if path not in directions:
            directions[path] = _direction(config, path)
    out: dict = {}
    for path in keys:
        _set(out, path, _changed(_value(config, path), path, directions[path]))
    try:
        piezobearing.config.validate(piezobearing.config.deep_merge(config, out))
        return out
    except piezobearing.config.ConfigError:
        return _override_one_by_one(config, keys)


def _set(tree: dict, path: str, value) -> None:
    *parents, last = path.split(".")
    for k in parents:
        tree = tree.setdefault(k, {})
    tree[last] = value


def _direction(config: dict, path: str) -> bool:
    """Whether ``path`` must go up (else down) for ``config`` with that one change to be valid."""
    for up in (False, True):
        change: dict = {}
        _set(change, path, _changed(_value(config, path), path, up))
        try:
            piezobearing.config.validate(piezobearing.config.deep_merge(config, change))
            return up
        except piezobearing.config.ConfigError:
            continue
    raise AssertionError(f"no valid change of {path}")


def _override_one_by_one(config: dict, keys: list[str]) -> dict:
    """:func:`_override` key by key, each change validated with those before it."""
    out: dict = {}
    for path in keys:
        for up in (False, True):
            _set(out, path, _changed(_value(config, path), path, up))
            try:
                piezobearing.config.validate(piezobearing.config.deep_merge(config, out))
                break
            except piezobearing.config.ConfigError:
                continue
        else:
            raise AssertionError(f"no valid change of {path}")
    return out


def _readers(key: str) -> set[str]:
    """Rules whose declared reads cover the leaf key ``key``."""
    return {r for r, paths in READS.items() if any(key == p or key.startswith(p + ".") for p in paths)}


def test_every_rule_reruns_on_the_keys_its_stage_reads_and_no_other_rule_does(scratch, dry):
    """For each rule, every config key its stage reads changed at once: ``snakemake -n`` lists exactly the rules
    that read any of those keys and the rules downstream of them. Rules whose stages read the same keys give the
    same changed config, so one dry run answers for all of them (on the CI config 20 dry runs for 25 rules:
    ``bearing_lpm`` and ``bearing_sampling``, ``noisy``, ``fault_indicator`` and ``snr_study``, and the three
    sensor FEM rules share theirs); each rule's assertions are checked on its config's dry run."""
    d, env, children = scratch
    config = piezobearing.config.load(d / "config/ci.yaml")
    # the rules of the CI targets (the archive's rules, outside rule all, have a test of their own; the
    # running-bearing guide's rule, outside rule all too, is not in this DAG)
    keys = {rule: rule_keys(config, rule) for rule in sorted(READS) if rule in children}
    first = {}  # each distinct key set: the first rule that reads it (names its override file)
    for rule, k in keys.items():
        first.setdefault(k, rule)
    directions: dict[str, bool] = {}
    overrides = {k: _override(config, list(k), directions) for k in first}
    with ThreadPoolExecutor(2) as pool:
        listed = dict(zip(first, pool.map(lambda k: dry_listed(d, dry, first[k], overrides[k]), first), strict=True))
    for rule, k in keys.items():
        expected = _downstream({r for key in k for r in _readers(key) if r in children}, children)
        assert rule in listed[k], f"{rule} does not rerun after a change of {list(k)}"
        assert listed[k] == expected, (
            f"after a change of {rule}'s keys: extra {listed[k] - expected}, missing {expected - listed[k]}")


def rule_keys(config: dict, rule: str) -> tuple[str, ...]:
    """The leaf config keys ``rule``'s stage reads (sorted), less :data:`SKIP` and the unset optional keys (a
    path, a WAV scale: they stay unset)."""
    return tuple(sorted(k for k in {leaf for p in READS[rule] for leaf in _leaves(config, p)} - SKIP
                        if _value(config, k) is not None))


def dry_listed(d: Path, dry, name: str, override: dict) -> set[str]:
    """The rules ``snakemake -n`` lists with ``override`` on top of the CI config (written to change_NAME.yaml)."""
    extra = d / f"change_{name}.yaml"
    extra.write_text(yaml.safe_dump(override))
    out = dry(["-n", "--configfile", "config/ci.yaml", extra.name])
    assert out.returncode == 0, f"{name}: {out.stderr[-2000:]}"
    return _jobs(out.stdout + out.stderr)


def test_an_undeclared_key_read_raises_naming_the_rule_and_the_fix():
    from piezobearing.workflow.registry import UndeclaredKeyError, declared, declared_config

    config = piezobearing.config.load(ROOT / "config/ci.yaml")
    sub = declared_config(declared(config, "sensor_voltage"), "sensor_voltage")
    assert sub["signals"]["skip_s"] == config["signals"]["skip_s"]
    with pytest.raises(UndeclaredKeyError, match=r"signals\.snr_dB.*READS\['sensor_voltage'\]"):
        sub["signals"]["snr_dB"]


@pytest.mark.parametrize(
    "module, rules",
    [
        # a leaf of the plotting package: only the figure that draws with it
        ("plotting/bearing.py", {"fig03"}),
        # the envelope analysis and SNR statistics: every rule of the signals stage module, not the bearing's; the sensor comparison (its chain is chain.signals)
        (
            "signals/analysis.py",
            {"sensor_voltage", "noisy", "envelope", "fault_indicator", "snr_study", "snr_study_figure",
             "defect_events", "fault_type_voltage", "sensor_comparison", "sensor_comparison_figure"},
        ),
    ],
)
def test_a_changed_package_module_reruns_exactly_the_rules_whose_code_imports_it(scratch, dry, module, rules):
    d, env, children = scratch
    f = d / "src/piezobearing" / module
    original = f.read_text()
    try:
        f.write_text(original + "\n# an edit\n")
        out = dry(["-n", "--configfile", "config/ci.yaml"])
    finally:
        f.write_text(original)
    assert out.returncode == 0, out.stderr[-2000:]
    assert _jobs(out.stdout + out.stderr) == _downstream(rules, children)


def test_a_replaced_record_with_an_older_time_reruns_what_reads_it(scratch, dry):
    from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
    from piezobearing.io import write_measurement
    from piezobearing.stages.calibration import nominal_circuit

    d, env, children = scratch
    config = piezobearing.config.load(d / "config/ci.yaml")
    record = d / "data/record.csv"

    def write(seed: int) -> None:
        syn = config["synthesis"]
        write_measurement(synthesize(PressProtocol.from_config(syn), nominal_circuit(config), seed, []), record)

    write(1)
    (d / "record.yaml").write_text(yaml.safe_dump({"calibration": {"measurement": "data/record.csv"}}))
    args = ["--configfile", "config/ci.yaml", "record.yaml"]
    out = dry(["--cores", "2", *args])  # a real run: the stand-ins of what reads it
    assert out.returncode == 0, out.stderr[-3000:]
    before = record.stat().st_mtime
    write(2)  # another record, then dated a day back (as cp -p, unzip or rsync -a leave it)
    os.utime(record, (before - 86400, before - 86400))
    out = dry(["-n", *args])
    assert out.returncode == 0, out.stderr[-2000:]
    assert _jobs(out.stdout + out.stderr) == _downstream(set(RECORD_RULES), children)
    assert RECORD_RULES == {"diagnose", "extract_sensitivity", "fig05", "fit_resistance"}
