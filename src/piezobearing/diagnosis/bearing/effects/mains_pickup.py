"""``mains_pickup``: interference at the mains frequency and its odd harmonics, on a running rig.

Physics
-------
As on the calibration bench (:mod:`piezobearing.diagnosis.calibration.effects.mains_pickup`,
whose model and start values this effect uses): the PZT is a high-impedance
source, and on a rig the motor and its drive sit next to the sensor's lead,
so 50 or 60 Hz and odd harmonics add to the voltage, whatever the bearing does.

Parameters: ``mains_frequency_Hz`` in [49.5, 60.5] Hz; ``mains_h{k}_cos_V``,
``mains_h{k}_sin_V`` in [-100, 100] V for the odd harmonics below 0.49 f_s.
"""

from __future__ import annotations

from dataclasses import replace

from ...calibration.effects import mains_pickup
from .base import Effect


def _calib():
    """The calibration subject's mains effect (imported when used: the two catalogues stay independent)."""
    return mains_pickup.EFFECT


class MainsPickup(Effect):
    name = "mains_pickup"
    title = "mains interference (50/60 Hz + odd harmonics)"
    example = {"mains_frequency_Hz": 50.02, "mains_h1_cos_V": 3.0, "mains_h1_sin_V": 3.0}
    example_reason = (
        "4.2 V at 50.02 Hz: a high-impedance PZT beside the motor and its drive picks up volts of mains field, "
        "beside a rig voltage that swings tens of volts"
    )
    physics = (
        "The PZT is a high-impedance source next to the motor and its drive: the mains field at 50 or 60 Hz "
        "and its odd harmonics add to the voltage, whatever the bearing does."
    )

    def params(self, record):
        """The calibration effect's parameters, the amplitudes' bounds widened to +-100 V (a running rig's
        voltage swings tens of volts, the calibration's millivolts)."""
        return [
            replace(p, lower=-100.0, upper=100.0) if p.name.endswith("_V") else p for p in _calib().params(record)
        ]

    def additive(self, values, record):
        return _calib().additive(values, record)

    def starts(self, ctx):
        return _calib().starts(ctx)

    def summary(self, values):
        return _calib().summary(values)


EFFECT = MainsPickup()
