"""``sensitivity_drift``: the sensor's gain changes along the record.

Physics
-------
The charge constant of soft PZT rises with temperature (of order
+0.1-0.4 %/K near room temperature; the figure varies between materials and
is not known for this disk), and a DAQ or charge-amplifier gain drifts while
it warms up. A fixture warmed by a hand, a lamp or the press itself then
makes the same force give a voltage that grows (or falls) along the record:
every impulse fits with a different gain, and the misfit grows towards both
ends of the record.

Model
-----
The voltage across the electrodes is multiplied by
g(t) = 1 + s (t - t_mid), t_mid the middle of the record (so that s alone
cannot mimic a constant d33 error), before the DAQ. The carried force noise
is scaled by the same g(t): its rms over the record, sqrt(mean g^2), on the
noise path (``response``) and g(t) itself as the noise envelope.

Parameter: ``sensitivity_slope_per_s`` (s) in [-0.01, 0.01] 1/s.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord


def gain(values: dict, record: ForceRecord, size: int) -> np.ndarray:
    """g(t) at the ``size`` samples of a voltage that ends with the record (padding before it) [-]."""
    t = record.time_s - 0.5 * (record.time_s[0] + record.time_s[-1])
    pad = max(size - record.n, 0)
    t = np.concatenate([np.full(pad, t[0]), t])
    return 1.0 + values["sensitivity_slope_per_s"] * t


class SensitivityDrift(Effect):
    name = "sensitivity_drift"
    title = "gain changing along the record"
    order = 30
    example = {"sensitivity_slope_per_s": 2e-3}
    example_reason = (
        "a gain rising by 5% over a 25 s record: chosen detectable at the default noise, larger than a typical thermal drift over 25 s"
    )
    physics = (
        "The sensitivity changes along the record (d33 of soft PZT rises by ~0.1-0.4 %/K; DAQ gains drift "
        "while warming up): the voltage is multiplied by 1 + s (t - t_mid), so impulses late in the record "
        "come out larger (s > 0) or smaller than early ones."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        return [
            Param(
                "sensitivity_slope_per_s",
                0.0,
                -0.01,
                0.01,
                scale=1e-4,
                description="relative change of the sensitivity per second [1/s]",
            )
        ]

    def voltage(self, voltage_V, values, record):
        if values["sensitivity_slope_per_s"] == 0:
            return voltage_V
        return voltage_V * gain(values, record, voltage_V.size)

    def response(self, values, record):
        if values["sensitivity_slope_per_s"] == 0:
            return 1.0
        return float(np.sqrt(np.mean(gain(values, record, record.n) ** 2)))

    def noise_envelope(self, values, record):
        if values["sensitivity_slope_per_s"] == 0:
            return None
        return gain(values, record, record.n)

    def summary(self, values):
        s = values["sensitivity_slope_per_s"]
        return f"sensitivity slope = {s * 100:+.3f} %/s"


EFFECT = SensitivityDrift()
