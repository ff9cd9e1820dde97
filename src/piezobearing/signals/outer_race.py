"""The baseline detector's outer-race test: a record's roller-passage harmonics against the healthy baseline's.

The test minimises over the phase of the roller train (inside) and over the
fundamental (outside, from up to four starts), and a Monte Carlo or a
classification runs it on hundreds of records. :func:`harmonic_tests` steps
every record's and start's searches together (:func:`.scalar_search.fminbound_many`:
scipy's bounded Brent, problem by problem the same steps) and evaluates the
harmonic fits (:func:`.harmonics.harmonic_fits`) and the phase searches as
arrays over all of them; :func:`harmonic_test` is the batch of one. Each
record's numbers are exactly those of the record alone (tests).
"""

from __future__ import annotations

import numpy as np
from scipy.special import chdtr, chdtrc, gammaincinv, gammaln

from .harmonics import below_nyquist, harmonic_fits
from .scalar_search import fminbound_many


def log_chi2_sf(q, dof):
    """ln P(chi^2_dof > q), with the leading asymptotic term where scipy underflows [-] (arrays too).

    ``scipy.stats.chi2.logsf`` bit for bit, from its special functions (scipy.special): above the median
    ln(chdtrc), below it ln(1 - chdtr); 0 for q <= 0, NaN for dof <= 0 or q NaN (scipy.special: the
    workflow's detection jobs need nothing else of scipy.stats); tests/test_signals_synthetic.py compares the
    two on a grid.
    """
    q, dof = np.broadcast_arrays(np.asarray(q, float), np.asarray(dof, float))
    v = np.full(q.shape, -np.inf)
    valid = dof > 0
    v[~valid | np.isnan(q)] = np.nan
    v[valid & (q <= 0)] = 0.0
    with np.errstate(invalid="ignore"):
        inside = valid & (q > 0) & (q < np.inf)
    x, d = q[inside], dof[inside]
    upper = x > 2 * gammaincinv(d / 2, 0.5)  # above the median
    out = np.empty(x.shape)
    with np.errstate(divide="ignore"):
        out[upper] = np.log(chdtrc(d[upper], x[upper]))
        out[~upper] = np.log1p(-chdtr(d[~upper], x[~upper]))
    v[inside] = out
    bad = ~np.isfinite(v)
    if bad.any():
        a = 0.5 * dof[bad]
        v[bad] = -0.5 * q[bad] + (a - 1.0) * np.log(0.5 * q[bad]) - gammaln(a)
    return float(v) if v.ndim == 0 else v


