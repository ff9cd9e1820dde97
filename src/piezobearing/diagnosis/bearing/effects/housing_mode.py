"""``housing_mode``: a resonance of the housing between the rollers and the sensor, the rung above the shaft's dynamics.

Physics
-------
The chain puts each roller's load on the sensor through the housing's static influence line. A housing has modes:
where one lies inside the DAQ's band (a light or tall housing, a sensor on a bracket), every roller passage and
every groove edge rings it, and the roller passage's harmonics near it are lifted by up to 1 / (2 zeta); above the
band, its ring after each passage, averaged over a DAQ sample, is a short dip after each passage that a narrow
groove under the sensor mimics (docs/validation/bearing_diagnosis.md, "A housing mode inside the band").

Model
-----
The dynamic rung's sensor force, on its fine grid, through one single-degree-of-freedom mode of static gain 1
(:func:`piezobearing.housing.one_mode.through_mode`) before the average over each DAQ sample; it rides on
``shaft_dynamics`` (the fine grid is that rung's: :func:`~piezobearing.diagnosis.bearing.chain.sensor_force`).

Parameters: ``housing_mode_Hz`` (0: off) and ``housing_mode_damping_ratio`` in [0.001, 0.5] (log scale). The
frequency is fitted where it lies below the record's Nyquist frequency (the record holds its ring's lines); above
it, it is held at the rig file's ``bearing_diagnosis.housing_mode_Hz`` (the record sees the mode only through the
samples' average). The damping ratio is fitted from the rig file's ``housing_mode_damping_ratio`` (default 0.02)
or from the best of a scan.

Where a user finds the values: the housing's lowest mode in the direction of the load, from an impact test on the
housing (a tap with a hammer, the accelerometer's or the sensor's own spectrum) or from the housing's FEM (the
workflow's ``results/bearing/housing_modes_healthy.json``: 2731 Hz at 1.16 % for the paper's housing); bolted
cast-iron housings damp their modes at 0.5-5 %.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .. import chain
from .base import Effect

#: Bounds of the mode's damping ratio [-].
DAMPING_BOUNDS = (1e-3, 0.5)
#: Damping ratio the fit starts from where the rig file gives none [-] (the middle of the 0.5-5 % of bolted housings).
DAMPING_START = 0.02
#: The start scan of a mode the rig file does not give, coarse then fine: frequencies from this share of the
#: sampling rate to the Nyquist frequency [-] (a mode lower than 0.08 f_s, 204 Hz at 2550 Hz, would be a housing
#: far softer than the rollers' contacts) in relative steps of :data:`COARSE_STEP_RATIO` at the damping ratios of
#: :data:`COARSE_DAMPING`; then around the best, steps of :data:`FINE_STEP_RATIO` at :data:`FINE_DAMPING`.
SCAN_FROM_RATIO = 0.08
#: The coarse scan's relative frequency step [-]: half the half-power width 2 zeta f at its lightest damping.
COARSE_STEP_RATIO = 0.02
#: The coarse scan's damping ratios [-].
COARSE_DAMPING = (0.02, 0.06, 0.2)
#: The fine scan's relative frequency step [-] (six either side of the coarse best): a third of the half-power width
#: at 0.6 %, its lightest damping.
FINE_STEP_RATIO = 0.004
#: The fine scan's damping ratios [-].
FINE_DAMPING = (0.006, 0.01, 0.02, 0.04, 0.08)


def frequency_identifiable(record, mode_Hz: float) -> bool:
    """Whether the record holds a mode's frequency: 0 (not given by the rig file: found from the record, below its
    Nyquist frequency) or a given mode below the Nyquist frequency."""
    return mode_Hz <= 0.0 or mode_Hz < 0.5 * record.sample_rate_Hz


class HousingModeEffect(Effect):
    name = "housing_mode"
    title = "a housing mode between rollers and sensor"
    rides_on = ("shaft_dynamics",)
    mimics_defects = True
    example = {"housing_mode_Hz": 1100.0, "housing_mode_damping_ratio": 0.02}
    example_reason = (
        "a housing's lowest mode at 1.1 kHz, inside a 2550 Hz record's band, damped at 2 % (a light pedestal or a "
        "sensor on a bracket; the paper's housing has its first at 2.73 kHz)"
    )
    physics = (
        "A resonance of the housing between the rollers and the sensor: every roller passage and groove edge rings "
        "it, the roller passage's harmonics near it are lifted. Modelled as one single-degree-of-freedom mode on the "
        "dynamic rung's sensor force, before the DAQ's average."
    )

    def params(self, record) -> list[Param]:
        f0, z0 = record.rig.housing_mode or (0.0, DAMPING_START)
        vary = frequency_identifiable(record, f0)
        return [
            Param("housing_mode_Hz", float(f0), 0.0, 0.5 * record.sample_rate_Hz if vary else 1e6, scale=100.0,
                  vary=vary, description="frequency of the housing's mode [Hz]"),
            Param("housing_mode_damping_ratio", float(np.clip(z0, *DAMPING_BOUNDS)), *DAMPING_BOUNDS, log=True,
                  description="damping ratio of the housing's mode [-]"),
        ]

    def starts(self, ctx):
        """The best of a scan (:func:`best_mode`)."""
        return [best_mode(ctx)[0]]

    def summary(self, values):
        return (f"housing mode {values['housing_mode_Hz']:.5g} Hz at {100 * values['housing_mode_damping_ratio']:.3g} % "
                "damping")


def best_mode(ctx) -> tuple[dict, float]:
    """The mode (frequency, damping ratio) of a grid that leaves the least misfit on the current fit's values, and
    that misfit: the residual's sum of squares, its mean taken out (the DC level is the fit's) [V^2].

    The grid: the rig file's frequency (and, below the Nyquist frequency, ten steps of :data:`FINE_STEP_RATIO`
    either side) at 0.3-2.5 times its damping ratio; where the rig file gives none, a coarse scan from
    :data:`SCAN_FROM_RATIO` of the sampling rate to the Nyquist frequency, refined around its best. Each candidate
    passes one integration of the dynamic chain through its mode
    (:func:`~piezobearing.diagnosis.bearing.chain.mode_voltages`; 340 candidates of a 2 s record at 2550 Hz cost
    about ten evaluations of the chain)."""
    rec = ctx.record
    nyquist = 0.5 * rec.sample_rate_Hz
    f0, z0 = rec.rig.housing_mode or (0.0, DAMPING_START)
    if f0 > 0:
        freqs = np.array([f0])
        if frequency_identifiable(rec, f0):
            freqs = f0 * (1 + FINE_STEP_RATIO * np.arange(-10, 11))
            freqs = freqs[freqs < nyquist]
        return _best(ctx, freqs, np.clip(z0 * np.array([0.3, 0.6, 1.0, 1.6, 2.5]), *DAMPING_BOUNDS))
    lo = SCAN_FROM_RATIO * rec.sample_rate_Hz
    coarse = lo * (1 + COARSE_STEP_RATIO) ** np.arange(int(np.log(nyquist / lo) / np.log1p(COARSE_STEP_RATIO)))
    f = _best(ctx, coarse, np.array(COARSE_DAMPING))[0]["housing_mode_Hz"]
    fine = f * (1 + FINE_STEP_RATIO) ** np.arange(-6, 7)
    return _best(ctx, fine[(fine >= lo) & (fine < nyquist)], np.array(FINE_DAMPING))


def _best(ctx, freqs: np.ndarray, damping: np.ndarray) -> tuple[dict, float]:
    modes = [(float(f), float(z)) for f in freqs for z in damping]
    values = {k: v for k, v in ctx.values.items() if not k.startswith("housing_mode_")}
    # what the current model adds to the chain's voltage (an interference's), kept beside each mode
    other = ctx.model_V - chain.voltage(ctx.record.rig, values)
    best, at = np.inf, modes[0]
    for m, v in zip(modes, chain.mode_voltages(ctx.record.rig, values, modes), strict=True):
        e = chain.centred_ss(ctx.voltage_V - other - v)
        if e < best:
            best, at = e, m
    return {"housing_mode_Hz": at[0], "housing_mode_damping_ratio": at[1]}, best


EFFECT = HousingModeEffect()
