"""The calibrated test's statistics (piezobearing.comparison.statistics, .calibrated) on known distributions."""

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from piezobearing.comparison import calibrated, statistics


def test_threshold_at_a_false_alarm_rate_on_a_known_distribution():
    """On 200 000 Exp(1) draws the threshold at alpha is -ln(alpha) within its sampling error, and exactly
    floor(alpha N) draws lie above it."""
    x = np.random.default_rng(3).exponential(1.0, 200_000)
    for alpha in (0.05, 0.01):
        t = statistics.threshold_at(x, alpha)
        assert t == pytest.approx(-np.log(alpha), rel=0.02)
        assert np.count_nonzero(x > t) == int(np.floor(alpha * x.size))
    # 20 values, alpha 0.05: one above the threshold, the 19th smallest
    assert statistics.threshold_at(np.arange(20.0), 0.05) == 18.0


def test_clopper_pearson_is_scipys_exact_interval():
    for k, n in ((0, 100), (1, 100), (37, 100), (99, 100), (100, 100), (3, 7)):
        low, high = statistics.clopper_pearson(k, n)
        ci = stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="exact")
        assert low == pytest.approx(ci.low, rel=1e-9, abs=1e-12)
        assert high == pytest.approx(ci.high, rel=1e-9, abs=1e-12)


def test_detection_probability_at_a_threshold():
    d = statistics.detection(np.arange(10.0), 6.5)
    assert (d.detected, d.n, d.probability) == (3, 10, 0.3)
    assert (d.ci_low, d.ci_high) == pytest.approx(statistics.clopper_pearson(3, 10))


def test_tail_fit_recovers_an_exponential_tail():
    """Excesses of an exponential over its 80 % quantile are exponential: the fit's shape is near 0, its scale
    the exponential's, its 1 % threshold -scale ln(0.01), and the KS check does not reject it."""
    scale = 2.0
    x = np.random.default_rng(5).exponential(scale, 5000)
    fit = statistics.tail_threshold(x, 0.01, 0.2)
    assert fit.n_excesses == 1000
    assert abs(fit.shape) < 0.1
    assert fit.scale == pytest.approx(scale, rel=0.1)
    assert fit.threshold == pytest.approx(-scale * np.log(0.01), rel=0.05)
    assert fit.ks_p_value > 0.05


def test_tail_fit_rejects_a_wrong_tail():
    """A tail that is not generalized Pareto (two separated clusters of excesses) is rejected by the KS check."""
    rng = np.random.default_rng(6)
    x = np.concatenate([rng.normal(0.0, 1.0, 800), rng.normal(10.0, 0.01, 100), rng.normal(20.0, 0.01, 100)])
    assert statistics.tail_threshold(x, 0.01, 0.2).ks_p_value < 0.01


def test_roc_area_of_two_normals():
    """AUC of N(d, 1) against N(0, 1) is Phi(d / sqrt(2)); the curve runs from (1, 1) to (0, 0)."""
    rng = np.random.default_rng(7)
    h, f = rng.normal(0.0, 1.0, 2000), rng.normal(1.0, 1.0, 2000)
    r = statistics.roc(h, f)
    assert r.auc == pytest.approx(stats.norm.cdf(1.0 / np.sqrt(2.0)), abs=0.015)
    assert (r.false_alarm_rate[0], r.detection_probability[0]) == (1.0, 1.0)
    assert (r.false_alarm_rate[-1], r.detection_probability[-1]) == (0.0, 0.0)


def test_sensor_test_counts_unknown_as_an_alarm():
    settings = {"false_alarm_rate": 0.05, "tail_false_alarm_rate": 0.01, "tail_fraction": 0.2}
    h = np.linspace(-10.0, 0.0, 40)
    f = np.array([5.0, 6.0, -20.0, 7.0])
    out = calibrated.sensor_test(h, f, ["outer_race", "unknown", "none", "inner_race"], "outer_race", settings)
    assert out["calibrated_threshold_dB"] == pytest.approx(h[-3])
    assert out["calibrated_detection_probability"] == 0.75
    assert out["type_correct_rate"] == 0.25
    assert out["alarm_rate_faulty"] == 0.75
    assert out["tail_excesses"] == 8


def test_smallest_detected_width_per_sweep():
    df = pd.DataFrame({"sensor": ["pzt"] * 3 + ["accelerometer"] * 3, "defect_width_m": [1e-4, 3e-4, 9e-4] * 2,
                       "calibrated_detection_probability": [0.2, 0.6, 1.0, 0.1, 0.3, 0.4]})
    w = calibrated.smallest_detected_width(df)
    assert list(w[:3]) == [3e-4] * 3
    assert w[3:].isna().all()
