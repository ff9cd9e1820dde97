"""Running-bearing records from the dynamic LPM: the diagnosis held against a model it does not fit.

The diagnosis fits the quasi-static surrogate (:mod:`piezobearing.bearing.surrogate`: the rings' static
equilibrium at every instant). These records come from the 4-DOF lumped-parameter model instead
(:func:`piezobearing.bearing.lpm.simulate_lpm`: the shaft's mass on its rollers, the pedestal, damping,
integrated in time; its defects' own geometry, :class:`piezobearing.bearing.lpm.Defect`), each roller's load
through the housing's influence line, averaged over each DAQ sample window, through the one sensor model
(:mod:`piezobearing.sensor.response`), plus white noise. What they hide is named by the catalogue's
parameters (``radial_load_N``, ``outer_defect_width_m``, ...), so a diagnosis's answer reads against them.

The two models differ where the dynamics matter: the shaft rings at its ~2 kHz mode on its rollers after a
defect's edge, and a moving defect (inner race, rolling element) unloads and reloads a roller faster than
the shaft can follow.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...bearing.lpm import Defect, LPMParameters, resample_loads, simulate_lpm
from ...bearing.surrogate import InfluenceLine
from ...housing.one_mode import through_mode
from ...io import BearingRecord
from ...signals.detection import noise_std_for_snr
from .chain import PRE_ROLL_TAU
from .effects import CATALOGUE
from .model import RigRecord
from .subject import rig_from_config

#: Longest LPM integration step [s]: the config's 36 steps per 1/2550 s (10.9 us; ~40 steps per period of
#: the shaft-on-rollers mode, ~75 per passage of a 0.9 mm groove).
MAX_STEP_S = 0.392156e-3 / 36
#: Depth of a hidden groove [m] (the paper's 1 mm: a roller bridges it, the depth never acts).
DEPTH_M = 1.0e-3
#: The LPM's shaft and pedestal parameters a record may hold apart from its rig file's (:func:`lpm_parameters`).
RIG_DYNAMICS = ("shaft_mass_kg", "bearing_damping_N_s_per_m", "pedestal_mass_kg", "pedestal_stiffness_N_per_m",
                "pedestal_damping_N_s_per_m")
#: Extra simulated time before the circuit's pre-roll: the LPM's start from static equilibrium settles [s].
SETTLE_S = 0.02


def lpm_parameters(config: dict, hidden: dict, start_phase_rad: float, seed: int = 0) -> LPMParameters:
    """The LPM of the config's healthy bearing with the ``hidden`` conditions and defects (catalogue names).

    ``speed_deviation_ratio`` runs the shaft at (1 + it) times ``bearing.shaft_speed_rpm`` at t = 0, and
    ``speed_ramp_Hz_per_s`` (not a catalogue parameter: a record's condition) changes it at that rate; ``roller_k_offset_m``
    makes roller k smaller by it (a gap larger by it, as the surrogate's offsets); the defects are grooves
    1 mm deep. A rolling-element groove at ``roller_defect_spin_rad`` faces the outer race at spin 0.
    ``defect_edge_radius_m`` (not a catalogue parameter: a record's condition, as the ramp) rounds every
    defect's edges with a fillet of that radius (:func:`~piezobearing.bearing.lpm.chord_drop_m`; the widths
    are then the widths at the surface), where the catalogue's defects have sharp edges. ``housing_mode_Hz`` and
    ``housing_mode_damping_ratio`` (record conditions too) are read by :func:`lpm_sensor_force`. The shaft's and
    the pedestal's dynamics are the config's (``bearing.shaft_mass_kg`` ...) unless ``hidden`` gives the record's own
    (:data:`RIG_DYNAMICS`): a rig whose shaft, damping or pedestal differ from what its rig file says.
    """
    b = dict(config["bearing"], roller_diameter_scatter_m=0.0, cage_slip=0.0, slip_jitter=0.0,
             speed_ramp_rpm_per_s=0.0)
    p = LPMParameters.from_config(b, faulty=False, seed=seed)
    geo = replace(p.geometry, radial_clearance_m=hidden.get("radial_clearance_m", p.geometry.radial_clearance_m))
    defects = []
    rho = hidden.get("defect_edge_radius_m", 0.0)
    if hidden.get("outer_defect_width_m", 0.0) > 0:
        defects.append(Defect(hidden.get("outer_defect_angle_rad", 0.0), hidden["outer_defect_width_m"], DEPTH_M,
                              "outer_race", edge_radius_m=rho))
    if hidden.get("inner_defect_width_m", 0.0) > 0:
        defects.append(Defect(hidden.get("inner_defect_angle_rad", 0.0), hidden["inner_defect_width_m"], DEPTH_M,
                              "inner_race", edge_radius_m=rho))
    if hidden.get("roller_defect_width_m", 0.0) > 0:
        defects.append(Defect(-hidden.get("roller_defect_spin_rad", 0.0), hidden["roller_defect_width_m"], DEPTH_M,
                              "rolling_element", int(hidden.get("roller_defect_index", 0)), rho))
    dev = tuple(-hidden.get(f"roller_{k}_offset_m", 0.0) for k in range(geo.n_rollers))
    return replace(
        p,
        geometry=geo,
        radial_load_N=hidden.get("radial_load_N", p.radial_load_N),
        shaft_speed_Hz=p.shaft_speed_Hz * (1.0 + hidden.get("speed_deviation_ratio", 0.0)),
        speed_ramp_Hz_per_s=hidden.get("speed_ramp_Hz_per_s", 0.0),
        cage_slip=hidden.get("cage_slip_ratio", 0.0),
        start_angle_rad=start_phase_rad,
        defects=tuple(defects),
        roller_diameter_deviation_m=dev if any(dev) else (),
        **{k: float(hidden[k]) for k in RIG_DYNAMICS if k in hidden},
    )


def lpm_sensor_force(config: dict, influence: InfluenceLine, hidden: dict, time_s: np.ndarray,
                     max_step_s: float = MAX_STEP_S) -> np.ndarray:
    """The LPM's sensor force [N] averaged over each sample window of the uniform clock ``time_s`` [s].

    The LPM (:func:`lpm_parameters`, roller 0 at ``bearing_diagnosis.synthetic_start_phase_deg`` at t = 0) starts
    from static equilibrium :data:`SETTLE_S` before the first window, steps at most ``max_step_s``; each
    roller's load times the influence line at its angle, summed, is box-averaged over the windows, times
    ``load_share_ratio``. With a ``housing_mode_Hz`` in ``hidden`` the summed force passes through that housing
    mode first (:func:`piezobearing.housing.one_mode.through_mode`, damping ratio ``housing_mode_damping_ratio``, default 0.02).
    """
    t = np.asarray(time_s, dtype=float)
    dt = float(t[1] - t[0])
    p = lpm_parameters(config, hidden, float(np.radians(config["bearing_diagnosis"]["synthetic_start_phase_deg"])))
    h = dt / int(np.ceil(dt / max_step_s))
    t_start = t[0] - dt - SETTLE_S
    res = simulate_lpm(p, t_start, int(np.ceil((t[-1] + dt - t_start) / h)), h)
    fine = np.sum(res.load_N * influence(res.psi_rad), axis=1)
    if hidden.get("housing_mode_Hz", 0.0) > 0:
        fine = through_mode(fine, h, hidden["housing_mode_Hz"], hidden.get("housing_mode_damping_ratio", 0.02))
    return resample_loads(res.time_s, fine[:, None], t, dt, "average")[:, 0] * hidden.get("load_share_ratio", 1.0)


def lpm_record(
    config: dict,
    influence: InfluenceLine,
    hidden: dict,
    sample_rate_Hz: float,
    duration_s: float,
    snr_dB: float,
    seed: int,
    harmonic: tuple[np.ndarray, np.ndarray] | None = None,
    tachometer: bool = False,
    max_step_s: float = MAX_STEP_S,
) -> BearingRecord:
    """A running-bearing record of the dynamic LPM with the ``hidden`` conditions (see the module docstring).

    Parameters
    ----------
    config : dict
        The validated config (``bearing``, ``sensor``, ``signals``, ``bearing_diagnosis``).
    influence : InfluenceLine
        The housing's sensor force per radial roller load [N/N].
    hidden : dict
        Catalogue parameter values (any of the catalogue's effects; ``load_share_ratio`` scales the force,
        ``mains_*`` add the mains effect's voltage).
    sample_rate_Hz, duration_s : float
        The DAQ's clock [Hz] and the record's length [s].
    snr_dB : float
        White noise at 10 log10(P_s / sigma^2) over the noiseless record [dB].
    seed : int
        Seed of the noise.
    harmonic : (ndarray, ndarray), optional
        The sensor FEM's response (else the paper sensor's, :func:`~piezobearing.sensor.response.sensor_model`).
    tachometer : bool
        Write the shaft speed as ``speed_rpm`` (with a ``speed_ramp_Hz_per_s``, the speed at each sample).
    max_step_s : float
        The LPM's longest integration step [s] (:data:`MAX_STEP_S`; shorter, for records at a finer step than
        the dynamic rung's own).
    """
    dt = 1.0 / sample_rate_Hz
    t = dt * np.arange(int(round(duration_s * sample_rate_Hz)))
    rig = rig_from_config(config, influence, t, harmonic=harmonic)
    # the circuit's pre-roll (as the chain's) on the LPM's own force
    n_pre = int(np.ceil(PRE_ROLL_TAU * rig.tau_s / dt))
    t_ext = t[0] + dt * np.arange(-n_pre, t.size)
    force = lpm_sensor_force(config, influence, hidden, t_ext, max_step_s)
    v = rig.gain_factor * rig.sensor.voltage(force, dt)[n_pre:]
    if any(k.startswith("mains_") for k in hidden):
        rr = RigRecord(t, None, "voltage", "V", rig=rig)
        values = {**CATALOGUE["mains_pickup"].defaults(rr), **{k: x for k, x in hidden.items() if k.startswith("mains_")}}
        v = v + CATALOGUE["mains_pickup"].additive(values, rr)
    rng = np.random.default_rng(seed)
    v = v + noise_std_for_snr(v, snr_dB) * rng.standard_normal(v.size)
    f0 = config["bearing"]["shaft_speed_rpm"] / 60.0
    speed = None
    if tachometer:
        speed = 60.0 * (f0 * (1.0 + hidden.get("speed_deviation_ratio", 0.0)) + hidden.get("speed_ramp_Hz_per_s", 0.0) * t)
    return BearingRecord(t, v, speed, "lpm", (), np.zeros(t.size, dtype=bool))


def draw_conditions(rng: np.random.Generator, config: dict) -> tuple[dict, dict]:
    """A rig file and a record's hidden truth drawn across a running rig's plausible range.

    The rig file (``bearing.radial_load_N`` 100-2000 N log-uniform, ``bearing.radial_clearance_m`` 0-60 um) is
    what the diagnosis believes; the record differs from it by a load within x/÷ 1.5 (kept in 100-2000 N), a
    clearance of 0-60 um, cage slip 0-3 %, a speed -3..+3 % off the file's, roller diameters scattered by a
    standard deviation of 0-2 um, and in two draws of three a groove (outer race, inner race or on a roller,
    equally often) 0.1-1.2 mm wide at any angle. Returns (config, hidden) in the catalogue's names.
    """
    c = {k: (dict(v) if isinstance(v, dict) else v) for k, v in config.items()}
    load = float(np.exp(rng.uniform(np.log(100.0), np.log(2000.0))))
    c["bearing"] = dict(config["bearing"], radial_load_N=load, radial_clearance_m=float(rng.uniform(0.0, 60e-6)))
    z = int(config["bearing"]["n_rollers"])
    hidden = {
        "radial_load_N": float(np.clip(load * np.exp(rng.uniform(-np.log(1.5), np.log(1.5))), 100.0, 2000.0)),
        "radial_clearance_m": float(rng.uniform(0.0, 60e-6)),
        "cage_slip_ratio": float(rng.uniform(0.0, 0.03)),
        "speed_deviation_ratio": float(rng.uniform(-0.03, 0.03)),
    }
    scatter = float(rng.uniform(0.0, 2e-6))
    for k, x in enumerate(scatter * rng.standard_normal(z)):
        if k:
            hidden[f"roller_{k}_offset_m"] = float(x)
    kind = int(rng.integers(0, 3)) if rng.uniform() < 2 / 3 else None
    width, angle = float(rng.uniform(0.1e-3, 1.2e-3)), float(rng.uniform(-np.pi, np.pi))
    if kind == 0:
        hidden.update(outer_defect_width_m=width, outer_defect_angle_rad=angle)
    elif kind == 1:
        hidden.update(inner_defect_width_m=width, inner_defect_angle_rad=angle)
    elif kind == 2:
        hidden.update(roller_defect_width_m=width, roller_defect_spin_rad=angle,
                      roller_defect_index=float(rng.integers(0, z)))
    return c, hidden
