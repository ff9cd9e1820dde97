"""End to end: the workflow on config/ci.yaml in a fresh copy, twice.

Other stages add their own checks on the same run through the ``ci_run``
fixture (tests/conftest.py), so the workflow runs once per test session; the
second clean run (``ci_rerun``) checks that the numbers are reproducible.
"""

import json
from pathlib import Path

import pandas as pd
import pytest
from conftest import result_numbers, snakemake

pytestmark = pytest.mark.slow

CALIBRATION_OUTPUTS = [
    "results/calibration/measurement.csv",
    "results/calibration/sensitivity.json",
    "results/calibration/resistance.json",
    "results/sensor/lowfreq.json",
    "results/figures/fig05.png",
    "results/figures/fig06.png",
    "results/figures/fig08a.png",
    "results/notebooks/fig05_calibration_impulses.ipynb",
    "results/scorecard.md",
    "results/scorecard.csv",
]


def test_calibration_outputs_exist_and_hold_sane_values(ci_run: Path):
    for f in CALIBRATION_OUTPUTS:
        assert (ci_run / f).stat().st_size > 0, f
    sens = json.loads((ci_run / "results/calibration/sensitivity.json").read_text())
    res = json.loads((ci_run / "results/calibration/resistance.json").read_text())
    lf = json.loads((ci_run / "results/sensor/lowfreq.json").read_text())
    assert sens["n_impulses"] == 6
    assert 0.06 < sens["sensitivity_V_per_N"] < 0.09
    assert res["resistance_ohm"] == pytest.approx(50e6, rel=0.05)
    lo, hi = res["resistance_ci95_ohm"]
    assert lo < 50e6 < hi
    assert res["nrmse"] < 0.1
    assert lf["linear_from_Hz"] == 30.0
    assert 1.0 < lf["reference_sensitivity_V_per_N"] < 1.6
    card = pd.read_csv(ci_run / "results/scorecard.csv")
    assert {"impulse-peak sensitivity at ~0.5 Hz", "circuit resistance R (fitted)"} <= set(card["quantity"])


def test_nothing_left_to_do_after_a_run(ci_run: Path):
    out = snakemake("-n", "--configfile", "config/ci.yaml", cwd=ci_run)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "Nothing to be done" in out.stdout + out.stderr


def _numbers(root: Path) -> dict[str, str]:
    return {rel: (root / rel).read_text() for rel in result_numbers(root)}


def _first_difference(a: str, b: str) -> str:
    """Where two texts first differ, with a little context."""
    i = next((k for k, (x, y) in enumerate(zip(a, b, strict=False)) if x != y), min(len(a), len(b)))
    return f"...{a[max(0, i - 60) : i + 40]!r} vs ...{b[max(0, i - 60) : i + 40]!r}"


def test_a_second_clean_run_gives_identical_numbers(ci_run: Path, ci_rerun: Path):
    first, second = _numbers(ci_run), _numbers(ci_rerun)
    assert first.keys() == second.keys()
    differ = {k: _first_difference(first[k], second[k]) for k in first if first[k] != second[k]}
    assert not differ, "results differ between two clean runs:\n" + "\n".join(f"{k}: {v}" for k, v in differ.items())
