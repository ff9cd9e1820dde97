r"""The running bearing's forward model: from the operating point to the recorded sensor voltage.

.. math::
    V(t) = \mathcal{C}\left[\,s\,F_s(t)\,\right] + V_{dc} + V_{add}(t),\qquad
    F_s(t) = \frac{1}{\Delta t}\int_{t-\Delta t/2}^{t+\Delta t/2} \sum_j Q_j\, g(\psi_j)\, dt'

F_s is the quasi-static sensor force of :mod:`piezobearing.bearing.surrogate`
averaged over each sample window (the roller loads Q_j of the rings'
equilibrium with any defect's drop, times the housing's influence line g),
s the share of that force the sensor's mounting passes (1 nominal), and C
the sensor circuit of Eq. 6 (gain d33/C times the FEM correction, time
constant RC), integrated exactly for a force linear between samples from a
steady state (a pre-roll of 8 RC time constants is simulated and dropped).
V_dc is the DAQ's offset, V_add additive interference (mains).

The cage turns at 2 pi FTF (1 - slip) with the shaft speed f_r (a constant,
or the tachometer's record); the roller set is at ``start_phase_rad`` at the
first sample. Defects: an outer-race groove at a fixed angle from the
sensor, an inner-race groove turning with the shaft (at ``inner_defect_angle_rad``
from the sensor at the first sample), a groove on one roller spinning with it
(``roller_defect_spin_rad`` at the first sample; 0 faces the outer race).
Moving defects are solved on a fine grid (sub-samples) and averaged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...bearing.lpm import BearingGeometry, kinematic_frequencies
from ...bearing.surrogate import (
    InfluenceLine,
    Operating,
    Surrogate,
    cage_phase,
    inner_race_drop,
    outer_race_drop,
    phase_edges,
    rolling_element_drop,
)
from ...sensor.calibration import rc_voltage

#: Narrowest groove the fine grid must resolve (3 sub-samples across its passage) [m].
MIN_WIDTH_M = 0.25e-3
#: Pre-roll before the record, in RC time constants (steady state to e^-8).
PRE_ROLL_TAU = 8.0


@dataclass(frozen=True, eq=False)
class Rig:
    """What the chain holds fixed for one record: bearing, housing, circuit, nominal operating point, clock.

    Parameters
    ----------
    geometry : BearingGeometry
    influence : InfluenceLine
        Sensor force per newton of radial roller load [N/N].
    gain_V_per_N : float
        d33 / C times the sensor FEM's correction [V/N].
    tau_s : float
        R C of the circuit [s].
    radial_load_N, radial_clearance_m, shaft_speed_Hz : float
        The nominal operating point [N, m, Hz].
    time_s : ndarray
        The record's uniform clock [s].
    tach_Hz : ndarray or None
        Shaft speed from the tachometer at each sample [Hz].
    """

    geometry: BearingGeometry
    influence: InfluenceLine
    gain_V_per_N: float
    tau_s: float
    radial_load_N: float
    radial_clearance_m: float
    shaft_speed_Hz: float
    time_s: np.ndarray
    tach_Hz: np.ndarray | None = None
    surrogate: Surrogate = field(default=None, repr=False)

    def __post_init__(self):
        if self.surrogate is None:
            object.__setattr__(self, "surrogate", Surrogate(self.geometry, self.influence))

    @property
    def n(self) -> int:
        return int(self.time_s.size)

    @property
    def dt_s(self) -> float:
        return float((self.time_s[-1] - self.time_s[0]) / (self.n - 1))

    @property
    def n_pre(self) -> int:
        """Samples simulated before the record (steady state of the circuit)."""
        return int(np.ceil(PRE_ROLL_TAU * self.tau_s / self.dt_s))

    @property
    def pitch_rad(self) -> float:
        return self.geometry.roller_pitch_rad

    def ftf_ratio(self) -> float:
        """FTF / f_r without slip [-]."""
        return kinematic_frequencies(self.geometry, 1.0).ftf_Hz

    def frequencies(self, shaft_Hz: float, slip: float = 0.0) -> dict[str, float]:
        """Kinematic frequencies at a shaft speed with cage slip (the cage and what rolls on it slow down) [Hz]."""
        k = kinematic_frequencies(self.geometry, shaft_Hz)
        ftf = k.ftf_Hz * (1 - slip)
        z = self.geometry.n_rollers
        bsf = ftf * self.geometry.outer_raceway_radius_m / (0.5 * self.geometry.roller_diameter_m)
        return {"shaft_Hz": shaft_Hz, "ftf_Hz": ftf, "bpfo_Hz": z * ftf, "bpfi_Hz": z * (shaft_Hz - ftf), "bsf_Hz": bsf}

    def substeps(self) -> int:
        """Sub-samples per sample for moving defects: 3 across the narrowest groove's passage."""
        g = self.geometry
        ri = 0.5 * (g.pitch_diameter_m - g.roller_diameter_m)
        v = ri * 2 * np.pi * self.shaft_speed_Hz * 1.2  # rolling speed on the inner race, 20% margin
        return int(np.clip(np.ceil(3 * v * self.dt_s / MIN_WIDTH_M), 1, 64))


