"""The record on the roller-passage clock: the passage phase measured on the record, the record resampled on it.

Why. A cage that slips by a new amount at every roller passage (``bearing.slip_jitter``) lets the passage
times wander: at 2% jitter per passage the n-th passage is off its mean time by 0.02 sqrt(n) periods, a fifth of
a period after a second. The baseline detector's fold and roller-passage fit assume a constant period
(:mod:`.baseline`); the smeared train then no longer matches the healthy baseline's harmonics and an impact no
longer falls in the same cell of the fold (docs/validation/detection.md: the limit lies between 1% and 2% jitter).

What. The sensor sees every roller pass, so the record carries its own tachometer: the roller train's
fundamental. :func:`passage_phase` demodulates the record at the mean BPFO and smooths the product over one
period twice (a triangle two periods wide: it suppresses the train's harmonics, which land on multiples of
BPFO); the unwrapped angle, refined by Gauss-Newton steps on the whole waveform, is the passage phase theta(t)
[cycles] up to a constant. :func:`on_passage_clock`
resamples the record at the instants where theta is uniform (the order-tracking step, with the record's own
phase instead of a shaft encoder's) by a Kaiser-windowed sinc, which keeps white noise nearly white with its variance (the sum of the squared weights is 1 on the grid and 0.938 half-way between samples: test). On that clock
the roller train is periodic again: the baseline detector's roller-passage fit and rolling-element fold (2 BSF
turns with the cage: a fixed multiple of theta) run unchanged, and the inner-race fold follows its own phase,
Z f_shaft t - theta (the defect turns with the shaft, at constant speed on the record's clock). The outer-race
test stays on the record's clock (the phase's own noise smears the resampled train; docs/theory/detection.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Half-width of the resampling kernel [samples] and its Kaiser window's beta.
HALF_WIDTH = 16
KAISER_BETA = 8.0


def _smooth(y: np.ndarray, m: int) -> np.ndarray:
    """``y`` through a centred moving average of ``m`` samples, twice (a triangle of 2m - 1), the ends on the
    samples there are."""
    k = np.ones(m)
    for _ in range(2):
        num = np.convolve(y, k, mode="same")
        den = np.convolve(np.ones(y.size), k, mode="same")
        y = num / den
    return y


def passage_phase(x: np.ndarray, dt_s: float, f0_Hz: float, n_refine: int = 3) -> np.ndarray:
    """The roller-passage phase theta(t_i) [cycles] of the record ``x`` [V] (sample step ``dt_s`` [s]) whose
    roller train runs at about ``f0_Hz`` [Hz] (BPFO at the mean slip). Defined up to a constant.

    First the fundamental's phase: f0 t plus the unwrapped angle of the record demodulated at f0 and smoothed
    over one period twice, over 2 pi. Then ``n_refine`` Gauss-Newton steps with the whole waveform: the train's
    shape w(theta) (least squares on the harmonics of theta below Nyquist, the record's own) and the local
    shift d theta = S(r w') / S(w'^2), r = x - w(theta), S the same smoothing. On the synthetic 96 V roller
    bumps at the paper's 10 dB the fundamental alone leaves 0.0105 cycle rms, the waveform 0.0045.

    Raises
    ------
    ValueError
        Where theta does not increase over the record (no roller train to follow: too much noise).
    """
    x = np.asarray(x, float)
    t = np.arange(x.size) * dt_s
    m = max(int(round(1.0 / (f0_Hz * dt_s))), 1)
    y = x - x.mean()
    theta = f0_Hz * t + np.unwrap(np.angle(_smooth(y * np.exp(-2j * np.pi * f0_Hz * t), m))) / (2.0 * np.pi)
    k = np.arange(1, max(int(np.floor(0.5 / (dt_s * f0_Hz) * 0.999)), 1) + 1)
    for _ in range(n_refine):
        ph = 2.0 * np.pi * np.outer(theta, k)
        a = np.column_stack([np.ones(x.size), np.cos(ph), np.sin(ph)])
        c = np.linalg.lstsq(a, x, rcond=None)[0]
        w = a @ c
        dw = (np.sin(ph) * (-2.0 * np.pi * k * c[1:k.size + 1]) + np.cos(ph) * (2.0 * np.pi * k * c[k.size + 1:])).sum(1)
        theta = theta + _smooth((x - w) * dw, m) / _smooth(dw * dw, m)
    if not np.all(np.diff(theta) > 0.0):
        raise ValueError("the roller-passage phase does not increase over the record: the roller train is "
                         "lost in the noise; set signals.detector.follow_passage_phase to false")
    return theta


def kernel_weights(frac: np.ndarray, half_width: int = HALF_WIDTH, beta: float = KAISER_BETA) -> np.ndarray:
    """Weights of the samples i0 - H + 1 .. i0 + H for a point at i0 + ``frac`` (0 <= frac < 1): a sinc
    under a Kaiser window of half-width H, shape (len(frac), 2H)."""
    j = np.arange(-half_width + 1, half_width + 1)
    d = np.asarray(frac, float)[:, None] - j[None, :]
    return np.sinc(d) * _kaiser(d / half_width, beta)


def _kaiser(u: np.ndarray, beta: float) -> np.ndarray:
    """The Kaiser window at u in [-1, 1] (0 outside)."""
    return np.where(np.abs(u) < 1.0, np.i0(beta * np.sqrt(np.clip(1.0 - u * u, 0.0, None))) / np.i0(beta), 0.0)


@dataclass(frozen=True)
class PassageClock:
    """A record resampled where its roller-passage phase is uniform.

    Attributes
    ----------
    voltage_V : ndarray
        The record at the new instants [V], one sample per ``dt_s`` of passage-clock time.
    time_s : ndarray
        The instants of the original record's clock at which it was sampled [s].
    f0_Hz : float
        The mean roller-passage rate [Hz]: theta advances f0 dt per sample.
    theta : ndarray
        The passage phase at those instants [cycles] (uniform).
    """

    voltage_V: np.ndarray
    time_s: np.ndarray
    f0_Hz: float
    theta: np.ndarray


def on_passage_clock(x: np.ndarray, dt_s: float, f0_Hz: float) -> PassageClock:
    """The record ``x`` [V] resampled at the instants where its passage phase (:func:`passage_phase`) is
    uniform, one sample per ``dt_s`` [s] at the mean passage rate; the first and last ``HALF_WIDTH`` samples
    (the kernel's reach) are left out."""
    x = np.asarray(x, float)
    theta = passage_phase(x, dt_s, f0_Hz)
    t = np.arange(x.size) * dt_s
    lo, hi = HALF_WIDTH * dt_s, (x.size - 1 - HALF_WIDTH) * dt_s
    th_lo, th_hi = np.interp([lo, hi], t, theta)
    rate = (theta[-1] - theta[0]) / (t[-1] - t[0])  # mean passage rate [cycles/s]
    n = int(np.floor((th_hi - th_lo) / (rate * dt_s))) + 1
    th = th_lo + rate * dt_s * np.arange(n)
    tj = np.interp(th, theta, t)
    u = tj / dt_s
    i0 = np.floor(u).astype(int)
    w = kernel_weights(u - i0)
    idx = np.clip(i0[:, None] + np.arange(-HALF_WIDTH + 1, HALF_WIDTH + 1)[None, :], 0, x.size - 1)
    return PassageClock(np.einsum("ij,ij->i", w, x[idx]), tj, float(rate), th)
