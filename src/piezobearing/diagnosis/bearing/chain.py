r"""The running bearing's forward model: from the operating point to the recorded sensor voltage.

.. math::
    V(t) = \mathcal{C}\left[\,s\,F_s(t)\,\right] + V_{dc} + V_{add}(t),\qquad
    F_s(t) = \frac{1}{\Delta t}\int_{t-\Delta t/2}^{t+\Delta t/2} \sum_j Q_j\, g(\psi_j)\, dt'

F_s is the quasi-static sensor force of :mod:`piezobearing.bearing.surrogate`
averaged over each sample window (the roller loads Q_j of the rings'
equilibrium with any defect's drop, times the housing's influence line g),
s the share of that force the sensor's mounting passes (1 nominal), and C
the sensor model (:class:`~piezobearing.sensor.response.SensorModel`, the
workflow's too: the circuit of Eq. 6 with gain d33/C times the sensor FEM's
correction, time constant RC; times ``bearing_diagnosis.gain_factor``, a
DAQ amplifier's gain), integrated exactly for a force linear between samples
from a steady state (a pre-roll of 8 RC time constants is simulated and dropped).
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

from collections.abc import Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from ...bearing.geometry import BearingGeometry, kinematic_frequencies
from ...bearing.shaft_dynamics import STEPS_PER_PERIOD, ShaftDynamics, shaft_mode, steps_per_sample
from ...bearing.shaft_dynamics import sensor_force as dyn_sensor_force
from ...bearing.surrogate import (
    InfluenceLine,
    Operating,
    OuterGroove,
    Surrogate,
    cage_phase,
    inner_race_contact,
    phase_edges,
    roller_groove_drop,
    rolling_element_drop,
)
from ...housing.one_mode import through_mode
from ...sensor.response import SensorModel
from ..record import UniformClock

#: Narrowest groove the fine grid must resolve (3 sub-samples across its passage) [m].
MIN_WIDTH_M = 0.25e-3
#: Pre-roll before the record, in RC time constants (steady state to e^-8).
PRE_ROLL_TAU = 8.0
#: Values that act after the sensor force (with ``mains_*``): a change of them reuses the force.
AFTER_FORCE = frozenset({"load_share_ratio", "dc_offset_V"})
#: Forces (as circuit voltages) a rig keeps: the current point and a finite-difference Jacobian's steps,
#: within CACHE_BYTES for a long record.
CACHE_SIZE = 24
CACHE_BYTES = 64e6
#: Most bytes of the dynamic rung's kinematic grids a rig keeps (:func:`kinematic_grid`: roller angles, their
#: normals and the influence line at them; 4 arrays of steps x rollers each); a larger grid is computed at every call.
GRID_BYTES = 256e6
#: Most kinematic grids a rig keeps (the least recently used goes first): a finite-difference Jacobian steps the start
#: phase, the speed and the slip one after another (a grid each) and returns to its point's grid for every other
#: parameter.
GRID_KEEP = 4
#: Fewest steps per period of a housing mode (the ``housing_mode`` effect) on the dynamic rung's grid, whatever the
#: shaft's mode asks (:data:`~piezobearing.bearing.shaft_dynamics.STEPS_PER_PERIOD`): the lightly damped mode's
#: first-order hold (:func:`~piezobearing.housing.one_mode.through_mode`) needs them; at 16 the force through a
#: 2731 Hz mode is 3.2 % off the LPM, at 24 1.0 % (tests/test_diagnosis_bearing_housing_rung.py).
MODE_STEPS_PER_PERIOD = 24


@dataclass(frozen=True, eq=False)
class Rig(UniformClock):
    """What the chain holds fixed for one record: bearing, housing, circuit, nominal operating point, clock.

    Parameters
    ----------
    geometry : BearingGeometry
    influence : InfluenceLine
        Sensor force per newton of radial roller load [N/N].
    sensor : SensorModel
        Force to voltage: the circuit and the sensor FEM's correction.
    gain_factor : float
        A DAQ amplifier's gain on the sensor model's voltage (1: none) [-].
    radial_load_N, radial_clearance_m, shaft_speed_Hz : float
        The nominal operating point [N, m, Hz].
    time_s : ndarray
        The record's uniform clock [s].
    tach_Hz : ndarray or None
        Shaft speed from the tachometer at each sample [Hz].
    dynamics : ShaftDynamics or None
        The rig's shaft and pedestal (``bearing.shaft_mass_kg`` ...): the values the ``shaft_dynamics`` effect
        starts from and holds (None: the LPM's keys are not known, the effect cannot be added).
    steps_per_period : int
        The dynamic rung's integration steps per period of the shaft's mode
        (:func:`~piezobearing.bearing.shaft_dynamics.steps_per_sample`; ``bearing_diagnosis.dynamic_steps_per_period``).
    housing_mode : (float, float) or None
        A housing mode between the rollers and the sensor the rig's user knows (``bearing_diagnosis.housing_mode_Hz``,
        ``housing_mode_damping_ratio``): its frequency [Hz] and damping ratio [-], the values the ``housing_mode``
        effect starts from (and holds the frequency at, where it lies above the record's Nyquist frequency); None:
        not known.
    fit_shaft_mass : bool
        Fit the shaft's mass even where its mode (at ``dynamics``' mass) lies above the record's Nyquist frequency:
        the dynamic rung's scan of the mass found the record's shaft other than the rig file's
        (:func:`~piezobearing.diagnosis.bearing.rung.mass_scan`), so the record sees the mode's ring.
    """

    geometry: BearingGeometry
    influence: InfluenceLine
    sensor: SensorModel
    gain_factor: float
    radial_load_N: float
    radial_clearance_m: float
    shaft_speed_Hz: float
    time_s: np.ndarray
    tach_Hz: np.ndarray | None = None
    dynamics: ShaftDynamics | None = None
    steps_per_period: int = STEPS_PER_PERIOD
    housing_mode: tuple[float, float] | None = None
    fit_shaft_mass: bool = False
    surrogate: Surrogate = field(default=None, repr=False)
    cache: dict = field(default_factory=dict, repr=False, compare=False)
    #: The dynamic rung's last kinematic grids (:func:`kinematic_grid`), the last used last.
    grid: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        if self.surrogate is None:
            object.__setattr__(self, "surrogate", Surrogate(self.geometry, self.influence))

    @property
    def tau_s(self) -> float:
        """The sensor circuit's R C [s]."""
        return self.sensor.tau_s

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
        """Kinematic frequencies at a shaft speed with cage slip (``bearing.geometry.kinematic_frequencies``) [Hz]."""
        return kinematic_frequencies(self.geometry, shaft_Hz, slip).to_dict()

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
    f, t_ext, dyn = forces(rig, values)
    if dyn is not None:  # the dynamic rung: the 4-DOF dynamics after the pre-roll, through any housing mode
        mode = None
        if values.get("housing_mode_Hz", 0.0) > 0:
            mode = (float(values["housing_mode_Hz"]), float(values["housing_mode_damping_ratio"]))
        f = sampled(rig, f, dyn, mode)
    return f, t_ext


