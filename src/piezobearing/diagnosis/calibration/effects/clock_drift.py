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

import numpy as np

from ...params import Param
from .base import Effect, ForceRecord

#: Half-length [samples] and Kaiser beta of the interpolation kernel.
HALF, BETA = 16, 6.0
#: Samples interpolated at once: the kernel's (samples x 2 HALF) arrays stay ~1 MB each for any record length.
CHUNK = 1 << 12


def kernel(frac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Taps m = -HALF+1..HALF and weights h[k, m] of the windowed sinc reading at k0 + frac[k]."""
    m = np.arange(-HALF + 1, HALF + 1)
    t = np.asarray(frac, dtype=float)[:, None] - m[None, :]
    win = np.i0(BETA * np.sqrt(np.clip(1 - (t / HALF) ** 2, 0, None))) / np.i0(BETA)
    h = np.sinc(t) * win
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


def noise_gain(f_per_sample: np.ndarray, epsilon: float, n: int, k: int = 16) -> np.ndarray:
    """sqrt(mean over the record of |H_mu(f)|^2): the kernel's rms response at the record's offsets [-].

    ``k`` offsets mu = frac(epsilon j) at evenly spaced samples j of the record.
    """
    shift = epsilon * np.linspace(0, n - 1, k)
    m, h = kernel(shift - np.floor(shift))
    f = np.asarray(f_per_sample, dtype=float)
    out = np.empty(f.shape)
    for a in range(0, f.size, CHUNK):  # (taps x frequencies) complex arrays, a chunk at a time
        e = np.exp(-2j * np.pi * np.outer(m, f[a : a + CHUNK]))
        out[a : a + CHUNK] = np.sqrt(np.mean(np.abs(h @ e) ** 2, axis=0))
    return out


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
        return 1.0 if e == 0 else noise_gain(record.freq_Hz * record.dt_s, e, record.n)

    def summary(self, values):
        e = values["clock_drift_ppm"]
        return f"clock drift = {e:.1f} ppm ({e * 1e-3:.3f} ms per s, voltage {'later' if e >= 0 else 'earlier'})"


EFFECT = ClockDrift()
