"""Profile-likelihood intervals (fitting/profile.py): equal to the Jacobian's where the cost is quadratic,
and found by refitting where it is not."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from piezobearing.fitting.least_squares import fit
from piezobearing.fitting.params import Param
from piezobearing.fitting.profile import honest_intervals, profile_interval

T = np.linspace(0.0, 1.0, 40)


def line_problem(seed: int = 1):
    y = 2.0 + 3.0 * T + np.random.default_rng(seed).normal(0, 0.1, T.size)
    fn = lambda v: (y - (v["offset_V"] + v["slope_V"] * T)) / 0.1  # noqa: E731
    ps = [Param("offset_V", 0.0), Param("slope_V", 0.0)]
    return fn, ps, fit(fn, ps)


def decay_problem(seed: int):
    """A decay of time constant 50 ms in 40 samples over 1 s at noise 0.3: tau is poorly and asymmetrically pinned."""
    y = np.exp(-T / 0.05) + np.random.default_rng(seed).normal(0, 0.3, T.size)
    fn = lambda v: (y - v["amp_V"] * np.exp(-T / v["tau_s"])) / 0.3  # noqa: E731
    ps = [Param("amp_V", 1.0, 0.0, 10.0), Param("tau_s", 0.05, 1e-3, 10.0, log=True)]
    return fn, ps, fit(fn, ps)


def test_model_linear_in_its_parameters_keeps_the_jacobian_interval():
    """Quadratic cost: chi2 rises by exactly D at the Jacobian ends, and the profile reproduces them."""
    fn, ps, res = line_problem()
    h = honest_intervals(fn, ps, res)
    for name in ("offset_V", "slope_V"):
        assert h[name].method == "jacobian (checked)"
        assert h[name].rise == pytest.approx([1.0, 1.0], abs=1e-6)
        assert h[name].ci == res.ci95[name]
    prof = profile_interval(fn, ps, res, "slope_V")  # the ends are found to 1% of the half-width in sqrt(P)
    lo, hi = res.ci95["slope_V"]
    assert prof.ci == pytest.approx([lo, hi], abs=0.01 * (hi - lo))


def test_nonlinear_parameter_is_profiled_and_its_ends_raise_chi2_by_the_threshold():
    """Seed 0 of the decay: the Jacobian ends of tau raise chi2 by 0.95 and 1.49 D (not quadratic), so tau is
    profiled; refitting with tau fixed at either profile end raises chi2 by D (1%), and the interval is
    shifted towards short tau against the Jacobian's."""
    fn, ps, res = decay_problem(0)
    h = honest_intervals(fn, ps, res)["tau_s"]
    assert h.method == "profile" and max(abs(r - 1) for r in h.rise) > 0.25
    dof = res.n_data - res.n_free
    from scipy.stats import t as student_t

    d = res.chi2 / dof * student_t.ppf(0.975, dof) ** 2
    for end in h.ci:
        fixed = [replace(p, vary=False, value=end) if p.name == "tau_s" else p for p in ps]
        assert fit(fn, fixed).chi2 - res.chi2 == pytest.approx(d, rel=0.02)
    assert h.ci[1] < h.jacobian_ci[1]


def test_profile_follows_a_valley_of_two_confounded_parameters_to_a_bound():
    """y = a b t: only the product is determined (r = -1). With b bounded to [0.5, 2] and a free, the profile of
    a is flat while b compensates and closes where b reaches its bounds: [p / 2, 2 p] widened by D, not the
    Jacobian's (meaningless) interval."""
    y = 3.0 * T + np.random.default_rng(4).normal(0, 0.1, T.size)
    fn = lambda v: (y - v["a_V"] * v["b_ratio"] * T) / 0.1  # noqa: E731
    ps = [Param("a_V", 3.0, 0.0, 100.0), Param("b_ratio", 1.0, 0.5, 2.0)]
    res = fit(fn, ps)
    prod = res.values["a_V"] * res.values["b_ratio"]
    h = profile_interval(fn, ps, res, "a_V")
    assert h.ci[0] == pytest.approx(prod / 2, rel=0.03) and h.ci[1] == pytest.approx(2 * prod, rel=0.03)


def test_an_end_the_data_do_not_close_is_the_bound():
    """Seed 2 of the decay: chi2 never rises by D towards short tau before its bound of 1 ms."""
    fn, ps, res = decay_problem(2)
    h = honest_intervals(fn, ps, res)["tau_s"]
    assert h.method == "profile"
    assert h.at_bound == [True, False] and h.ci[0] == pytest.approx(1e-3)


def test_an_evaluation_budget_stops_a_profile_and_says_so():
    """The same profiled tau (seed 0 of the decay) with too few evaluations allowed keeps the Jacobian
    interval, flagged; the cheap checks are counted too, and a generous budget changes nothing."""
    fn, ps, res = decay_problem(0)
    free = honest_intervals(fn, ps, res)["tau_s"]
    stopped = honest_intervals(fn, ps, res, max_evaluations=6)["tau_s"]
    assert stopped.method == "jacobian (not honest; profile over budget)"
    assert stopped.ci == stopped.jacobian_ci == free.jacobian_ci
    assert honest_intervals(fn, ps, res, max_evaluations=100_000)["tau_s"].ci == free.ci