def _speed(rig: Rig, values: dict, t_ext: np.ndarray) -> np.ndarray | float:
    """Shaft speed [Hz]: the tachometer's (extended back at its first value) or the fitted constant, times
    1 + ``speed_deviation_ratio``."""
    dev = 1.0 + values.get("speed_deviation_ratio", 0.0)
    if rig.tach_Hz is None:
        return dev * float(values["shaft_speed_Hz"])
    pre = np.full(t_ext.size - rig.n, rig.tach_Hz[0])
    return dev * np.concatenate([pre, rig.tach_Hz])


def sensor_force(rig: Rig, values: dict) -> tuple[np.ndarray, np.ndarray]:
    """Sampled sensor force on the record's clock with its pre-roll, and that clock [N, s]."""
    g = rig.geometry
    dt = rig.dt_s
    t_ext = rig.time_s[0] + dt * np.arange(-rig.n_pre, rig.n)
    slip = values.get("cage_slip_ratio", 0.0)
    speed = _speed(rig, values, t_ext)
    phi = cage_phase(t_ext, speed, g, 0.0, slip)
    phi = phi - phi[rig.n_pre] + values["start_phase_rad"]
    op = Operating(values.get("radial_load_N", rig.radial_load_N), values.get("radial_clearance_m", rig.radial_clearance_m))
    offsets = None
    if "roller_1_offset_m" in values:
        offsets = tuple([0.0] + [values[f"roller_{k}_offset_m"] for k in range(1, g.n_rollers)])
    outer, key = None, None
    w_o = values.get("outer_defect_width_m", 0.0)
    if w_o > 0:
        ang = values["outer_defect_angle_rad"]

        def outer(psi, ang=ang, w=w_o):
            return outer_race_drop(psi, ang, w, g)

        key = ("outer", w_o, ang)
    w_i = values.get("inner_defect_width_m", 0.0)
    w_r = values.get("roller_defect_width_m", 0.0)
    if w_i <= 0 and w_r <= 0:
        return rig.surrogate.box_average(phase_edges(phi), op, outer, key, offsets), t_ext
    # moving defects: sub-samples at the centres of S equal parts of each sample window
    s = rig.substeps()
    edges = phase_edges(phi)
    frac = (np.arange(s) + 0.5) / s
    phi_f = (edges[:-1, None] + np.diff(edges)[:, None] * frac[None, :]).ravel()
    drop = np.zeros((phi_f.size, g.n_rollers))
    if w_i > 0:
        # the shaft turns f_r / FTF times as far as the cage
        theta = values["inner_defect_angle_rad"] + (phi_f - values["start_phase_rad"]) / (rig.ftf_ratio() * (1 - slip))
        drop += inner_race_drop(rig.surrogate.roller_angles(phi_f), theta, w_i, g)
    if w_r > 0:
        spin = values["roller_defect_spin_rad"] + (g.outer_raceway_radius_m / (0.5 * g.roller_diameter_m)) * (
            phi_f - values["start_phase_rad"]
        )
        drop += rolling_element_drop(g.n_rollers, int(values.get("roller_defect_index", 0)), spin, w_r, g)
    f = rig.surrogate.fine_force(phi_f, op, drop, outer, key, offsets)
    return f.reshape(-1, s).mean(axis=1), t_ext


def voltage(rig: Rig, values: dict, additive: np.ndarray | None = None) -> np.ndarray:
    """The recorded voltage the chain predicts on the record's clock [V]."""
    f, _ = sensor_force(rig, values)
    share = values.get("load_share_ratio", 1.0)
    v = rc_voltage(share * f, rig.dt_s, rig.gain_V_per_N, rig.tau_s)[rig.n_pre :]
    v = v + values.get("dc_offset_V", 0.0)
    if additive is not None:
        v = v + additive
    return v
