"""``d33_scale``: the charge constant differs from the datasheet by a factor.

Physics
-------
The d33 of a soft PZT disk scatters by +-10-20% between batches (datasheet
tolerance), falls with ageing (a few % per decade of time) and after a
depoling excursion (heat, a large reverse field), so the configured
d33 = 400 pC/N can be off by a factor k of 0.8-1.2. The charge is
q = k d33 F, so every impulse scales by k while tau = RC stays.

Exact equivalence
-----------------
The RC circuit's response H(s) = k d33 R s / (1 + s R C) depends on
k d33, R and C only through two combinations: R k d33 (the response below
the corner, 1/(2 pi R C)) and k d33 / C (the gain above it). A record
therefore determines R d33 and d33/C (and tau = RC, their ratio); it
cannot separate d33, C and R. Once R refits, a d33 scaled by k is the same
record as ``extra_capacitance`` dC = C (1/k - 1) with R scaled by k
(k = 0.85 at C = 261 pF: dC = +46 pF, R 15% low), and the diagnosis says
so instead of choosing. The force-noise response is the same H, so the
noise floors are identical too.

Model
-----
The circuit's d33 (``SensorCircuit.d33_C_per_N``) times ``d33_scale_ratio``.

Parameter: ``d33_scale_ratio`` in [0.5, 1.5] (neutral 1).
"""

from __future__ import annotations

from dataclasses import replace

from ....fitting.params import Param
from .base import Effect, ForceRecord

EQUIVALENCE = (
    "exactly equivalent on any record: the RC response k d33 R s / (1 + s R C) fixes only R d33 and d33/C "
    "(hence tau = RC); d33, C and R are not separately determined. A d33 scaled by k is the same record as "
    "an extra capacitance dC = C (1/k - 1) with R scaled by k; calibrate C (or d33) independently to tell them apart"
)


class D33Scale(Effect):
    name = "d33_scale"
    title = "d33 off the datasheet by a factor"
    order = 110
    example = {"d33_scale_ratio": 0.85}
    example_reason = (
        "d33 15% below the datasheet: batch tolerance (+-10-20%) and ageing"
    )
    physics = (
        "The charge constant of the disk differs from the configured d33 by a factor k (batch tolerance, "
        "ageing, partial depoling): every impulse scales by k, tau = RC stays. Once R refits this is exactly "
        "the record of an extra capacitance C (1/k - 1): a record determines R d33 and d33/C only."
    )
    equivalent_to = {"extra_capacitance": EQUIVALENCE}

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "d33_scale_ratio",
                1.0,
                0.5,
                1.5,
                scale=0.01,
                description="d33 over its configured value [-]",
            )
        ]

    def circuit(self, circuit, values):
        return replace(circuit, d33_C_per_N=circuit.d33_C_per_N * values["d33_scale_ratio"])

    def summary(self, values):
        return f"d33 x {values['d33_scale_ratio']:.4f}"


EFFECT = D33Scale()