def _rotate(c: np.ndarray, phi) -> np.ndarray:
    """Harmonic coefficients (a_k, b_k; the mean left out) of the periodic signals ``c`` (P, 2K + 1) shifted in
    phase by ``phi`` (P,) at the fundamental [V], shape (P, 2K)."""
    phi = np.asarray(phi, float)[:, None]
    k = np.arange(1, (c.shape[-1] - 1) // 2 + 1)[None, :]
    a, b = c[:, 1::2], c[:, 2::2]
    cos, sin = np.cos(k * phi), np.sin(k * phi)
    out = np.empty((c.shape[0], c.shape[-1] - 1))
    out[:, 0::2] = a * cos - b * sin
    out[:, 1::2] = a * sin + b * cos
    return out


def _information(gram: np.ndarray, sigma: float, cb: np.ndarray, tolerance: float) -> np.ndarray:
    """Inverse covariance of the harmonic coefficients (the mean marginalised) [1/V^2]:
    (sigma^2 [(A^T A)^-1]_harmonics + diag(tolerance^2 |c_b,k|^2))^-1.

    [(A^T A)^-1]_hh^-1 is the Schur complement S = G_hh - G_h0 G_0h / G_00 of the mean (no inverse; two
    inverses of (2K) x (2K) matrices were 1.0 s of the 1.85 s outer-race test at 25.6 kHz); with a
    ``tolerance``, (sigma^2 S^-1 + D)^-1."""
    s = gram[1:, 1:] - np.outer(gram[1:, 0], gram[0, 1:]) / gram[0, 0]
    if tolerance <= 0:
        return s / sigma**2
    cov = sigma**2 * np.linalg.inv(s) + np.diag(tolerance**2 * np.repeat(cb[1::2] ** 2 + cb[2::2] ** 2, 2))
    return np.linalg.inv(cov)


def _phase_search(c: np.ndarray, cb: np.ndarray, info: np.ndarray, gain_tolerance: float = 0.0,
                  n_phases: int = 512) -> tuple[float, float]:
    """min over phi (and g) of q = (c - g R(phi) c_b)^T info (c - g R(phi) c_b) + (g - 1)^2 / tau^2: (q, phi).

    tau = ``gain_tolerance``: g = 1 for tau = 0, else the gain that minimises q
    (a Gaussian prior of standard deviation tau on the baseline's level:
    q stays chi^2 with the same degrees of freedom). The
    cross term is a trigonometric polynomial in phi: with the diagonal of
    ``info`` it is Re sum_k z_k e^{i k phi}, evaluated on ``n_phases`` phases
    by one FFT (its maximum is the best phase either way); the best phase is
    then refined on the exact q. :func:`_phase_searches` of one.
    """
    q, phi = _phase_searches(c[None, :], cb[None, :], info[None], gain_tolerance, n_phases)
    return float(q[0]), float(phi[0])


def _phase_searches(c: np.ndarray, cb: np.ndarray, info: np.ndarray, gain_tolerance: float = 0.0,
                    n_phases: int = 512) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_phase_search` of each row: ``c``, ``cb`` (P, 2K + 1), ``info`` (P, 2K, 2K): (q (P,), phi (P,))."""
    kk = (c.shape[-1] - 1) // 2

    def q(i: np.ndarray, phi: np.ndarray) -> np.ndarray:
        b, ci, inf = _rotate(cb[i], phi), c[i, 1:], info[i]
        if gain_tolerance <= 0:
            d = ci - b
            return np.einsum("pi,pij,pj->p", d, inf, d)
        p = 1.0 / gain_tolerance**2
        g = (np.einsum("pi,pij,pj->p", ci, inf, b) + p) / (np.einsum("pi,pij,pj->p", b, inf, b) + p)
        d = ci - g[:, None] * b
        return np.einsum("pi,pij,pj->p", d, inf, d) + p * (g - 1.0) ** 2

    w = np.diagonal(info, axis1=1, axis2=2)[:, 0::2]
    z = np.zeros((c.shape[0], n_phases), complex)
    z[:, 1:kk + 1] = w * (c[:, 1::2] - 1j * c[:, 2::2]) * np.conj(cb[:, 1::2] - 1j * cb[:, 2::2])
    cross = np.real(n_phases * np.fft.ifft(z, axis=1))
    h = 2.0 * np.pi / n_phases
    phi_c = np.argmax(cross, axis=1) * h
    x, fun = fminbound_many(q, phi_c - h, phi_c + h, 1e-6)
    q_c = q(np.arange(c.shape[0]), phi_c)
    better = fun < q_c
    return np.where(better, fun, q_c), np.where(better, x, phi_c)


def harmonic_test(x: np.ndarray, dt_s: float, f0_Hz: float, baseline, sigma: float,
                  tolerance: float = 0.0, f_range_Hz: tuple[float, float] | None = None,
                  gain_tolerance: float = 0.0) -> dict:
    """Roller-passage harmonics of ``x`` against the baseline's (outer-race test); :func:`harmonic_tests` of one.

    q(f, phi) = (c(f) - g R(phi) c_b)^T C^-1 (c(f) - g R(phi) c_b), c(f) the
    least-squares coefficients of the harmonics k f, k = 1..K below Nyquist,
    C = sigma^2 [(A^T A)^-1]_harmonics + diag(tolerance^2 |c_b|^2) (the mean
    marginalised), g = 1 or, with ``gain_tolerance`` tau > 0, fitted with the
    penalty (g - 1)^2 / tau^2 added (a Gaussian prior on the baseline's
    level; the degrees of freedom stay), minimised over the phase phi of the
    roller train. Without ``f_range_Hz``, at f = ``f0_Hz``: under noise alone
    q ~ chi^2_{2K-1}.

    With ``f_range_Hz`` (the slip window) the fundamental is the healthy
    model's: f, phi = argmin ||x - mean - A(f) g R(phi) c_b||^2 (the baseline's
    waveform fitted to the record; in sigma^2 units RSS(f) + q(f, phi), RSS(f)
    the free harmonic fit's residual at f, by Pythagoras), and q is taken
    there. It is bounded by the likelihood ratio of the healthy model
    against the free one (any harmonics, f fitted too), q = LR - (RSS(f) -
    min RSS) / sigma^2 <= LR ~ chi^2_{2K-1} (Wilks: the search over f is in
    both models). Two alternatives were measured on the LPM records and
    not taken (docs/theory/detection.md): f from the free fit alone, whose error inflates q at
    low SNR (the healthy bearing called faulty in 8 of 50 seeds at -10 dB);
    and the minimum of q over f, which never exceeds q at the true f but
    lets the search average the fault's harmonics away (the 0.9 mm
    outer-race fault at -10 dB detected in 5 of 100 seeds instead of 98).

    The f search: K is fixed by the range's top (:func:`below_nyquist`); a
    grid with the top harmonic moving a quarter of a bin between nodes, each
    node scored with the diagonal of A^T A from the record's 16-fold padded
    FFT (the phase by FFT, :func:`_phase_search`), then the best nodes and
    the node of ``f0_Hz`` (the free fit's f) refined on the exact misfit
    (:func:`.harmonics.harmonic_fit`).

    Returns
    -------
    dict
        statistic q, dof, log10_p, phase_rad, f0_Hz (the healthy model's f), n_harmonics K.
    """
    x = np.asarray(x, float)
    return harmonic_tests(x[None, :], dt_s, [f0_Hz], [baseline], [sigma], tolerance, f_range_Hz, gain_tolerance)[0]


def harmonic_tests(x: np.ndarray, dt_s: float, f0_Hz, baselines, sigma, tolerance: float = 0.0,
                   f_range_Hz: tuple[float, float] | None = None, gain_tolerance: float = 0.0) -> list[dict]:
    """:func:`harmonic_test` of each row of ``x`` (R, n) [V] with its own ``f0_Hz`` [Hz], baseline (anything
    with ``coefficients``) and ``sigma`` [V] (sequences of R); the searches of all rows run together."""
    x = np.asarray(x, float)
    f0, sigma = np.asarray(f0_Hz, float), np.asarray(sigma, float)
    f_top = f0 if f_range_Hz is None else np.full(f0.shape, f_range_Hz[1])
    ks = np.array([min(below_nyquist(dt_s, float(ft)), (b.coefficients.size - 1) // 2)
                   for ft, b in zip(f_top, baselines, strict=True)])
    out: list = [None] * x.shape[0]
    for k in np.unique(ks):  # rows of one K together (a batch shares K)
        for rows in row_chunks(np.flatnonzero(ks == k), x.shape[1], int(k)):
            res = _tests_of_one_k(x[rows], dt_s, f0[rows], [baselines[r] for r in rows], sigma[rows], int(k),
                                  tolerance, f_range_Hz, gain_tolerance)
            for r, d in zip(rows, res, strict=True):
                out[r] = d
    return out


#: Largest number of matrix entries (Gram and information matrices of every start, the records) one batch of
#: :func:`harmonic_tests` holds: about 25 MB in all, so that a batch needs no more memory than the one-record code
#: at high rates (at 25.6 and 51.2 kHz, K = 182 and 361: one record a batch; at 2550 Hz, 100).
BATCH_ENTRIES = 1_000_000


def row_chunks(rows: np.ndarray, n: int, k: int):
    """``rows`` in batches whose Gram and information matrices (up to four starts a record) and records stay
    within :data:`BATCH_ENTRIES`."""
    size = max(1, BATCH_ENTRIES // (4 * (2 * k + 1) ** 2 + 2 * n))
    for i in range(0, len(rows), size):
        yield rows[i:i + size]


def _tests_of_one_k(x, dt_s, f0, baselines, sigma, k, tolerance, f_range_Hz, gain_tolerance) -> list[dict]:
    cb = np.array([b.coefficients[: 2 * k + 1] for b in baselines])
    xx = np.array([float(r @ r) for r in x])

    def exact(rec: np.ndarray, f: np.ndarray) -> tuple:
        """(min_phi q(f, phi), its phi, RSS(f) / sigma^2) of the records ``rec`` at ``f``, (P,) each"""
        c, gram, xt = harmonic_fits(x[rec], dt_s, f, k)
        info = np.array([_information(gram[i], sigma[r], cb[r], tolerance) for i, r in enumerate(rec)])
        q, phi = _phase_searches(c, cb[rec], info, gain_tolerance)
        rss = np.array([xx[r] - c[i] @ xt[i] for i, r in enumerate(rec)]) / sigma[rec] ** 2
        return q, phi, rss

    if f_range_Hz is None:
        f_best = f0
        val, phi, _ = exact(np.arange(x.shape[0]), f0)
    else:
        f_best, val, phi = _frequency_searches(x, dt_s, f0, f_range_Hz, k, cb, sigma, tolerance, exact,
                                               gain_tolerance)
    dof = 2 * k - 1
    return [{"statistic": float(v), "dof": dof, "log10_p": log_chi2_sf(float(v), dof) / np.log(10.0),
             "phase_rad": float(p), "f0_Hz": float(f), "n_harmonics": k} for v, p, f in zip(val, phi, f_best, strict=True)]


def _starts(x, dt_s, f0_Hz, grid, k, cb, sigma, tolerance, gain_tolerance, n_refine) -> list[int]:
    """The grid nodes whose exact misfit the search refines (:func:`harmonic_test`): the ``n_refine`` best local
    minima of the grid's score, then the node of ``f0_Hz``, without repeats."""
    n = x.size
    m = 16 * int(2 ** np.ceil(np.log2(n)))
    spec = np.fft.rfft(x - x.mean(), m)
    idx = np.clip(np.rint(np.outer(grid, np.arange(1, k + 1)) * m * dt_s).astype(int), 0, spec.size - 1)
    coef = 2.0 / n * spec[idx]  # a_k - i b_k at each node, to the padded grid's resolution
    cbc = cb[1::2] - 1j * cb[2::2]
    amp2 = np.abs(cbc) ** 2
    w = 1.0 / (2.0 * sigma**2 / n + tolerance**2 * amp2)
    p = 512 if k < 64 else 4 * int(2 ** np.ceil(np.log2(k)))
    z = np.zeros((grid.size, p), complex)
    z[:, 1:k + 1] = w * coef * np.conj(cbc)
    cross = np.real(p * np.fft.ifft(z, axis=1)).max(axis=1)
    if gain_tolerance > 0:  # the gain g = (cross + 1/tau^2) / (sum w |c_b|^2 + 1/tau^2) profiled out
        pg = 1.0 / gain_tolerance**2
        q = (w * np.abs(coef) ** 2).sum(axis=1) + pg - (cross + pg) ** 2 / ((w * amp2).sum() + pg)
    else:
        q = (w * (np.abs(coef) ** 2 + amp2)).sum(axis=1) - 2.0 * cross
    score = q - 0.5 * n / sigma**2 * (np.abs(coef) ** 2).sum(axis=1)  # RSS(f) + q, less a constant
    loc = [i for i in range(grid.size)
           if score[i] <= score[max(i - 1, 0)] and score[i] <= score[min(i + 1, grid.size - 1)]]
    starts = sorted(loc, key=lambda i: score[i])[:n_refine] + [int(np.argmin(np.abs(grid - f0_Hz)))]
    return list(dict.fromkeys(starts))


def _frequency_searches(x, dt_s, f0_Hz, f_range_Hz, k, cb, sigma, tolerance, exact, gain_tolerance=0.0,
                        n_refine=3):
    """The healthy model's fundamental in ``f_range_Hz`` for each row of ``x``, argmin RSS(f) + q(f):
    (f, q, phi), (R,) each (:func:`harmonic_test`).

    Each start node is refined by a bounded search over its two neighbouring intervals, then evaluated itself;
    the result is the first evaluation of least misfit in the order of a record's searches run one after the
    other (starts in order, each search's evaluations, then its node): all starts of all records step together.
    """
    n = x.shape[1]
    lo, hi = f_range_Hz
    h = 0.25 / (k * n * dt_s)
    grid = np.linspace(lo, hi, max(int(np.ceil((hi - lo) / h)), 1) + 1)
    rec, node, pos = [], [], []
    for r in range(x.shape[0]):
        for j, i in enumerate(_starts(x[r], dt_s, f0_Hz[r], grid, k, cb[r], sigma[r], tolerance, gain_tolerance,
                                      n_refine)):
            rec.append(r), node.append(i), pos.append(j)
    rec, node, pos = np.array(rec), np.array(node), np.array(pos)
    evals = []  # (problem, call number, f, q, phi, misfit) arrays of each call

    def misfit(i: np.ndarray, f: np.ndarray) -> np.ndarray:
        q, phi, rss = exact(rec[i], f)
        evals.append((i, np.full(i.size, len(evals)), f, q, phi, q + rss))
        return q + rss

    fminbound_many(misfit, grid[np.maximum(node - 1, 0)], grid[np.minimum(node + 1, grid.size - 1)], 1e-3 * h)
    misfit(np.arange(rec.size), grid[node])
    prob, call, f, q, phi, mis = (np.concatenate(a) for a in zip(*evals, strict=True))
    order = np.lexsort((call, pos[prob], rec[prob]))  # each record's evaluations in the one-by-one order
    f_best, q_best, phi_best = np.empty(x.shape[0]), np.empty(x.shape[0]), np.empty(x.shape[0])
    for r, idx in _groups(rec[prob][order], order):
        j = idx[int(np.argmin(mis[idx]))]  # the first of least misfit
        f_best[r], q_best[r], phi_best[r] = f[j], q[j], phi[j]
    return f_best, q_best, phi_best


def _groups(keys: np.ndarray, values: np.ndarray):
    """(key, values of that key) for a ``keys`` array sorted into runs."""
    cut = np.flatnonzero(np.diff(keys)) + 1
    for part_k, part_v in zip(np.split(keys, cut), np.split(values, cut), strict=True):
        if part_k.size:
            yield int(part_k[0]), part_v
