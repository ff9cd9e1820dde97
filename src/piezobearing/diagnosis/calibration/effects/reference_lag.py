"""``reference_lag``: a first-order lag of the reference force sensor.

Physics
-------
The piezoresistive reference (FlexiForce) and its conditioning and USB
electronics do not follow the force instantly: their reading is the true
force through a first-order lag of time constant tau_r (a few to a few tens
of milliseconds for a slow logger with its anti-alias filter), while the
PZT responds without delay. Compared with the recorded force the voltage
therefore leads: it is the RC response to the force *before* the lag,

.. math::  F_{true} = F_{rec} + \\tau_r \\dot F_{rec}.

Unlike a pure delay (``channel_delay``), a lag also rounds the recorded
force: the two differ at second order in w tau_r, which tells them apart.

Model
-----
The lag can only be undone where the recorded force has content; above
that band the recorded force is noise and a lead would only amplify it
into the residual. The model therefore leads the recorded force within its
band f_b (:func:`~piezobearing.diagnosis.calibration.effects.base.force_band_Hz`, where the force
spectrum stands 10x above its noise) with the zero-phase response

.. math::  1 + j\\,2\\pi f\\,\\tau_r\\,W(f),\\qquad W(f) = \\frac{1}{1 + (f/f_b)^8},

exact (to (f/f_b)^8) inside the band and 1 well above it. f_b is a
property of the record (a few to 15 Hz for hand presses), not a fitted
parameter; the synthesis uses the same record's band.

Parameter: ``lag_tau_s`` in [1e-5, 0.1] s (log scale).
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord, StartContext, fd_filter, force_band_Hz
from .channel_delay import best_lag_s

ORDER = 8


def lead(f_Hz: np.ndarray, tau_s: float, band_Hz: float) -> np.ndarray:
    """Band-limited lead 1 + j 2 pi f tau W(f) [-]."""
    f = np.asarray(f_Hz, dtype=float)
    return 1.0 + 2j * np.pi * f * tau_s / (1.0 + (f / band_Hz) ** ORDER)


class ReferenceLag(Effect):
    name = "reference_lag"
    title = "first-order lag of the reference sensor"
    order = 10
    example = {"lag_tau_s": 0.010}
    example_reason = (
        "a slow USB force logger with its anti-alias filter: a 10 ms lag (16 Hz corner)"
    )
    physics = (
        "The reference force sensor and its electronics read the force through a first-order lag tau_r, "
        "while the PZT responds at once: the voltage leads the recorded force. The model drives the circuit "
        "with F_rec + tau_r dF_rec/dt within the force's band (zero-phase). A lag differs from a pure delay "
        "at second order in w tau_r (it also rounds the force)."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "lag_tau_s",
                1e-5,
                1e-5,
                0.1,
                log=True,
                description="time constant of the reference sensor's lag [s]",
            )
        ]

    def force(self, force_N, values, record):
        fs, band, tau = record.sample_rate_Hz, force_band_Hz(record), values["lag_tau_s"]
        return fd_filter(force_N, lambda k: lead(k * fs, tau, band), int(4 * fs / band))

    def response(self, values, record):
        return lead(record.freq_Hz, values["lag_tau_s"], force_band_Hz(record))

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        """Off, and the lead of the measured voltage over the current model (cross-correlation), if any."""
        lead = -best_lag_s(ctx)
        on = lead if lead >= 2 * ctx.record.dt_s else 3e-3
        return [{"lag_tau_s": 1e-5}, {"lag_tau_s": float(np.clip(on, 1e-4, 0.05))}]

    def summary(self, values):
        return f"tau_r = {values['lag_tau_s'] * 1e3:.3g} ms"


EFFECT = ReferenceLag()