def sampled(rig: Rig, f: np.ndarray, dyn: tuple[int, int, np.ndarray], mode: tuple[float, float] | None) -> np.ndarray:
    """The sampled sensor force [N]: the quasi-static force ``f`` before the dynamic rung's first sample, then its
    fine force (``dyn`` of :func:`forces`) through the housing ``mode`` (frequency [Hz], damping ratio [-]; None:
    none), averaged over each sample window."""
    first, s, fine = dyn
    if mode is not None:
        fine = through_mode(fine, rig.dt_s / s, *mode)
    return np.concatenate([f[:first], fine.reshape(-1, s).mean(axis=1)])


def forces(rig: Rig, values: dict) -> tuple[np.ndarray, np.ndarray, tuple[int, int, np.ndarray] | None]:
    """The quasi-static sensor force on the record's clock with its pre-roll [N], that clock [s], and, with the
    dynamic rung (a ``shaft_mass_kg`` in the values), the dynamic force on its fine grid before any housing mode:
    (first sample, steps per sample S, force (n S,)) of :func:`shaft_dynamics_force`; else None."""
    g = rig.geometry
    dt = rig.dt_s
    t_ext = rig.time_s[0] + dt * np.arange(-rig.n_pre, rig.n)
    slip = values.get("cage_slip_ratio", 0.0)
    speed = _speed(rig, values, t_ext)
    phi = cage_phase(t_ext, speed, g, 0.0, slip)
    phi = phi - phi[rig.n_pre] + values["start_phase_rad"]
    op = operating(rig, values)
    offsets = None
    if "roller_1_offset_m" in values:
        offsets = tuple([0.0] + [values[f"roller_{k}_offset_m"] for k in range(1, g.n_rollers)])
    outer, key = None, None
    w_o = values.get("outer_defect_width_m", 0.0)
    if w_o > 0:
        outer = OuterGroove(float(values["outer_defect_angle_rad"]), float(w_o), g)
        key = outer.key
    w_i = values.get("inner_defect_width_m", 0.0)
    w_r = values.get("roller_defect_width_m", 0.0)
    edges = phase_edges(phi)
    f = rig.surrogate.box_average(edges, op, outer, key, offsets)
    if w_i > 0 or w_r > 0:
        f = f + moving_defect_change(rig, values, edges, op, outer, key, offsets)
    dyn = None
    if values.get("shaft_mass_kg", 0.0) > 0:
        dyn = shaft_dynamics_force(rig, values, edges, op, outer, offsets)
    return f, t_ext, dyn


