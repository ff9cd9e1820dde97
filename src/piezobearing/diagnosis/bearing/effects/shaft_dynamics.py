"""``shaft_dynamics``: the shaft's inertia on its rollers, the rung above the quasi-static model.

Physics
-------
The quasi-static chain holds the rings in equilibrium at every instant. The shaft (and the inner ring) has
mass, carried by the rollers' Hertz contacts with some damping, and the housing (the pedestal) has its own mass
and stiffness: after each edge of a groove the shaft rings at its mode on the rollers (sqrt(k_c / m_s) / 2 pi,
2.6 kHz for 1 kg on the paper's bearing at 500 N), the rollers beside the groove open and close during the
ring, and a defect that unloads a roller faster than the shaft follows (an inner-race or a roller's groove)
changes its neighbours' loads less than in equilibrium, so its dips are modulated through the load zone more
deeply. In a record these are the rings after the dips, a groove 20-26 deg from the sensor whose sensor force
is dominated by the ring (a quasi-static fit puts it a roller pitch away), and a moving defect's sidebands
6-7 dB stronger than the quasi-static model's (docs/validation/bearing_diagnosis.md).

Model
-----
The 4-DOF equations of the LPM (:mod:`piezobearing.bearing.shaft_dynamics`: shaft and pedestal, Hertz line
contacts that open, viscous damping) integrated on the chain's kinematics and drops at
``bearing_diagnosis.dynamic_steps_per_period`` (16) steps per period of the shaft's mode in the search and
``dynamic_final_steps_per_period`` (48) in the final refit of the model it selects, the sensor force averaged
over each DAQ sample; within 0.12-0.42 % (16) and 0.01-0.05 % (48) (rms) of the LPM at a finer step where the
quasi-static chain is 2-13 % off (``benchmarks/bench_shaft_dynamics.py --accuracy``).

Parameters: ``shaft_mass_kg`` in [0, 50] kg (0: the quasi-static chain, the effect off; the rig file's
``bearing.shaft_mass_kg`` is the start) and ``bearing_damping_N_s_per_m`` in [10, 1e5] N s/m (log scale;
start ``bearing.bearing_damping_N_s_per_m``). The pedestal's ``bearing.pedestal_mass_kg``,
``pedestal_stiffness_N_per_m`` and ``pedestal_damping_N_s_per_m`` are held at the rig file's values: its mode
lies far above any DAQ band a record of this sensor is held at. The shaft's mass is fitted only where the shaft's
mode (at the rig file's mass) lies below the record's Nyquist frequency; above it (the paper's 2550 Hz: Nyquist
1275 Hz against 2.6 kHz) the record sees the mode only through its aliases and the box average, and the mass is
held at the rig file's value (in the final fit's values without an interval), unless the record shows a shaft
other than the rig file's: the dynamic rung scans the mass (a quarter to four times the rig file's,
:func:`~piezobearing.diagnosis.bearing.rung.mass_scan`), and where a mass of the scan takes more off chi2 than the
selection rule asks of one parameter (a heavier shaft's mode, 1.8 kHz for 2 kg, rings at its alias, 0.7 kHz at
2550 Hz, and the box average passes a third of it), the rung runs again from that mass with the mass fitted.

Where a user finds the values: the shaft's mass is the shaft's and inner ring's (and anything they carry)
weighed or from the drawing, the share this bearing carries (half for a shaft between two equal bearings at
equal distances); the pedestal's mass is the housing's and outer ring's, its stiffness a static load over the
housing's deflection under it, or the housing FEM's (the workflow's ``bearing/housing_*`` outputs); the
damping, 2-8 % of critical on the shaft's mode, 2 zeta sqrt(k_c m_s), is what the fit finds.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .. import chain
from ..representations import fitted_kinematics
from .base import Effect
from .outer_race_defect import TRIAL_WIDTH_M

#: Bounds of the damping between shaft and pedestal [N s/m]: 0.03-300 % of critical for 1 kg on the paper's rig.
DAMPING_BOUNDS = (10.0, 1e5)


def mass_identifiable(record) -> bool:
    """Whether the shaft's mass is fitted: the record's Nyquist frequency lies above the shaft's mode at the rig
    file's mass, or the dynamic rung's scan of the mass found the record's shaft other than the rig file's
    (``rig.fit_shaft_mass``, :func:`~piezobearing.diagnosis.bearing.rung.mass_scan`)."""
    rig = record.rig
    if rig.dynamics is None:
        return False
    return rig.fit_shaft_mass or chain.shaft_mode_Hz(rig, rig.dynamics)[0] < 0.5 * record.sample_rate_Hz


class ShaftDynamicsEffect(Effect):
    name = "shaft_dynamics"
    title = "shaft dynamics on the rollers"
    example = {"shaft_mass_kg": 1.0, "bearing_damping_N_s_per_m": 1.5e3}
    example_reason = (
        "1 kg of shaft and inner ring on the paper's N 305 (a 25 mm shaft about 250 mm long carried by two "
        "bearings), damped by 1.5 kN s/m, about 4 % of critical on its 2.6 kHz mode: the LPM's own values"
    )
    physics = (
        "The shaft's mass rides on the rollers' contacts: after each groove edge it rings at its mode on the "
        "rollers (~2.6 kHz), the neighbouring rollers open and close, and a moving defect is modulated through the "
        "load zone more deeply than in equilibrium. Modelled by the LPM's 4-DOF dynamics on the chain's kinematics."
    )

    def params(self, record) -> list[Param]:
        rig = record.rig
        c0 = rig.dynamics.bearing_damping_N_s_per_m if rig.dynamics is not None else 1.5e3
        return [
            Param("shaft_mass_kg", 0.0, 0.0, 50.0, scale=0.1, vary=mass_identifiable(record),
                  description="mass of shaft and inner ring on the rollers [kg]"),
            Param("bearing_damping_N_s_per_m", float(np.clip(c0, *DAMPING_BOUNDS)), *DAMPING_BOUNDS, log=True,
                  description="damping between shaft and pedestal [N s/m]"),
        ]

    def starts(self, ctx):
        """The rig file's values; with an outer-race groove in the model, also the groove placed with the dynamics
        on (:func:`place_groove`): a quasi-static fit places a groove 20-26 deg from the sensor a roller pitch away,
        where its own dip falls at the time of the shaft's ring."""
        d = ctx.record.rig.dynamics
        if d is None:
            return [{}]
        own = {"shaft_mass_kg": d.shaft_mass_kg,
               "bearing_damping_N_s_per_m": float(np.clip(d.bearing_damping_N_s_per_m, *DAMPING_BOUNDS))}
        if ctx.values.get("outer_defect_width_m", 0.0) <= 0:
            return [own]
        return [own, *place_groove(ctx, own)]

    def summary(self, values):
        return (f"shaft {values['shaft_mass_kg']:.3g} kg on the rollers, damping "
                f"{values['bearing_damping_N_s_per_m']:.4g} N s/m")


