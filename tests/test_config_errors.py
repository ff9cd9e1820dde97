"""A bad config or study table stops with one line naming the key and the fix (CLI and workflow alike)."""

import copy

import pytest
from conftest import dry_run_errors

import piezobearing.config
from piezobearing.config.cases import check_studies


def error(config: dict) -> str:
    with pytest.raises(piezobearing.config.ConfigError) as e:
        piezobearing.config.validate(config, source="my.yaml")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("my.yaml: ")
    return msg


def test_the_schema_reads_the_same_with_libyaml_and_sets_no_defaults():
    """The workflow validates the config once, through ``piezobearing.config.validate`` (common.smk), which reads
    the schema with libyaml's loader: the same schema as PyYAML's pure-Python loader reads. Snakemake's own
    ``validate``, which the workflow does not call, would fill a schema ``default`` into the config: the schema has
    one, a defect's ``depth_m`` (the paper's 1 mm), and ``piezobearing.config.validate`` fills it
    (tests/test_diagnosis_bearing_feasible.py)."""
    import yaml

    text = piezobearing.config.SCHEMA_PATH.read_text()
    schema = yaml.load(text, Loader=piezobearing.config._LOADER)
    assert schema == yaml.safe_load(text)
    assert piezobearing.config._validator(str(piezobearing.config.SCHEMA_PATH)).schema == schema

    def defaults(node, path=()) -> list:
        if isinstance(node, dict):
            own = [(path, node["default"])] if "default" in node else []
            return own + [d for k, v in node.items() for d in defaults(v, (*path, k))]
        return [d for v in node for d in defaults(v, path)] if isinstance(node, list) else []

    for config_file in sorted(piezobearing.config.SCHEMA_PATH.parent.rglob("*.yaml")):
        # every config file the workflow and the docs ship: read_yaml (libyaml) gives the pure-Python loader's dict
        assert piezobearing.config.read_yaml(config_file) == (yaml.safe_load(config_file.read_text()) or {})

    assert defaults(schema) == [
        (("properties", "bearing", "properties", "defects", "items", "properties", "depth_m"), 1.0e-3)
    ]


def test_unknown_key_is_named_by_its_path_with_the_closest_key(paper_config):
    c = copy.deepcopy(paper_config)
    c["synthesis"]["resistence_ohm"] = 20.0e6
    msg = error(c)
    assert "key 'synthesis.resistence_ohm' is not a config key" in msg
    assert "did you mean 'synthesis.resistance_ohm'?" in msg


def test_unknown_top_level_key(paper_config):
    c = copy.deepcopy(paper_config)
    c["sead"] = 3
    assert "key 'sead' is not a config key; did you mean 'seed'?" in error(c)


def test_number_written_as_a_string_gets_the_yaml_hint(paper_config):
    c = copy.deepcopy(paper_config)
    c["synthesis"]["resistance_ohm"] = "50e6"  # what PyYAML makes of 50e6
    msg = error(c)
    assert "key 'synthesis.resistance_ohm'" in msg and "50.0e+6" in msg


def test_out_of_range_value(paper_config):
    c = copy.deepcopy(paper_config)
    c["synthesis"]["resistance_ohm"] = -5.0
    msg = error(c)
    assert "key 'synthesis.resistance_ohm': -5.0 is less than the minimum" in msg


def test_study_case_out_of_range_is_named_before_any_job(paper_config, tmp_path):
    table = tmp_path / "bad.tsv"
    table.write_text("synthesis__resistance_ohm\tsensor__cable_length_m\n50.0e+6\t2.0\n-5.0\t2.0\n")
    c = copy.deepcopy(paper_config)
    c["studies"] = [{"name": "calibration_circuit", "table": str(table)}]
    with pytest.raises(piezobearing.config.ConfigError) as e:
        check_studies(c)
    msg = str(e.value)
    assert f"{table}, case 2 (study calibration_circuit)" in msg and "synthesis.resistance_ohm" in msg
    assert set(check_studies(paper_config)) == {s["name"] for s in paper_config["studies"]}


@pytest.mark.parametrize(
    "override, fragment",
    [
        ("synthesis:\n  resistence_ohm: 20.0e+6\n", "key 'synthesis.resistence_ohm' is not a config key"),
        ("synthesis:\n  resistance_ohm: 50e6\n", "write numbers with a dot or a signed exponent"),
    ],
)
def test_workflow_stops_with_one_line_not_the_schema(tmp_path, override, fragment):
    user = tmp_path / "user.yaml"
    user.write_text(override)
    out, err = dry_run_errors(user)
    assert out.returncode != 0
    assert len(err) == 1 and fragment in err[0] and "user.yaml" in err[0], out.stderr[-2000:]
    assert "Failed validating" not in out.stderr and "Traceback" not in out.stderr


CHANGES = [
    ({}, None),
    ({("synthesis", "resistance_ohm"): 30.0e6}, None),
    ({("synthesis", "resistance_ohm"): -5.0}, "less than the minimum"),
    ({("synthesis", "resistance_ohm"): "50e6"}, "signed exponent"),
    ({("synthesis", "resistance_ohm"): -5.0, ("sensor", "cable_length_m"): "x"}, "key 'sensor.cable_length_m'"),
    ({("synthesis", "resistance_ohm"): float("nan")}, "not a finite number"),
    ({("synthesis", "resistence_ohm"): 1.0}, "did you mean 'synthesis.resistance_ohm'"),
    ({("signals", "detector"): "nonsense"}, "key 'signals.detector'"),
]


@pytest.mark.parametrize("changes, fragment", CHANGES)
def test_a_case_checked_by_its_changed_sections_is_checked_as_a_whole(paper_config, changes, fragment):
    """validate with a base (a study case against its valid base) gives the whole check's result and error."""
    base = piezobearing.config.validate(copy.deepcopy(paper_config))
    case = copy.deepcopy(base)
    for (section, key), value in changes.items():
        case[section][key] = value
    outcomes = []
    for check in (piezobearing.config.validate, lambda c, source: piezobearing.config.validate(c, source=source, base=base)):
        try:
            outcomes.append(check(copy.deepcopy(case), source="my.yaml"))
        except piezobearing.config.ConfigError as e:
            outcomes.append(str(e))
    assert outcomes[0] == outcomes[1]
    if fragment is None:
        assert outcomes[0] == case
    else:
        assert isinstance(outcomes[0], str) and fragment in outcomes[0], outcomes[0]
