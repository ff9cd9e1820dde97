"""``shaft_speed``: the shaft turns at a speed outside the tolerance the baseline allows.

Physics
-------
The speed the user believes (a motor's nameplate, a setpoint) can be off by
more than the drive's tolerance: a loaded induction motor slips, a belt
drive has its own ratio, a tachometer's pulses per turn are miscounted.
Every bearing frequency scales with it.

Model
-----
f_r = f_r,0 (1 + e), with f_r,0 the nominal speed (``bearing.shaft_speed_rpm``)
or the tachometer's record, and e free. With this effect in the model the
baseline's nuisance speed (free within ``bearing_diagnosis.speed_tolerance_ratio``)
is held at the nominal speed: both free would be one product, a valley the
fit wanders along (it spent 400 evaluations there on a 2 s record) and no
interval of e. The start e comes from the strongest line within +-50% of
the nominal BPFO in the record.

Parameter: ``speed_deviation_ratio`` in [-0.5, 0.5] (0: the nominal speed).
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect


def roller_pass_line_Hz(v: np.ndarray, dt_s: float, bpfo_Hz: float, half_width: float) -> float:
    """Frequency of the strongest spectral line within bpfo (1 +- half_width) [Hz] (Hann, zero-padded x8)."""
    x = np.asarray(v, dtype=float) - np.mean(v)
    nfft = 8 * int(2 ** np.ceil(np.log2(x.size)))
    p = np.abs(np.fft.rfft(x * np.hanning(x.size), nfft)) ** 2
    f = np.fft.rfftfreq(nfft, dt_s)
    sel = np.flatnonzero(np.abs(f - bpfo_Hz) <= half_width * bpfo_Hz)
    return float(f[sel[np.argmax(p[sel])]])


class ShaftSpeed(Effect):
    name = "shaft_speed"
    title = "shaft speed outside its tolerance"
    example = {"speed_deviation_ratio": 0.05}
    example_reason = (
        "5% off the nominal speed: an induction motor's slip under load is a few percent, or the drive runs at "
        "another set point than believed"
    )
    physics = (
        "The shaft turns at another speed than believed (motor slip, belt ratio, a miscounted tachometer): "
        "every bearing frequency scales with it."
    )

    def params(self, record) -> list[Param]:
        return [Param("speed_deviation_ratio", 0.0, -0.5, 0.5, scale=0.005, description="relative speed error [-]")]

    holds = ("shaft_speed_Hz",)

    def starts(self, ctx):
        rig = ctx.record.rig
        fr = rig.shaft_speed_Hz
        slip = ctx.values.get("cage_slip_ratio", 0.0)
        bpfo = rig.frequencies(fr, slip)["bpfo_Hz"]
        f = roller_pass_line_Hz(ctx.voltage_V, ctx.record.dt_s, bpfo, 0.5)
        return [{"speed_deviation_ratio": float(np.clip(f / bpfo - 1.0, -0.49, 0.49))}]

    def summary(self, values):
        return f"speed {100 * values['speed_deviation_ratio']:+.2f}% off the nominal"


EFFECT = ShaftSpeed()
