"""``channel_delay``: a time offset between the force and the voltage acquisitions.

Physics
-------
The reference force sensor (FlexiForce with its USB electronics) and the
PZT voltage (Spider-80Xi DAQ) are recorded by two devices that start on
their own clocks. When their time stamps are merged, the voltage sample
stamped t belongs to the force stamped t - delta:

.. math::  V(t) = \\mathcal{M}[F](t - \\delta).

USB start-up latencies and unsynchronised triggers give offsets of a few to
a few tens of milliseconds. delta > 0 means the voltage lags the force
record. Against tau = RC = 13 ms and impulses rising over 0.4 s, an offset
of 15 ms moves the voltage by about delta dV/dt, a sizeable fraction of the
signal.

Model
-----
The recorded force is delayed by a band-limited fractional delay (a phase
ramp exp(-j w delta) on a padded record that holds the first and last
values), before the circuit. The delay is all-pass, so the force noise
carried to the voltage keeps its level (|response| = 1).

Parameter: ``delay_s`` in [-0.1, 0.1] s.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord, StartContext, fd_filter

MAX_DELAY_S = 0.1


def fractional_delay(x: np.ndarray, delay_samples: float) -> np.ndarray:
    """x delayed by a (fractional) number of samples, y[k] = x(k - d), band-limited (see :func:`fd_filter`)."""
    return fd_filter(x, lambda k: np.exp(-2j * np.pi * k * delay_samples), int(np.ceil(abs(delay_samples))))


def best_lag_s(ctx: StartContext) -> float:
    """Lag [s] (within +-0.1 s, whole samples) at which the measured voltage best matches the current model's.

    Positive: the measured voltage comes later than the model's.
    """
    m = int(MAX_DELAY_S / ctx.record.dt_s)
    a = ctx.voltage_V - ctx.voltage_V.mean()
    b = ctx.model_V - ctx.model_V.mean()
    # Imported here: the diagnosis's start only; a job that synthesises records through the catalogue would
    # otherwise pay scipy.signal's second of import (see effects.base.force_band_Hz).
    from scipy.signal import correlate

    c = correlate(a, b, mode="full", method="fft")
    mid = b.size - 1
    return (int(np.argmax(c[mid - m : mid + m + 1])) - m) * ctx.record.dt_s


class ChannelDelay(Effect):
    name = "channel_delay"
    title = "time offset force/voltage channel"
    order = 20
    example = {"delay_s": 0.015}
    example_reason = (
        "two acquisition devices started by hand or over USB: offsets of a few to tens of ms are common"
    )
    physics = (
        "The reference force and the PZT voltage are recorded by two devices on their own clocks; the "
        "voltage stamped t belongs to the force stamped t - delta (delta > 0: the voltage lags). The model "
        "delays the recorded force by delta (band-limited, all-pass) before the circuit. USB latencies and "
        "unsynchronised triggers give a few to a few tens of milliseconds."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "delay_s",
                0.0,
                -MAX_DELAY_S,
                MAX_DELAY_S,
                scale=1e-3,
                description="voltage channel lag behind the force channel [s]",
            )
        ]

    def force(self, force_N, values, record):
        d = values["delay_s"]
        return force_N if d == 0 else fractional_delay(force_N, d / record.dt_s)

    def response(self, values, record):
        return np.exp(-2j * np.pi * record.freq_Hz * values["delay_s"])

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        """No delay, and the lag of the largest cross-correlation of measured and current model voltage."""
        return [{}, {"delay_s": best_lag_s(ctx)}]

    def summary(self, values):
        d = values["delay_s"]
        return f"delay = {d * 1e3:.2f} ms (voltage {'after' if d >= 0 else 'before'} force)"


EFFECT = ChannelDelay()
