"""``clock_drift``: the voltage DAQ's sample clock runs at a different rate from the force logger's.

Physics
-------
The reference force and the PZT voltage are sampled by two devices, each on
its own quartz clock (tolerance +-20-50 ppm, plus a temperature drift of a
few ppm). Their time stamps are merged assuming both run at the nominal
rate, so the voltage sample stamped t belongs to the force stamped
t (1 + epsilon): an offset that grows linearly along the record,
delta(t) = -epsilon (t - t0). 100 ppm gives 2.5 ms at the end of a 25 s
record; against tau = RC = 13 ms that moves the voltage by delta dV/dt, a
misfit that grows with time (a constant ``channel_delay`` can only take out
its mean).

Model
-----
The force on the disk at voltage sample k (time t_k from the first sample,
the instant both records are aligned at) is the recorded force read at
t_k (1 + epsilon), by Kaiser-windowed sinc interpolation (32 taps,
beta = 6: flat within 1.7% up to 0.45 of the sampling rate; the padding
samples the forward model puts before the record, at the initial force
level, keep their place; reads beyond the last sample hold it). The
interpolation at a fractional offset mu low-passes what it reads near
Nyquist (to 0.47 in power at mu = 0.5 above 0.45 fs), so on the noise path
the carried force noise is scaled by the rms over the record of the
kernel's response, sqrt(mean_k |H_mu_k(f)|^2) (:func:`noise_gain`): a
cubic spline instead, with response 1 assumed, left a correct model
``unexplained`` (lag-1 autocorrelation +0.11 of the whitened residual).

Parameter: ``clock_drift_ppm`` (epsilon in parts per million, > 0: the
voltage clock runs slow, its samples lie later in force time) in
[-1000, 1000] ppm.
"""

from __future__ import annotations

import math

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord

#: Half-length [samples] and Kaiser beta of the interpolation kernel.
HALF, BETA = 16, 6.0
#: Samples interpolated at once: the kernel's (samples x 2 HALF) arrays stay ~1 MB each for any record length.
CHUNK = 1 << 12


def _i0_series(y: np.ndarray) -> np.ndarray:
    """I0(2 sqrt(y)) = sum_k y^k / (k!)^2 by Horner's rule (22 terms: the first left out is below 1e-21
    of the sum for y <= BETA^2 / 4 = 9); numpy's and scipy's i0 take 10-30x longer on the kernel's arrays."""
    p = np.full(y.shape, _I0_TERMS[-1])
    for c in _I0_TERMS[-2::-1]:
        p *= y
        p += c
    return p


#: 1 / (k!)^2, k = 0..21: the Taylor coefficients of :func:`_i0_series`.
_I0_TERMS = np.array([1.0 / math.factorial(k) ** 2 for k in range(22)])


