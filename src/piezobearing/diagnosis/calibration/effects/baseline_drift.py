"""``baseline_drift``: a slow additive drift of the voltage.

Physics
-------
PZT is pyroelectric (p of about 4e-4 C/(m^2 K) for PZT-5A): a hand or a rod
warming the disk drives a current p A dT/dt through R, i.e. a voltage
R p A dT/dt. With A = 17.3 mm^2 and R = 50 MOhm, a warming of 0.1 K/s gives
about 35 mV that follows the slow temperature history. Amplifier offsets
and thermal EMFs add a constant or slowly varying term. Against the
impulses (about a second) these are smooth over the whole record.

Model
-----
A Legendre series of degree 3 over the record (x from -1 at its start to
+1 at its end):

.. math::  V_{drift}(t) = \\sum_{k=0}^{3} c_k P_k(x(t)).

Additive: it does not change the response. Start values: linear least
squares of the current residual.

Parameters: ``drift_p0_V`` ... ``drift_p3_V`` in [-10, 10] V.
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import legendre

from ...params import Param
from .base import Effect, ForceRecord, StartContext

DEGREE = 3


def basis(record: ForceRecord) -> np.ndarray:
    """Legendre polynomials P_0..P_3 over the record [-]."""
    t = record.time_s
    x = 2 * (t - t[0]) / (t[-1] - t[0]) - 1
    return legendre.legvander(x, DEGREE)


class BaselineDrift(Effect):
    name = "baseline_drift"
    title = "slow additive drift (pyroelectric/thermal)"
    order = 310
    example = {"drift_p0_V": 0.005, "drift_p1_V": 0.02, "drift_p2_V": -0.01, "drift_p3_V": 0.005}
    example_reason = (
        "pyroelectric current p A dT/dt through R: 0.1 K/s of warming gives ~35 mV at 50 MOhm; a 20 mV linear term with offset and curvature"
    )
    additive_only = True
    physics = (
        "PZT is pyroelectric: a hand or rod warming the disk drives a current p A dT/dt through R (about "
        "35 mV for 0.1 K/s at R = 50 MOhm), and offsets and thermal EMFs add to it. The model adds a smooth "
        "curve (Legendre polynomials to degree 3 over the record) to the voltage."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                f"drift_p{k}_V",
                0.0,
                -10.0,
                10.0,
                scale=1e-3,
                description=f"Legendre coefficient {k} of the drift [V]",
            )
            for k in range(DEGREE + 1)
        ]

    def additive(self, values, record):
        c = np.array([values[f"drift_p{k}_V"] for k in range(DEGREE + 1)])
        return basis(record) @ c

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        coef, *_ = np.linalg.lstsq(basis(ctx.record), ctx.residual_V, rcond=None)
        return [{f"drift_p{k}_V": float(np.clip(c, -10, 10)) for k, c in enumerate(coef)}]

    def summary(self, values):
        import math

        span = 2 * math.sqrt(sum(values[f"drift_p{k}_V"] ** 2 for k in range(1, DEGREE + 1)))
        return f"offset = {values['drift_p0_V'] * 1e3:.2f} mV, drift of the order of {span * 1e3:.2f} mV"


EFFECT = BaselineDrift()
