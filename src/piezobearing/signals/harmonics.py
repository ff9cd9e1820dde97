"""Least squares on the harmonics of one fundamental: the normal equations in closed form, QR where ill-posed.

The baseline detector (:mod:`.baseline`) fits every harmonic of the
roller-passage frequency f0 to a record: up to f_s (``alias_folds`` = 1),
that is 2 K + 1 = 723 columns for 25 600 samples at 25.6 kHz and 1447 for
51 200 at 51.2 kHz. A pivoted QR of the explicit matrix costs O(n K^2):
4.5 s per fit at 25.6 kHz, three fits per record (the Gauss-Newton step on
f0 and the refit) plus one for the baseline, 13 s of CPU per record.

Here the same least squares in O(n log n + K^3):

- A^T A in closed form: its entries are sums sum_i cos(m theta i), sum_i
  sin(m theta i), theta = 2 pi f0 dt, m = 0..2K, geometric sums
  (1 - e^{i m theta n}) / (1 - e^{i m theta}), written as
  sin(pi b) e^{i pi b} / (sin(pi a) e^{i pi a}) with a = m nu, b = m nu n
  reduced modulo 1 exactly (:func:`frac_cycles`, nu = f0 dt in cycles per
  sample), so near-integer m nu (a harmonic near a multiple of f_s/2) loses
  no digits;
- A^T x the record's DTFT at k f0, and the fitted part A c its inverse, each
  one Bluestein chirp convolution (:func:`chirp_sum`) with the chirp's phase
  nu k^2 / 2 reduced exactly (scipy's ``CZT`` computes w ** (k^2 / 2), whose
  phase error grows with k^2: about 1e-9 rad at 51 200 samples);
- A^T A c = A^T x by Cholesky, its reciprocal condition number estimated
  (LAPACK ``dpocon``). Below ``RCOND_MIN`` (A's condition number above
  about 100: f_s within about 0.01 / T of a multiple of f0, where folded
  harmonics nearly coincide on the sample grid; the paper's 2550 Hz without
  slip is exactly 36 BPFO) the fit falls back to the pivoted QR of the
  explicit matrix (:func:`lstsq_qr`), whose rank cut (1e-10) splits
  coincident columns at minimum norm. Above it the normal equations'
  fitted values equal the QR's to 1e-10 of the record (tests); at 2550 Hz,
  f_s 2.5e-3 / T off 36 f0 (A^T A's reciprocal condition 4e-6), they had
  differed by 6e-8 of the 96 V train (the Gauss-Newton f0 by 3e-11 of
  itself), hence the margin. Of 400 random slips in [0, 3%] (1 s records)
  2 fell back at 2550 Hz, none at 25.6 kHz.

The Gauss-Newton step on f0 (:func:`refine_period`) is the last coefficient
of the least squares on [A, dp/df0]; by Frisch-Waugh-Lovell it is
<M d, r> / <M d, M d>, M the projection off the harmonics, r the residual:
one more fit with the same factorisation. :func:`refine_period_qr` is the
same fit with explicit matrices and three pivoted QRs, kept as the reference
of the tests and the benchmark.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
from scipy.linalg import LinAlgError, cho_factor, cho_solve, lstsq
from scipy.linalg.lapack import dpocon

#: Smallest reciprocal condition number of A^T A solved by Cholesky (A's condition number about 100); below: QR.
RCOND_MIN = 1e-4


def frac_cycles(nu, k) -> np.ndarray:
    """nu x k reduced to [-0.5, 0.5) [cycles] for integers k, exact to about 1e-16 for |k| < 2^33 (``nu`` a
    float or an array broadcasting against ``k``).

    nu is split into a 20-bit, a next-20-bit and a rest part: the first two
    products with k are exact in double precision, so the reduction modulo 1
    loses nothing (the plain product loses |nu k| x 1e-16). Larger k fall
    back to the plain product. The reduction v - floor(v) equals
    ``np.mod(v, 1.0)`` bit for bit (v - trunc(v) is exact, and either way one
    rounding of it plus 1 where v < 0).
    """
    k = np.asarray(k, np.int64)
    kf = k.astype(float)
    if k.size and np.abs(k).max() >= 2**33:
        y = nu * kf
    else:
        hi = np.rint(nu * 2.0**20) / 2.0**20
        mid = np.rint((nu - hi) * 2.0**40) / 2.0**40
        a, b = hi * kf, mid * kf
        y = (a - np.floor(a)) + (b - np.floor(b)) + (nu - hi - mid) * kf  # v - floor(v): np.mod(v, 1.0), 4x faster
    return y - np.rint(y)


def chirp_sum(u: np.ndarray, nu, m_out: int) -> np.ndarray:
    """y_m = sum_j u_j exp(2 pi i nu j m), m = 0..m_out - 1 (Bluestein: one FFT convolution) [units of u].

    j m = (j^2 + m^2 - (m - j)^2) / 2, so y_m = c_m sum_j (u_j c_j) conj(c_{m-j}), c_k = exp(i pi nu k^2),
    the chirp's phase nu k^2 / 2 reduced exactly (:func:`frac_cycles`). Batched: ``u`` of shape (P, n) and
    ``nu`` of shape (P,), one sum per row (each row's numbers as alone: the FFTs act per row).
    """
    u = np.asarray(u, complex)
    nu = np.asarray(nu, float)
    nu_col = nu[..., None]
    nj = u.shape[-1]
    length = max(nj, m_out)
    k = np.arange(length, dtype=np.int64)
    c = np.exp(2j * np.pi * frac_cycles(0.5 * nu_col, k * k))
    nfft = scipy.fft.next_fast_len(nj + m_out - 1)
    h = np.zeros(c.shape[:-1] + (nfft,), complex)
    h[..., :m_out] = np.conj(c[..., :m_out])
    if nj > 1:
        h[..., nfft - nj + 1:] = np.conj(c[..., 1:nj])[..., ::-1]
    y = scipy.fft.ifft(scipy.fft.fft(u * c[..., :nj], nfft) * scipy.fft.fft(h))[..., :m_out]
    return y * c[..., :m_out]


def harmonic_matrix(n: int, dt_s: float, f0_Hz: float, n_harmonics: int) -> np.ndarray:
    """Columns 1, cos(2 pi k f0 t), sin(2 pi k f0 t), k = 1..K, at t = i dt [-]."""
    t = np.arange(n) * dt_s
    ph = 2.0 * np.pi * f0_Hz * np.outer(t, np.arange(1, n_harmonics + 1))
    a = np.empty((n, 2 * n_harmonics + 1))
    a[:, 0] = 1.0
    a[:, 1::2] = np.cos(ph)
    a[:, 2::2] = np.sin(ph)
    return a


def lstsq_qr(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Least squares by pivoted QR (rank-revealing: coincident folded harmonics get the minimum-norm split)."""
    return lstsq(a, x, cond=1e-10, lapack_driver="gelsy", check_finite=False)[0]


def gram(n: int, nu, n_harmonics: int) -> np.ndarray:
    """A^T A of :func:`harmonic_matrix` in closed form (nu = f0 dt [cycles per sample]; an array of P: P of
    them, shape (P, 2K + 1, 2K + 1)) [-]."""
    kk = n_harmonics
    m = np.arange(0, 2 * kk + 1, dtype=np.int64)
    nu = np.asarray(nu, float)[..., None]
    a, b = frac_cycles(nu, m), frac_cycles(nu, m * n)
    with np.errstate(divide="ignore", invalid="ignore"):
        geo = np.where(a == 0.0, float(n), np.sin(np.pi * b) / np.sin(np.pi * a) * np.exp(1j * np.pi * (b - a)))
    return gram_from_sums(n, geo.real, geo.imag)  # sum_i cos(2 pi m nu i), sum_i sin(2 pi m nu i)


def gram_from_sums(n: int, sc: np.ndarray, ss: np.ndarray) -> np.ndarray:
    """A^T A of :func:`harmonic_matrix` (K harmonics) from the sums sc_m = sum_i cos(m theta i) and
    ss_m = sum_i sin(m theta i), m = 0..2K, by the product-to-sum identities (leading axes: one matrix each) [-]."""
    sc, ss = np.asarray(sc), np.asarray(ss)
    kk = (sc.shape[-1] - 1) // 2
    k = np.arange(1, kk + 1)
    km, kp = np.abs(k[:, None] - k[None, :]), k[:, None] + k[None, :]
    dm = np.sign(k[:, None] - k[None, :])
    g = np.empty(sc.shape[:-1] + (2 * kk + 1, 2 * kk + 1))
    g[..., 0, 0] = n
    g[..., 0, 1::2], g[..., 0, 2::2] = sc[..., k], ss[..., k]
    g[..., 1::2, 0], g[..., 2::2, 0] = sc[..., k], ss[..., k]
    g[..., 1::2, 1::2] = 0.5 * (sc[..., km] + sc[..., kp])  # cos_j cos_l
    g[..., 2::2, 2::2] = 0.5 * (sc[..., km] - sc[..., kp])  # sin_j sin_l
    g[..., 1::2, 2::2] = 0.5 * (ss[..., kp] - dm * ss[..., km])  # cos_j sin_l = (sin((j+l)) - sin((j-l)))/2
    g[..., 2::2, 1::2] = np.swapaxes(g[..., 1::2, 2::2], -1, -2)
    return g


def cholesky_or_none(g: np.ndarray):
    """scipy's ``cho_factor`` of A^T A where its reciprocal condition number (LAPACK ``dpocon``) is at least
    ``RCOND_MIN``; None where it is ill-posed (fall back to QR)."""
    try:
        cf = cho_factor(g, check_finite=False)
    except LinAlgError:
        return None
    rcond, info = dpocon(cf[0], float(np.abs(g).sum(axis=0).max()))
    return cf if info == 0 and rcond >= RCOND_MIN else None


class Harmonics:
    """Least squares on the harmonics k f0, k = 1..K (and the mean) of n samples at dt.

    Parameters
    ----------
    n : int
    dt_s : float
        Sample step [s].
    f0_Hz : float
        Fundamental [Hz].
    n_harmonics : int
        K [-].
    """

    def __init__(self, n: int, dt_s: float, f0_Hz: float, n_harmonics: int):
        self.n, self.dt_s, self.f0_Hz, self.k = n, dt_s, f0_Hz, n_harmonics
        self.nu = f0_Hz * dt_s
        self.gram = gram(n, self.nu, n_harmonics)
        self.factor, self.matrix = cholesky_or_none(self.gram), None
        if self.factor is None:  # ill-posed: the explicit matrix and the pivoted QR
            self.matrix = harmonic_matrix(n, dt_s, f0_Hz, n_harmonics)

    @property
    def by_qr(self) -> bool:
        """True where the fit falls back to the pivoted QR (A^T A below ``RCOND_MIN``)."""
        return self.factor is None

    def project(self, x: np.ndarray) -> np.ndarray:
        """A^T x [units of x]."""
        d = chirp_sum(np.asarray(x, float), -self.nu, self.k + 1)
        xt = np.empty(2 * self.k + 1)
        xt[0], xt[1::2], xt[2::2] = d[0].real, d[1:].real, -d[1:].imag
        return xt

    def fit(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The least-squares coefficients c (mean, then a_k, b_k of a_k cos + b_k sin) and A^T x [units of x]."""
        xt = self.project(x)
        if self.factor is None:
            return lstsq_qr(self.matrix, np.asarray(x, float)), xt
        return cho_solve(self.factor, xt, check_finite=False), xt

    def synth(self, c: np.ndarray) -> np.ndarray:
        """A c: the periodic signal of coefficients ``c`` on the n samples [units of c]."""
        if self.matrix is not None:
            return self.matrix @ c
        z = np.empty(self.k + 1, complex)
        z[0], z[1:] = c[0], c[1::2] - 1j * c[2::2]
        return chirp_sum(z, self.nu, self.n).real

    def synth_derivative(self, c: np.ndarray) -> np.ndarray:
        """d(A c)/d f0 = t sum_k 2 pi k (b_k cos - a_k sin) [units of c / Hz]."""
        t = np.arange(self.n) * self.dt_s
        w = 2.0 * np.pi * np.arange(1, self.k + 1)
        if self.matrix is not None:
            return t * ((-c[1::2] * w) * self.matrix[:, 2::2] + (c[2::2] * w) * self.matrix[:, 1::2]).sum(axis=1)
        z = np.zeros(self.k + 1, complex)
        z[1:] = 1j * w * (c[1::2] - 1j * c[2::2])
        return t * chirp_sum(z, self.nu, self.n).real


def n_fitted(dt_s: float, f0_Hz: float, alias_folds: float) -> int:
    """Harmonics of the roller-passage fit: every one up to alias_folds / dt, at least those below Nyquist [-]."""
    return max(int(np.floor(alias_folds / dt_s / f0_Hz)), below_nyquist(dt_s, f0_Hz))


def below_nyquist(dt_s: float, f0_Hz: float) -> int:
    """Harmonics of f0 below 0.999 x the Nyquist frequency [-]."""
    return max(int(np.floor(0.5 / dt_s / f0_Hz * 0.999)), 1)


def periodic_part(x: np.ndarray, dt_s: float, f0_Hz: float, alias_folds: float = 1.0) -> np.ndarray:
    """The record's f0-periodic part [V]: least squares on every harmonic of f0 up to alias_folds / dt.

    On the sample grid a harmonic above Nyquist is a folded line in the
    band; near-coincident folds make the problem ill-conditioned, where
    :class:`Harmonics` falls back to the pivoted QR.
    """
    x = np.asarray(x, float)
    h = Harmonics(x.size, dt_s, f0_Hz, n_fitted(dt_s, f0_Hz, alias_folds))
    return h.synth(h.fit(x)[0])


def refine_period(x: np.ndarray, dt_s: float, f0_Hz: float, alias_folds: float = 1.0) -> tuple[float, np.ndarray]:
    """One Gauss-Newton step on f0 of the periodic fit, then the fit: (f0 [Hz], the periodic part [V]).

    The DTFT peak of a few lines is biased by their windows' leakage (a
    slip error of about 4e-9 leaves 1e-4 V of a 96 V roller train in the
    residual: structure a DAQ's micro-volt noise does not hide). The
    periodic model p = A c has d = dp/df0 = sum_k 2 pi k t (-a_k sin + b_k cos);
    the step is the coefficient of d in the least squares on [A, d]:
    <M d, r> / <M d, M d> (Frisch-Waugh-Lovell; M d = d less its own fit).
    Where the start's fit is ill-posed (:class:`Harmonics` falls back to QR)
    or |M d|^2 < 1e-6 |d|^2, the whole step is :func:`refine_period_qr`'s:
    at f_s = 36 f0 exactly (the paper's clock without slip) the FWL step on
    the minimum-norm split of coincident harmonics was noise (+-0.003 Hz
    where the QR method's is 2e-8 Hz) and called healthy records at a DAQ's
    micro-volt noise outer-race faults (3 of 10 seeds,
    ``tests/test_signals_detector_stages.py``).
    """
    x = np.asarray(x, float)
    k = n_fitted(dt_s, f0_Hz, alias_folds)
    h = Harmonics(x.size, dt_s, f0_Hz, k)
    if h.by_qr:  # near-coincident folds: the QR method throughout (its rank cut also decides the step)
        return refine_period_qr(x, dt_s, f0_Hz, alias_folds)
    c, _ = h.fit(x)
    r = x - h.synth(c)
    d = h.synth_derivative(c)
    md = d - h.synth(h.fit(d)[0])
    den = float(md @ md)
    if not den > 1e-6 * float(d @ d):  # d almost in the harmonics' span: the step is ill-posed, as above
        return refine_period_qr(x, dt_s, f0_Hz, alias_folds)
    step = float(md @ r) / den
    if abs(step) < 0.5 / (x.size * dt_s * k):  # within the linear range (half a cycle of the top harmonic over the record)
        f0_Hz += step
    h = Harmonics(x.size, dt_s, f0_Hz, k)
    return f0_Hz, h.synth(h.fit(x)[0])


def refine_period_qr(x: np.ndarray, dt_s: float, f0_Hz: float, alias_folds: float = 1.0) -> tuple[float, np.ndarray]:
    """:func:`refine_period` with explicit matrices and three pivoted QRs (13 s of CPU per record at
    25.6 kHz); the reference of the tests and ``benchmarks/bench_detector.py``."""
    x = np.asarray(x, float)
    k = n_fitted(dt_s, f0_Hz, alias_folds)
    a = harmonic_matrix(x.size, dt_s, f0_Hz, k)
    c = lstsq_qr(a, x)
    t = np.arange(x.size) * dt_s
    w = 2.0 * np.pi * np.arange(1, k + 1)
    deriv = t * ((-c[1::2] * w) * a[:, 2::2] + (c[2::2] * w) * a[:, 1::2]).sum(axis=1)
    step = float(lstsq_qr(np.column_stack([a, deriv]), x)[-1])
    if abs(step) < 0.5 / (x.size * dt_s * k):
        f0_Hz += step
    a = harmonic_matrix(x.size, dt_s, f0_Hz, k)
    return f0_Hz, a @ lstsq_qr(a, x)


def harmonic_fit(x: np.ndarray, dt_s: float, f0_Hz: float, n_harmonics: int) -> tuple:
    """Least squares of ``x`` [V] on :func:`harmonic_matrix`'s columns by the normal equations in closed form:
    (coefficients c [V], A^T A [-], A^T x [V]); the residual sum of squares is x^T x - c^T A^T x.

    O(n log n + K^3) instead of the O(n K^2) of a QR of A, so that the
    outer-race test can evaluate its statistic at many trial f0; the result
    equals the QR solution to rounding (test). :func:`harmonic_fits` of one record.
    """
    c, g, xt = harmonic_fits(np.asarray(x, float)[None, :], dt_s, np.array([f0_Hz], float), n_harmonics)
    return c[0], g[0], xt[0]


#: Largest number of complex entries of one batch of :func:`harmonic_fits` (chirps and Gram matrices): 64 MB.
BATCH_ENTRIES = 4_000_000


def harmonic_fits(x: np.ndarray, dt_s: float, f0_Hz: np.ndarray, n_harmonics: int) -> tuple:
    """:func:`harmonic_fit` of each row of ``x`` (P, n) [V] at its own fundamental ``f0_Hz`` (P,) [Hz]:
    (c (P, 2K + 1) [V], A^T A (P, 2K + 1, 2K + 1) [-], A^T x (P, 2K + 1) [V]).

    The Gram matrices and the records' DTFTs (:func:`chirp_sum`) as arrays over the rows, in batches of at most
    ``BATCH_ENTRIES``; each row's Cholesky solve (or, ill-posed, its pivoted QR) as :class:`Harmonics` does it.
    Each row's numbers are those of the row alone (the per-row FFTs and elementwise arithmetic are the same).
    """
    x = np.asarray(x, float)
    f0 = np.asarray(f0_Hz, float)
    p, n = x.shape
    kk = n_harmonics
    m = 2 * kk + 1
    c, g, xt = np.empty((p, m)), np.empty((p, m, m)), np.empty((p, m))
    step = max(1, BATCH_ENTRIES // (2 * n + m * m))
    for lo in range(0, p, step):
        sl = slice(lo, min(lo + step, p))
        nu = f0[sl] * dt_s
        g[sl] = gram(n, nu, kk)
        d = chirp_sum(x[sl], -nu, kk + 1)
        xt[sl, 0], xt[sl, 1::2], xt[sl, 2::2] = d[:, 0].real, d[:, 1:].real, -d[:, 1:].imag
    for i in range(p):
        cf = cholesky_or_none(g[i])
        if cf is None:  # ill-posed: the explicit matrix and the pivoted QR
            c[i] = lstsq_qr(harmonic_matrix(n, dt_s, float(f0[i]), kk), x[i])
        else:
            c[i] = cho_solve(cf, xt[i], check_finite=False)
    return c, g, xt
