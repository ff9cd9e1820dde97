"""Intervals of a fit whose residual is not white (fitting/correlation.py): a line in AR(1) noise, where the
slope's variance has a closed form."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import stdtrit

from piezobearing.fitting.correlation import correlation_factors, long_run_variance, plugin_lag
from piezobearing.fitting.least_squares import fit
from piezobearing.fitting.params import Param
from piezobearing.fitting.profile import honest_intervals

N = 4000
DRAWS = 400
T = np.linspace(0.0, 1.0, N)
X = np.column_stack([np.ones(N), T])
#: Binomial tolerance of a coverage of 0.95 in DRAWS draws: three standard deviations, 3 sqrt(0.95 0.05 / 400).
COVERAGE_TOL = 3.0 * np.sqrt(0.95 * 0.05 / DRAWS)


def ar1(rng, phi: float, n: int = N) -> np.ndarray:
    """Stationary AR(1) noise e_t = phi e_(t-1) + w_t, w white of unit variance."""
    w = rng.standard_normal(n)
    e = np.empty(n)
    e[0] = w[0] / np.sqrt(1.0 - phi**2)
    for i in range(1, n):
        e[i] = phi * e[i - 1] + w[i]
    return e


def slope_draws(phi: float, seed: int = 7):
    """(slope error, Gauss-Newton half-width, factor) of DRAWS least-squares lines y = 2 + 3 t + e."""
    rng = np.random.default_rng(seed)
    tq = float(stdtrit(N - 2, 0.975))
    inv = np.linalg.inv(X.T @ X)
    out = []
    for _ in range(DRAWS):
        y = 2.0 + 3.0 * T + ar1(rng, phi)
        beta = inv @ (X.T @ y)
        r = y - X @ beta
        half = tq * np.sqrt(r @ r / (N - 2) * inv[1, 1])
        out.append((beta[1] - 3.0, half, correlation_factors(-X, r)[1]))
    return np.array(out)


def exact_ratio(phi: float) -> float:
    """Var(slope) in AR(1) noise over the Gauss-Newton variance's expectation E[s^2] [(X^T X)^-1]_11, exactly:
    c Sigma c^T / (tr(M Sigma) / (n - 2) c c^T), Sigma_ij = phi^|i-j| / (1 - phi^2), c = row 1 of (X^T X)^-1 X^T,
    M = I - X (X^T X)^-1 X^T (the sums over lags end where phi^l < 1e-17)."""
    inv = np.linalg.inv(X.T @ X)
    c = (inv @ X.T)[1]
    lags = int(np.ceil(np.log(1e-17) / np.log(phi)))
    rho = phi ** np.arange(lags + 1) / (1.0 - phi**2)

    def quad(a, b):  # a^T Sigma b
        return rho[0] * (a @ b) + sum(rho[k] * (a[k:] @ b[:-k] + b[k:] @ a[:-k]) for k in range(1, lags + 1))

    var = quad(c, c)
    tr_h = sum(inv[i, j] * quad(X[:, i], X[:, j]) for i in range(2) for j in range(2))
    es2 = (N * rho[0] - tr_h) / (N - 2)
    return float(var / (es2 * (c @ c)))


def test_ar1_noise_corrected_interval_covers_and_white_one_does_not():
    """phi = 0.5: the slope's variance is 3.0 times the Gauss-Newton's (the closed form, 2.99 here); the
    corrected 95% interval covers the truth in 0.95 +- COVERAGE_TOL of 400 seeded draws, the white one in
    under 85%; the mean factor is the closed form's within 10% (the kernel estimate is a little low)."""
    d = slope_draws(0.5)
    err, half, f = d[:, 0], d[:, 1], d[:, 2]
    white = np.mean(np.abs(err) <= half)
    corrected = np.mean(np.abs(err) <= half * np.sqrt(f))
    assert abs(corrected - 0.95) <= COVERAGE_TOL
    assert white < 0.85
    assert np.mean(f) == pytest.approx(exact_ratio(0.5), rel=0.10)


def test_white_noise_leaves_the_interval_within_a_few_percent():
    """phi = 0: the factor is 1 in expectation (taken as at least 1): the corrected interval is the white one's
    within 3% in the median draw and 10% in 95% of the draws."""
    f = slope_draws(0.0)[:, 2]
    widen = np.sqrt(f)
    assert np.median(widen) <= 1.03
    assert np.quantile(widen, 0.95) <= 1.10
    assert np.min(f) >= 1.0


def test_lag_and_long_run_variance_of_a_known_series():
    """White noise of 20000 samples: the plug-in lag stays a few tens of samples (its covariances are noise) and
    the long-run variance is sum psi^2 (5%); AR(1) at
    phi = 0.8: the long-run variance over sum psi^2 approaches (1 + phi) / (1 - phi) = 9 (within 20%)."""
    rng = np.random.default_rng(3)
    w = rng.standard_normal(20000)
    lag = plugin_lag(w)
    assert lag <= 50
    assert long_run_variance(w, lag) == pytest.approx(w @ w, rel=0.05)
    e = ar1(rng, 0.8, 20000)
    assert long_run_variance(e, plugin_lag(e)) / (e @ e) == pytest.approx(9.0, rel=0.2)


def test_honest_intervals_widen_by_the_factor():
    """honest_intervals with a variance factor f: the Jacobian interval's half-width times sqrt(f), still
    checked (the threshold raised by f), and the factor reported; without one, no key is added."""
    rng = np.random.default_rng(5)
    y = 2.0 + 3.0 * T + 0.1 * ar1(rng, 0.5)
    fn = lambda v: (y - (v["offset_V"] + v["slope_V"] * T)) / 0.1  # noqa: E731
    ps = [Param("offset_V", 0.0), Param("slope_V", 0.0)]
    res = fit(fn, ps)
    plain = honest_intervals(fn, ps, res)
    f = dict(zip(["offset_V", "slope_V"], correlation_factors(res.jacobian, res.residual), strict=True))
    assert f["slope_V"] > 1.5
    wide = honest_intervals(fn, ps, res, inflation=f)
    for name in ("offset_V", "slope_V"):
        lo, hi = plain[name].ci
        wlo, whi = wide[name].ci
        assert wide[name].method == "jacobian (checked)"
        assert (whi - wlo) / (hi - lo) == pytest.approx(np.sqrt(f[name]), rel=1e-6)
        assert wide[name].jacobian_ci == plain[name].jacobian_ci
        assert wide[name].report()["correlation_factor"] == f[name]
        assert "correlation_factor" not in plain[name].report()