def kernel(frac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Taps m = -HALF+1..HALF and weights h[k, m] of the windowed sinc reading at k0 + frac[k].

    sinc(mu - m) = (-1)^m sin(pi mu) / (pi (mu - m)): one sine a sample; the Kaiser window
    I0(BETA sqrt(1 - (t / HALF)^2)) unscaled (the taps are normalised to sum 1).
    """
    m = np.arange(-HALF + 1, HALF + 1)
    mu = np.asarray(frac, dtype=float)[:, None]
    t = mu - m[None, :]
    win = _i0_series((0.5 * BETA) ** 2 * np.clip(1 - (t / HALF) ** 2, 0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        sinc = np.where(m % 2 == 0, 1.0, -1.0) * np.sin(np.pi * mu) / (np.pi * t)
    h = np.where(t == 0, 1.0, sinc) * win
    return m, h / h.sum(axis=1, keepdims=True)


def drifted(force_N: np.ndarray, epsilon: float, pad: int) -> np.ndarray:
    """The force read at index pad + (j - pad)(1 + epsilon) for each index j >= pad [N]."""
    x = np.asarray(force_N, dtype=float)
    out = np.empty_like(x)
    for a in range(0, x.size, CHUNK):
        j = np.arange(a, min(a + CHUNK, x.size), dtype=float)
        src = np.clip(np.where(j >= pad, pad + (j - pad) * (1.0 + epsilon), j), 0.0, x.size - 1.0)
        k0 = np.floor(src).astype(int)
        m, h = kernel(src - k0)
        out[a : a + j.size] = np.sum(x[np.clip(k0[:, None] + m[None, :], 0, x.size - 1)] * h, axis=1)
    return out


def noise_gain(f_per_sample: np.ndarray, epsilon: float, n: int, k: int = 16,
               cosines: np.ndarray | None = None) -> np.ndarray:
    """sqrt(mean over the record of |H_mu(f)|^2): the kernel's rms response at the record's offsets [-].

    ``k`` offsets mu = frac(epsilon j) at evenly spaced samples j of the record. With the taps h[m],
    |H_mu(f)|^2 = r[0] + 2 sum_d r[d] cos(2 pi d f), r the autocorrelation of h, so the mean over the
    offsets is one cosine series of the mean autocorrelation (2 HALF - 1 terms), evaluated term by term
    (memory: one array of the frequencies; 30x faster than the taps x frequencies complex products).
    ``cosines``: :func:`cosine_table` of ``f_per_sample``, when the caller keeps it (a fit asks at every epsilon).
    """
    shift = epsilon * np.linspace(0, n - 1, k)
    _, h = kernel(shift - np.floor(shift))
    taps = h.shape[1]
    r = np.array([np.mean(np.sum(h[:, d:] * h[:, : taps - d], axis=1)) for d in range(taps)])
    f = np.asarray(f_per_sample, dtype=float)
    cos = cosine_table(f) if cosines is None else cosines
    p = np.full(f.shape, r[0])
    for d in range(1, taps):
        p += 2.0 * r[d] * cos[d - 1]
    return np.sqrt(np.clip(p, 0.0, None))


def cosine_table(f_per_sample: np.ndarray) -> np.ndarray:
    """cos(2 pi d f) for d = 1..2 HALF - 1, one row each: :func:`noise_gain`'s terms [-]."""
    f = np.asarray(f_per_sample, dtype=float)
    return np.array([np.cos(2 * np.pi * d * f) for d in range(1, 2 * HALF)])


class ClockDrift(Effect):
    name = "clock_drift"
    title = "sample-clock rate difference force/voltage"
    order = 25
    example = {"clock_drift_ppm": 100.0}
    example_reason = (
        "two DAQ quartz clocks of +-50 ppm each: 100 ppm apart, 2.5 ms after 25 s"
    )
    physics = (
        "The force logger and the voltage DAQ sample on their own quartz clocks (+-20-50 ppm each); merged "
        "as if both ran at the nominal rate, the voltage stamped t belongs to the force at t (1 + epsilon): "
        "an offset growing along the record (100 ppm: 2.5 ms after 25 s), so the misfit grows in time. The "
        "model reads the recorded force at the drifted times (windowed-sinc interpolation)."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "clock_drift_ppm",
                0.0,
                -1000.0,
                1000.0,
                scale=1.0,
                description="rate of the voltage clock's offset from the force clock [ppm]",
            )
        ]

    def force(self, force_N, values, record):
        e = values["clock_drift_ppm"] * 1e-6
        # the forward model puts force_N.size - record.n padding samples before the record
        return force_N if e == 0 else drifted(force_N, e, max(force_N.size - record.n, 0))

    def response(self, values, record):
        e = values["clock_drift_ppm"] * 1e-6
        if e == 0:
            return 1.0
        if "clock_drift_cosines" not in record._cache:  # the same at every epsilon: kept on the record
            record._cache["clock_drift_cosines"] = cosine_table(record.freq_Hz * record.dt_s)
        return noise_gain(record.freq_Hz * record.dt_s, e, record.n, cosines=record._cache["clock_drift_cosines"])

    def summary(self, values):
        e = values["clock_drift_ppm"]
        return f"clock drift = {e:.1f} ppm ({e * 1e-3:.3f} ms per s, voltage {'later' if e >= 0 else 'earlier'})"


EFFECT = ClockDrift()