#: A placed groove within this of the current fit's angle is the rig file's start again [rad] (a tenth of the
#: 0.57 rad roller pitch of the paper's bearing; a misplaced groove lies a pitch away).
SAME_PLACE_RAD = 0.05
#: Time shifts the groove's placement resolves: this many per sample [-].
UPSAMPLE = 16


class LaggedMatch:
    """The best lag of an event's voltage against a residual: their circular cross-correlation, resolved to
    1/:data:`UPSAMPLE` of a sample (zero-padded spectra), at the lags a groove within half a roller pitch of its start
    gives (``|lag omega| <= pitch / 2``; ``omega`` the groove's angular speed relative to the rollers [rad/s])."""

    def __init__(self, residual: np.ndarray, dt_s: float, omega: float, pitch: float):
        r = residual - residual.mean()
        self.n = r.size
        self.big = self.n * UPSAMPLE
        self.spec_r = np.fft.rfft(r)
        self.lag_s = np.fft.fftfreq(self.big, 1.0 / self.big) * dt_s / UPSAMPLE  # the lag of each upsampled bin [s]
        self.near = np.abs(self.lag_s * omega) <= 0.5 * pitch

    def __call__(self, dv: np.ndarray) -> tuple[float, float, float] | None:
        """(lag [s], the event's least-squares amplitude there, the event's energy) at the largest correlation
        among the near lags; None where the event ``dv`` (its mean taken out) has no energy."""
        dv = dv - dv.mean()
        energy = float(dv @ dv)
        if energy <= 0:
            return None
        prod = np.zeros(self.big // 2 + 1, dtype=complex)
        prod[: self.n // 2 + 1] = self.spec_r * np.conj(np.fft.rfft(dv))
        corr = np.fft.irfft(prod, self.big) * UPSAMPLE  # sum_t r(t) dv(t - lag) (circular), sampled at 1/UPSAMPLE
        j = np.flatnonzero(self.near)[int(np.argmax(corr[self.near]))]
        return float(self.lag_s[j]), float(corr[j]) / energy, energy


def place_groove(ctx, own: dict, keep: int = 1) -> list[dict]:
    """Starts of an outer-race groove for the dynamic chain, found by cross-correlation: ``keep`` dicts.

    The dynamic chain's voltage with a groove at each angle a_k = a_0 + k x pitch within the load zone (+-100 deg;
    a_0 the current fit's angle) less the healthy dynamic chain's is one event per roller passage, its dip and
    the shaft's ring. A groove dth further on gives about the same events dth / omega_c later (omega_c the
    cage's angular speed): the residual of the healthy dynamic chain is cross-correlated with each a_k's events
    at lags within half a roller pitch, resolved to 1/:data:`UPSAMPLE` of a sample (the ring's period spans
    about one sample at 2550 Hz: a fit started a few hundredths of a radian off ends in another ring's phase).
    Each a_k's best lag (a positive amplitude) gives an angle and a width (the dip grows as the width squared);
    of the two that explain most of the residual farther than :data:`SAME_PLACE_RAD` from a_0 (where the rig
    file's start already puts it), those whose start leaves less misfit than the groove at a_0 with the dynamics
    are returned, at most ``keep`` (each start is a whole fit of the dynamic chain: a groove the quasi-static fit
    placed right gets none).
    """
    rig = ctx.record.rig
    values = {**ctx.values, **own}
    pitch = rig.pitch_rad
    a0 = float(values["outer_defect_angle_rad"])
    w = max(float(values["outer_defect_width_m"]), TRIAL_WIDTH_M)
    healthy = chain.voltage(rig, {**values, "outer_defect_width_m": 0.0})
    omega = 2 * np.pi * fitted_kinematics(values, ctx.record)["frequencies"]["ftf_Hz"]
    match = LaggedMatch(ctx.voltage_V - healthy, ctx.record.dt_s, omega, pitch)
    scored = []
    for k in range(-6, 7):
        ak = a0 + k * pitch
        if abs(ak) > np.radians(100.0):
            continue
        dv = chain.voltage(rig, {**values, "outer_defect_angle_rad": ak, "outer_defect_width_m": w}) - healthy
        best = match(dv)
        if best is None:
            continue
        lag, amp, energy = best
        if amp > 0:
            scored.append((amp * amp * energy, {**own, "outer_defect_angle_rad": float(ak + lag * omega),
                                                "outer_defect_width_m": float(np.clip(w * np.sqrt(amp), 0.05e-3, 2.9e-3))}))
    scored.sort(key=lambda x: -x[0])
    moved = [t for _, t in scored if abs(t["outer_defect_angle_rad"] - a0) > SAME_PLACE_RAD][:2]
    here = chain.misfit(rig, ctx.voltage_V, values)
    return [t for t in moved if chain.misfit(rig, ctx.voltage_V, {**values, **t}) < here][:keep]


EFFECT = ShaftDynamicsEffect()
