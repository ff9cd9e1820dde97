"""Rule params Snakemake prints short: the config values a stage reads are recorded and shown as their keys and a
digest, and still trigger a rerun when any value changes (the full check on the workflow: test_workflow_rerun)."""

import copy
import pickle

from snakemake.persistence import PersistenceBase

from piezobearing.workflow.registry import ShortParam, rule_params


def _recorded(value) -> str:
    """What Snakemake records of a param and compares to decide a rerun (snakemake.persistence)."""
    return PersistenceBase._serialize_param_builtin(None, value)


def test_a_rule_param_is_recorded_as_its_keys_and_a_digest(paper_config):
    params = rule_params("bearing_lpm", paper_config, "workflow/scripts/bearing_lpm.py")
    recorded = _recorded(params["reads"])
    assert recorded.startswith("{seed, bearing} sha256:") and len(recorded) < 60, recorded
    assert recorded == str(params["reads"])


def test_the_digest_changes_with_any_value_and_only_then(paper_config):
    reads = rule_params("bearing_lpm", paper_config, "workflow/scripts/bearing_lpm.py")["reads"]
    same = rule_params("bearing_lpm", copy.deepcopy(paper_config), "workflow/scripts/bearing_lpm.py")["reads"]
    assert _recorded(same) == _recorded(reads)
    changed = copy.deepcopy(paper_config)
    changed["bearing"]["defects"][0]["depth_m"] *= 1.0 + 1e-12  # a nested value, changed in the last digits
    assert _recorded(rule_params("bearing_lpm", changed, "workflow/scripts/bearing_lpm.py")["reads"]) != _recorded(
        reads
    )


def test_the_stage_still_receives_the_values(paper_config):
    reads = rule_params("bearing_lpm", paper_config, "workflow/scripts/bearing_lpm.py")["reads"]
    back = pickle.loads(pickle.dumps(reads))  # as Snakemake hands params to a script job
    assert isinstance(back, ShortParam) and back == reads
    assert back["bearing"]["shaft_speed_rpm"] == paper_config["bearing"]["shaft_speed_rpm"]
