"""``d33_nonlinearity``: a stress-dependent charge constant.

Physics
-------
Soft PZT (APC 850 is a PZT-5A type) gains charge constant under
compressive stress: domain-wall motion adds an extrinsic part that grows
with stress, so the charge is not exactly d33 F. To second order

.. math::  q = d_{33} (F + \\beta F^2),

i.e. the small-signal sensitivity d33 (1 + 2 beta F) rises with the
force. Over the 4.7 mm disk 15 N is 0.9 MPa; under a rod tip the contact
stress is locally several times higher. Bigger impulses then give
proportionally more voltage than smaller ones, which a linear model
cannot follow whatever R.

Model
-----
The circuit is driven by F + beta F^2 (the recorded force on the disk).
The force noise reaches the voltage with the small-signal gain
1 + 2 beta F(t): its rms sqrt(mean((1 + 2 beta F)^2)) on the noise path
(``response``) and its shape along the record (``noise_envelope``, F the
denoised recorded force), so the residual is allowed to be louder at the
press peaks by as much as the model says.

Parameter: ``beta_per_N`` in [-0.05, 0.05] 1/N.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord, denoised_force


class D33Nonlinearity(Effect):
    name = "d33_nonlinearity"
    title = "stress-dependent d33"
    order = 50
    example = {"beta_per_N": 1.5e-3}
    example_reason = (
        "+3% sensitivity at 10 N: soft PZT gains ~1%/MPa under compression and a rod tip concentrates the 0.6 MPa mean stress several-fold; FlexiForce's own linearity error (+-3% FS) looks the same"
    )
    physics = (
        "Under compressive stress soft PZT gains charge constant (domain-wall motion), so the charge is "
        "d33 (F + beta F^2) and the sensitivity d33 (1 + 2 beta F) grows with the force: larger impulses "
        "give relatively more voltage, which no R can reproduce."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "beta_per_N",
                0.0,
                -0.05,
                0.05,
                scale=1e-3,
                description="quadratic coefficient of the charge, q = d33 (F + beta F^2) [1/N]",
            )
        ]

    def force(self, force_N, values, record):
        return force_N + values["beta_per_N"] * force_N**2

    def response(self, values, record):
        return float(np.sqrt(np.mean((1 + 2 * values["beta_per_N"] * record.force_N) ** 2)))

    def noise_envelope(self, values, record):
        if values["beta_per_N"] == 0:
            return None
        return 1 + 2 * values["beta_per_N"] * denoised_force(record)

    def summary(self, values):
        b = values["beta_per_N"]
        return f"beta = {b:.3g} 1/N (sensitivity {2000 * b:+.2g}% at 10 N)"


EFFECT = D33Nonlinearity()