def mode_voltages(rig: Rig, values: dict, modes: list[tuple[float, float]]) -> Iterator[np.ndarray]:
    """The recorded voltage the chain predicts [V] through each housing mode (frequency [Hz], damping ratio [-]) of
    ``modes``, with the dynamic rung's values (a ``shaft_mass_kg``): the 4-DOF dynamics integrated once, on a grid
    fine enough for the highest of the modes, and passed through each (the ``housing_mode`` effect's start scan):
    :func:`voltage` without its additive interference."""
    top = max(m for m, _ in modes)
    f, _, dyn = forces(rig, {**values, "housing_mode_Hz": top})
    for mode in modes:
        yield values.get("load_share_ratio", 1.0) * circuit_voltage(rig, sampled(rig, f, dyn, mode)) \
            + values.get("dc_offset_V", 0.0)


def moving_defect_change(rig: Rig, values: dict, edges: np.ndarray, op: Operating, outer, key, offsets) -> np.ndarray:
    """What an inner-race or rolling-element groove changes in each sample's mean sensor force [N].

    Each sample window is cut into S equal parts (:meth:`Rig.substeps`);
    only the samples in which a sub-sample finds a roller over the groove
    are solved: the mean over their sub-samples of the equilibrium with the
    groove's drop minus the table without it (the rest of the sample is the
    table's exact box average, :meth:`~piezobearing.bearing.surrogate.Surrogate.box_average`).
    """
    g = rig.geometry
    slip = values.get("cage_slip_ratio", 0.0)
    w_i = values.get("inner_defect_width_m", 0.0)
    w_r = values.get("roller_defect_width_m", 0.0)
    s = rig.substeps()
    frac = (np.arange(s) + 0.5) / s
    change = np.zeros(edges.size - 1)
    # the shaft turns f_r / FTF times as far as the cage, the roller R_o / r times
    cage_per_shaft = rig.ftf_ratio() * (1 - slip)
    spin_per_cage = g.outer_raceway_radius_m / (0.5 * g.roller_diameter_m)
    cand = np.zeros(change.size, dtype=bool)
    if w_i > 0:
        ri = 0.5 * (g.pitch_diameter_m - g.roller_diameter_m)
        x = values["inner_defect_angle_rad"] + (edges - values["start_phase_rad"]) / cage_per_shaft - edges
        cand |= _passes(x, 0.5 * w_i / ri, rig.pitch_rad)
    if w_r > 0:
        spin = values["roller_defect_spin_rad"] + spin_per_cage * (edges - values["start_phase_rad"])
        cand |= _passes(spin, 0.5 * w_r / (0.5 * g.roller_diameter_m), np.pi)
    cand = np.flatnonzero(cand)
    if not cand.size:
        return change
    # the sub-samples of the candidate samples only (the same numbers as over the whole record)
    phi_f = (edges[cand, None] + (edges[cand + 1] - edges[cand])[:, None] * frac[None, :]).ravel()
    hit = np.zeros(phi_f.size, dtype=bool)
    if w_i > 0:
        theta = values["inner_defect_angle_rad"] + (phi_f - values["start_phase_rad"]) / cage_per_shaft
        j_i, d_i = inner_race_contact(phi_f, theta, w_i, g)
        hit |= d_i > 0
    if w_r > 0:
        d_r = roller_groove_drop(values["roller_defect_spin_rad"] + spin_per_cage * (phi_f - values["start_phase_rad"]),
                                 w_r, g)
        hit |= d_r > 0
    at = np.unique(np.flatnonzero(hit) // s)
    if not at.size:
        return change
    samples = cand[at]
    sub = (at[:, None] * s + np.arange(s)[None, :]).ravel()
    drop = np.zeros((sub.size, g.n_rollers))
    rows = np.arange(sub.size)
    if w_i > 0:
        drop[rows, j_i[sub]] += d_i[sub]
    if w_r > 0:
        drop[:, int(values.get("roller_defect_index", 0))] += d_r[sub]
    diff = rig.surrogate.fine_change(phi_f[sub], op, drop, outer, key, offsets)
    change[samples] = diff.reshape(-1, s).mean(axis=1)
    return change


#: The shaft's dynamics are simulated from at least this long before the record's first sample, from static
#: equilibrium (their start transient decays as exp(-zeta omega t): 20 ms is 14 time constants at the rig's 5 %
#: damping; ten time constants where the damping is lighter, :func:`shaft_dynamics_force`) [s].
DYNAMICS_SETTLE_S = 0.02


def operating(rig: Rig, values: dict) -> Operating:
    """The operating point of ``values``: their radial load and clearance, the rig file's where they hold none."""
    return Operating(values.get("radial_load_N", rig.radial_load_N), values.get("radial_clearance_m", rig.radial_clearance_m))


def dynamics_of(rig: Rig, values: dict) -> ShaftDynamics:
    """The rig's shaft and pedestal with the values' ``shaft_mass_kg`` and ``bearing_damping_N_s_per_m``."""
    d = rig.dynamics
    return replace(d, shaft_mass_kg=float(values["shaft_mass_kg"]),
                   bearing_damping_N_s_per_m=float(values.get("bearing_damping_N_s_per_m", d.bearing_damping_N_s_per_m)))


def shaft_mode_Hz(rig: Rig, dyn: ShaftDynamics, op: Operating | None = None) -> tuple[float, float]:
    """The shaft's mode on its rollers along the load [Hz] and its damping ratio [-] at the operating point (the
    rig's nominal one by default): :func:`piezobearing.bearing.shaft_dynamics.shaft_mode`."""
    op = op or operating(rig, {})
    return shaft_mode(dyn, float(op.radial_load_N), float(op.radial_clearance_m), rig.geometry.roller_length_m,
                      rig.geometry.n_rollers)


def shaft_dynamics_force(rig: Rig, values: dict, edges: np.ndarray, op: Operating, outer,
                         offsets) -> tuple[int, int, np.ndarray]:
    """The sensor force of the dynamic rung on its fine grid from sample ``first`` on, S steps per sample:
    (first, S, force (n S,)) [N]; :func:`sensor_force` averages it over the sample windows.

    On the grid of :func:`fine_grid` the roller angles and every drop (an outer-race groove, a moving defect, the
    rollers' offsets) enter the 4-DOF dynamics (:func:`~piezobearing.bearing.shaft_dynamics.sensor_force`), which
    start at rest :data:`DYNAMICS_SETTLE_S` (or ten decay times) before the record's first sample; the samples
    before ``first`` keep the quasi-static force (the circuit's pre-roll). With a ``housing_mode_Hz`` in the values
    (the ``housing_mode`` effect) :func:`sensor_force` passes this force through that mode on the grid, before the
    average (:func:`~piezobearing.housing.one_mode.through_mode`, damping ratio ``housing_mode_damping_ratio``; from
    static equilibrium at ``first``, as the shaft).
    """
    dyn = dynamics_of(rig, values)
    first, s, psi, drop, normals, g = fine_grid(rig, values, edges, op, outer, offsets, dyn)
    f = dyn_sensor_force(psi, drop, op.radial_load_N, op.radial_clearance_m, rig.geometry.roller_length_m,
                         rig.influence, dyn, rig.dt_s / s, normals, g)
    return first, s, f


def kinematic_grid(rig: Rig, e: np.ndarray, s: int) -> tuple[np.ndarray, np.ndarray, tuple, np.ndarray]:
    """The cage phases (n S,), roller angles (n S, Z), their normals (sin psi, -cos psi) and the influence line at
    them g(psi) (n S, Z) of :func:`fine_grid`'s grid: S steps in each window between the cage phases ``e``.

    They depend on the kinematics only (the phases, not the loads, the defects or the damping): the rig keeps the
    last :data:`GRID_KEEP` grids (at most :data:`GRID_BYTES`), which serve every step of a finite-difference Jacobian
    in a parameter other than the start phase, the speed or the slip, and the return to its point's grid after a
    step in those (the same numbers as computed anew).
    """
    z = rig.geometry.n_rollers
    key = (s, e.tobytes())
    hit = rig.grid.pop(key, None)
    if hit is not None:
        rig.grid[key] = hit  # the last used last
        return hit
    frac = (np.arange(s) + 0.5) / s
    phi = (e[:-1, None] + np.diff(e)[:, None] * frac[None, :]).ravel()
    psi = rig.surrogate.roller_angles(phi)
    # the normals by the angle sum (psi_j = phi + j pitch): two products instead of two transcendentals per roller
    pj = rig.pitch_rad * np.arange(z)
    sp, cp = np.sin(phi)[:, None], np.cos(phi)[:, None]
    cpj, spj = np.cos(pj), np.sin(pj)
    sn = sp * cpj
    sn += cp * spj  # in place: the same sums, a 10 MB array fewer to fill on a 2 s record
    cn = cp * cpj
    cn -= sp * spj
    normals = (sn, np.negative(cn, out=cn))
    g = rig.influence(psi)
    size = 4 * psi.nbytes
    if size <= GRID_BYTES:
        for a in (phi, psi, *normals, g):
            a.flags.writeable = False
        rig.grid[key] = (phi, psi, normals, g)
        _trim(rig.grid, min(GRID_KEEP, int(GRID_BYTES // size)))
    return phi, psi, normals, g


def fine_grid(rig: Rig, values: dict, edges: np.ndarray, op: Operating, outer, offsets,
              dyn: ShaftDynamics) -> tuple[int, int, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray], np.ndarray]:
    """The dynamic rung's grid: (first sample, steps per sample S, roller angles (n, Z) [rad], extra gaps (n, Z) [m],
    the rollers' normals (sin psi, -cos psi), the influence line at the roller angles (n, Z)).

    Each sample window from ``first`` on (its cage phase from ``edges``) is cut into S equal steps
    (:func:`~piezobearing.bearing.shaft_dynamics.steps_per_sample` at the shaft's mode, at least the moving
    defects' :meth:`Rig.substeps` and as many per period of a ``housing_mode_Hz`` as of the shaft's mode, at least
    :data:`MODE_STEPS_PER_PERIOD`); ``first`` lies :data:`DYNAMICS_SETTLE_S`, or ten decay times of the shaft's
    mode where that is longer, before the record's first sample (within the circuit's pre-roll). An outer-race
    groove narrower than a roller pitch holds one roller at a time: its drop is computed for the roller nearest
    to it only (the same numbers as for every roller).
    """
    f_mode, zeta = shaft_mode_Hz(rig, dyn, op)
    dt = rig.dt_s
    moving = values.get("inner_defect_width_m", 0.0) > 0 or values.get("roller_defect_width_m", 0.0) > 0
    s = max(steps_per_sample(f_mode, dt, rig.steps_per_period), rig.substeps() if moving else 1,
            steps_per_sample(values.get("housing_mode_Hz", 0.0), dt, max(rig.steps_per_period, MODE_STEPS_PER_PERIOD)))
    settle = max(DYNAMICS_SETTLE_S, 10.0 / max(zeta * 2 * np.pi * f_mode, 1e-12))
    n_ext = edges.size - 1
    first = max(0, n_ext - rig.n - int(np.ceil(settle / dt)))
    phi, psi, normals, g = kinematic_grid(rig, edges[first:], s)
    drop = _moving_drops(rig, values, phi) if moving else np.zeros(psi.shape)
    if isinstance(outer, OuterGroove) and outer.width_m < rig.geometry.outer_raceway_radius_m * rig.pitch_rad:
        j = np.mod(np.rint((outer.angle_rad - phi) / rig.pitch_rad), rig.geometry.n_rollers).astype(int)
        rows = np.arange(phi.size)
        drop[rows, j] += outer(psi[rows, j])
    elif outer is not None:
        drop += outer(psi)
    if offsets is not None:
        drop += np.asarray(offsets)[None, :]
    return first, s, psi, drop, normals, g


def _moving_drops(rig: Rig, values: dict, phi: np.ndarray) -> np.ndarray:
    """The drops (n, Z) [m] of an inner-race and a rolling-element groove at cage phases ``phi`` (n,)."""
    g = rig.geometry
    slip = values.get("cage_slip_ratio", 0.0)
    cage_per_shaft = rig.ftf_ratio() * (1 - slip)
    spin_per_cage = g.outer_raceway_radius_m / (0.5 * g.roller_diameter_m)
    drop = np.zeros((phi.size, g.n_rollers))
    if values.get("inner_defect_width_m", 0.0) > 0:
        theta = values["inner_defect_angle_rad"] + (phi - values["start_phase_rad"]) / cage_per_shaft
        j, d = inner_race_contact(phi, theta, values["inner_defect_width_m"], g)
        drop[np.arange(phi.size), j] += d
    if values.get("roller_defect_width_m", 0.0) > 0:
        spin = values["roller_defect_spin_rad"] + spin_per_cage * (phi - values["start_phase_rad"])
        drop += rolling_element_drop(g.n_rollers, int(values.get("roller_defect_index", 0)), spin,
                                     values["roller_defect_width_m"], g)
    return drop


def _passes(angle_at_edges: np.ndarray, half_rad: float, period_rad: float) -> np.ndarray:
    """Which sample windows may hold a passage of a groove: the angle (linear in the cage phase, given at the
    windows' edges) comes within ``half_rad`` of a multiple of ``period_rad`` (margin 0.1% + 1e-9 rad for the
    sub-samples' rounding; the drops then decide exactly)."""
    lo = np.minimum(angle_at_edges[:-1], angle_at_edges[1:])
    hi = np.maximum(angle_at_edges[:-1], angle_at_edges[1:])
    h = 1.001 * half_rad + 1e-9
    return np.floor((hi + h) / period_rad) >= np.ceil((lo - h) / period_rad)


def force_key(values: dict) -> tuple:
    """The values the sensor force depends on: all but the mounting's share, the DC level and the
    additive interference (``mains_*``), which act after the force (a finite-difference step in one
    of them reuses the force)."""
    return tuple(sorted((k, float(v)) for k, v in values.items() if k not in AFTER_FORCE and not k.startswith("mains_")))


def unit_voltage(rig: Rig, values: dict) -> np.ndarray:
    """The circuit's voltage for the whole sensor force (share 1, no DC) on the record's clock [V], cached
    per :func:`force_key` (the fit evaluates the chain at the same force many times)."""
    key = force_key(values)
    hit = rig.cache.get(key)
    if hit is not None:
        return hit
    v = circuit_voltage(rig, sensor_force(rig, values)[0])
    v.flags.writeable = False
    rig.cache[key] = v
    _trim(rig.cache, int(np.clip(CACHE_BYTES / (8 * v.size), 2, CACHE_SIZE)))
    return v


def _trim(cache: dict, most: int) -> None:
    """Drop ``cache``'s first entries (the oldest; the least recently used where a hit moves its entry last) until it
    holds at most ``most``."""
    while len(cache) > most:
        cache.pop(next(iter(cache)))


def circuit_voltage(rig: Rig, force_N: np.ndarray) -> np.ndarray:
    """The circuit's voltage for a sampled sensor force with its pre-roll, on the record's clock [V]."""
    return rig.gain_factor * rig.sensor.voltage(force_N, rig.dt_s)[rig.n_pre :]


def voltage(rig: Rig, values: dict, additive: np.ndarray | None = None) -> np.ndarray:
    """The recorded voltage the chain predicts on the record's clock [V].

    The circuit is linear: the share s scales the voltage of the whole force (:func:`unit_voltage`).
    """
    share = values.get("load_share_ratio", 1.0)
    v = share * unit_voltage(rig, values)
    v = v + values.get("dc_offset_V", 0.0)
    if additive is not None:
        v = v + additive
    return v


def centred_ss(r: np.ndarray) -> float:
    """A residual's sum of squares, its mean taken out (the DC level is the fit's) [V^2]."""
    r = np.asarray(r, dtype=float)
    return float(np.sum((r - r.mean()) ** 2))


def misfit(rig: Rig, voltage_V: np.ndarray, values: dict) -> float:
    """The chain's misfit on ``voltage_V`` at ``values``: the residual's :func:`centred_ss` [V^2]."""
    return centred_ss(voltage_V - voltage(rig, values))
