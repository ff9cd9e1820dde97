"""The default examples show the tool at work: the paper config's running-bearing record hides an outer-race
groove that the diagnosis finds; the healthy record is one run beside it (config/examples/healthy_bearing.yaml);
the ladder shows, beside the steps kept, what the best candidates not kept would have left."""

import copy
from pathlib import Path

import pytest
from matplotlib.patches import Rectangle

from piezobearing import config
from piezobearing.plotting.diagnostics import CANDIDATES, ladder


def test_the_default_record_hides_a_fault_and_the_healthy_one_is_a_run_beside_it(paper_config):
    hidden = paper_config["bearing"]["hidden_effects"]
    assert [h["name"] for h in hidden] == ["outer_race_defect"]
    healthy = config.load(Path(__file__).resolve().parents[1] / "config" / "examples" / "healthy_bearing.yaml")
    assert healthy["bearing"]["hidden_effects"] == [] and config.results_folder(healthy) == "results/healthy_bearing"


@pytest.mark.slow
def test_the_diagnosis_finds_the_default_records_groove(ci_config, ci_influence):
    """The default record (CI mesh, the paper config's 2 s at 2550 Hz and 30 dB): the groove selected alone,
    its width and angle inside their 95% intervals."""
    from piezobearing.diagnosis.bearing.subject import SUBJECT, synthesise

    c = copy.deepcopy(ci_config)
    c["bearing_diagnosis"]["synthetic_duration_s"] = config.load()["bearing_diagnosis"]["synthetic_duration_s"]
    influence = ci_influence
    hidden = c["bearing"]["hidden_effects"]
    d = SUBJECT.diagnose((synthesise(c, c["seed"], hidden, influence), influence), c)[1]
    assert d["selected"] == ["outer_race_defect"] and d["verdict"] == "explained"
    assert d["fault"]["type"] == "outer_race"
    for k, v in hidden[0]["params"].items():
        lo, hi = d["fault"]["ci95"][k]
        assert lo <= v <= hi, (k, v, lo, hi)


def test_the_ladder_shows_the_candidates_not_kept_beside_a_single_step():
    fit = {"nrmse": 0.0212, "noise_floor_nrmse": 0.021}
    ranking = [{"effect": f"effect_{i}", "nrmse": 0.0212, "noise_floor_nrmse": 0.021} for i in range(5)]
    d = {"baseline": fit, "steps": [{"effects": [], **fit}], "dropped_steps": [], "selected": [],
         "ranking": ranking, "verdict": "explained"}
    ax = ladder(d).axes[0]
    bars = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_height() > 0]
    assert len(bars) == 1 + CANDIDATES
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert labels[0] == "baseline" and labels[1] == "(+\neffect_0)\nnot kept"
