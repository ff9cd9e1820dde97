"""The bearing: geometry, kinematic frequencies and the 4-DOF lumped-parameter model.

SKF N 305 ECP cylindrical roller bearing (paper Sec. III-A, IV): 11 rollers,
outer ring stationary in the housing, inner ring turning with the shaft.

Functional API (what callers need): :class:`LPMParameters` (a frozen
dataclass: geometry, operating point, defects, slip; ``from_config`` or built
directly) -> :func:`simulate_lpm` -> :class:`LPMResult` (roller loads and
displacements on the integration grid); :func:`kinematic_frequencies` for the
characteristic frequencies with cage slip; :meth:`LPMParameters.motion` for
the kinematics alone (roller, cage, shaft and roller-spin angles, with slip
jitter and a speed ramp).

Angles
------
Roller and defect positions are angles psi [rad] in the bearing's plane,
measured from the direction of the radial load (the bottom of the bearing,
-z) and increasing with the sense of rotation. The outward unit normal of the
outer raceway at psi is ``n(psi) = (sin psi, -cos psi)`` in the (y, z) plane
of the housing model (y horizontal, z up, x along the shaft).

Size. Over 600 lines as one module: the geometry, contact law, defects, parameters and the time
integration are the one 4-DOF model and share its frozen parameter dataclasses; the compiled step loop
lives in :mod:`piezobearing.bearing.lpm_kernel`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..config import ConfigError
from . import surface
from .geometry import BearingGeometry, kinematic_frequencies
from .lpm_kernel import newmark_lpm

#: The defect types of ``bearing.defects``.
DEFECT_TYPES = ("outer_race", "inner_race", "rolling_element")

#: Palmgren's line-contact constant: delta = 3.84e-5 Q^0.9 / l^0.8 with delta,
#: l in mm and Q in N (Harris & Kotzalas, Rolling Bearing Analysis, Eq. 6.41),
#: converted to SI: delta [m] = PALMGREN_SI * Q^0.9 * l^-0.8 with l in m.
PALMGREN_SI = 3.84e-5 * 1e-3 * 1e3**-0.8


# ---------------------------------------------------------------------------
# Contact law and the outer-race defect
# ---------------------------------------------------------------------------


def line_contact_stiffness(roller_length_m: float) -> float:
    """Load-deflection constant K of one roller between both raceways.

    Palmgren's line contact, delta = 3.84e-5 Q^0.9 / l^0.8 (mm, N) for each of
    the two contacts (roller-inner race, roller-outer race), in series:
    delta_roller = 2 PALMGREN_SI Q^0.9 l^-0.8, hence Q = K delta^(10/9) with

    .. math::  K = \\left(2\\,c_P\\,l^{-0.8}\\right)^{-10/9}

    Parameters
    ----------
    roller_length_m : float
        Effective contact length l [m].

    Returns
    -------
    float
        K [N / m^(10/9)]; 6.3e8 for l = 9.76 mm.
    """
    return float((2 * PALMGREN_SI * roller_length_m**-0.8) ** (-10 / 9))


def contact_law(delta_m: np.ndarray, k_contact: float) -> tuple[np.ndarray, np.ndarray]:
    """Hertzian line contact Q = K <delta>^(10/9) and its slope, vectorised.

    Parameters
    ----------
    delta_m : ndarray
        Roller deflections (overlap) [m]; no load where negative.
    k_contact : float
        K [N / m^(10/9)].

    Returns
    -------
    q_N : ndarray
        Contact loads [N].
    dq_N_per_m : ndarray
        dQ / d delta [N/m].
    """
    d = np.maximum(delta_m, 0.0)
    # the power only where a roller is loaded (most of a bearing's rollers carry nothing; 0 ** (1/9) is 0)
    d19 = np.zeros_like(d)
    np.power(d, 1 / 9, out=d19, where=d > 0)
    return k_contact * d * d19, (10 / 9) * k_contact * d19


def chord_drop_m(arc_m: np.ndarray, width_m: float, depth_m: float, relative_radius_m: float,
                 edge_radius_m: float = 0.0) -> np.ndarray:
    """How far a roller sinks over a gap of width w, at arc position u [m].

    Sharp edges (``edge_radius_m`` 0): a roller whose contact point is the arc length u past the gap's
    entry edge (0 <= u <= w) rests on the nearer edge; with the relative radius R of the two surfaces
    (roller against raceway) its centre sinks ``R - sqrt(R^2 - min(u, w - u)^2)``, capped at the depth;
    0 outside.

    Rounded edges (``edge_radius_m`` rho > 0): each edge is a fillet of radius rho, tangent to the raceway
    where the gap opens (w is the width at the surface, from where one fillet leaves the raceway to where
    the other rejoins it; the walls stand w - 2 rho apart). A roller over the fillet touches it on the
    line through the fillet's centre, so its centre circles that centre at R + rho: the drop is the sharp
    formula with R + rho for R, ``(R + rho) - sqrt((R + rho)^2 - min(u, w - u)^2)``, capped at the depth.
    It holds while the contact stays on the fillet's quarter circle (u <= R + rho, always for a gap
    narrower than the roller) and is exact in the unrolled picture of the relative radius (the fillet's
    own curvature adds to the raceway's to first order in rho / raceway radius). The same deepest point is
    reached by a sharp gap of width ``2 sqrt(R^2 - (R - drop)^2)`` (:meth:`Defect.equivalent_sharp_width_m`),
    narrower than w; the dip lasts the whole surface width.

    Parameters
    ----------
    arc_m : ndarray
        Arc position of the contact from the gap's centre [m].
    width_m, depth_m : float
        Gap width w at the surface and depth [m].
    relative_radius_m : float
        R [m] (:meth:`BearingGeometry.relative_radius_m`).
    edge_radius_m : float
        rho, the edges' fillet radius [m]; 0: sharp edges.
    """
    u = np.asarray(arc_m) + 0.5 * width_m
    inside = (u > 0) & (u < width_m)
    m = np.minimum(u, width_m - u)
    r = relative_radius_m + edge_radius_m
    drop = r - np.sqrt(np.maximum(r * r - m * m, 0.0))
    return np.where(inside, np.minimum(drop, depth_m), 0.0)


def _wrap(angle_rad: np.ndarray) -> np.ndarray:
    """Angles to [-pi, pi) [rad]."""
    return np.mod(np.asarray(angle_rad) + np.pi, 2 * np.pi) - np.pi


def max_edge_radius_m(width_m: float, depth_m: float) -> float:
    """The largest fillet that rounds both edges of a gap ``width_m`` wide and ``depth_m`` deep: half the width (the
    fillets meet), and the depth (a fillet reaches the bottom) [m]."""
    return min(0.5 * width_m, depth_m)


@dataclass(frozen=True)
class Defect:
    """A local defect: a groove across a raceway or a flat on a roller, with sharp or rounded edges.

    Parameters
    ----------
    angle_rad : float
        ``outer_race``: centre from the load direction (the sensor) [rad];
        ``inner_race``: centre on the inner ring at t = 0, from the load
        direction, turning with the shaft [rad]; ``rolling_element``: the
        flat's angle on its roller at t = 0, from the roller's contact with the
        outer race, in the roller's spin relative to the cage [rad].
    width_m : float
        Width w across the rolling direction's arc (groove) or chord (flat) [m].
    depth_m : float
        Depth of the removed material [m] (caps the drop).
    kind : {"outer_race", "inner_race", "rolling_element"}
    roller : int
        ``rolling_element``: index of the roller with the flat.
    edge_radius_m : float
        Radius rho of the fillet that rounds each edge [m] (:func:`chord_drop_m`); 0: sharp edges. At most
        half the width and at most the depth.
    """

    angle_rad: float
    width_m: float
    depth_m: float
    kind: str = "outer_race"
    roller: int = 0
    edge_radius_m: float = 0.0

    def __post_init__(self):
        if self.kind not in DEFECT_TYPES:
            raise ValueError(f"defect type must be one of {', '.join(DEFECT_TYPES)}, got {self.kind!r}")
        if not 0.0 <= self.edge_radius_m <= max_edge_radius_m(self.width_m, self.depth_m):
            raise ValueError(f"defect edge radius must be within [0, min(width/2, depth)] = "
                             f"[0, {max_edge_radius_m(self.width_m, self.depth_m):.4g}] m, got {self.edge_radius_m!r}")

    def max_drop_m(self, relative_radius_m: float) -> float:
        """Deepest a roller sinks at the defect's centre: min(depth, R - sqrt(R^2 - (w/2)^2)) [m].

        R is the relative radius of the surfaces in contact
        (:meth:`BearingGeometry.relative_radius_m`); R = r for a flat raceway.
        For the 0.9 mm groove on the N 305's outer race (R = 6.14 mm) 16.5 um,
        against 20.3 um on a flat raceway. Rounded edges: R + rho for R (:func:`chord_drop_m`).
        """
        r, hw = relative_radius_m + self.edge_radius_m, 0.5 * self.width_m
        if hw >= r:
            return self.depth_m
        return float(min(self.depth_m, r - np.sqrt(r * r - hw * hw)))

    def equivalent_sharp_width_m(self, relative_radius_m: float) -> float:
        """Width of the sharp-edged gap whose roller sinks as deep as over this one [m].

        ``2 sqrt(R^2 - (R - drop)^2)`` with the deepest drop of :meth:`max_drop_m`: the width itself for
        sharp edges (while the depth does not cap the drop), narrower for rounded ones (0.6 mm with
        rho = 0.15 mm on the N 305's outer race: 0.593 mm).
        """
        r, drop = relative_radius_m, self.max_drop_m(relative_radius_m)
        if drop >= r:
            return 2.0 * r
        return float(2.0 * np.sqrt(r * r - (r - drop) ** 2))


def defects_from_config(bearing: dict) -> tuple[Defect, ...]:
    """The defects of ``bearing.defects`` (a list of {type, width_m, depth_m, angle_deg[, roller, edge_radius_m]}).

    ``edge_radius_m`` (default 0, sharp edges): the fillet radius rounding both edges (:func:`chord_drop_m`).

    ``roller`` (rolling element only, default 0): the roller with the flat. With equal
    rollers a flat on roller j is the flat on roller 0 with ``start_angle_deg`` moved by
    j 360/Z deg (the rollers are interchangeable); with ``roller_diameter_scatter_m`` > 0
    they are not, and the index picks which roller carries it.
    """
    out = []
    for i, d in enumerate(bearing.get("defects", [])):
        rho = d.get("edge_radius_m", 0.0)
        if rho > max_edge_radius_m(d["width_m"], d["depth_m"]):
            raise ConfigError(
                f"key 'bearing.defects[{i}].edge_radius_m': a fillet of {rho:g} m does not fit a defect "
                f"{d['width_m']:g} m wide and {d['depth_m']:g} m deep; use at most half the width and at most the "
                "depth (0: sharp edges)"
            )
        out.append(Defect(np.radians(d["angle_deg"]), d["width_m"], d["depth_m"], d["type"], d.get("roller", 0), rho))
    return tuple(out)


@dataclass(frozen=True)
class Motion:
    """Kinematics of the bearing on a time grid (angles in the sense of rotation).

    Attributes
    ----------
    time_s : ndarray (n,)
    shaft_angle_rad : ndarray (n,)
        Angle the shaft (inner ring) has turned since t = 0 [rad].
    cage_angle_rad : ndarray (n,)
        Angle the cage has turned since t = 0, with slip and its jitter [rad].
    psi_rad : ndarray (n, Z)
        Roller angles from the load direction, wrapped to [-pi, pi) [rad].
    spin_rad : ndarray (n,)
        Roller spin relative to the cage since t = 0 (the same for all rollers) [rad].
    """

    time_s: np.ndarray
    shaft_angle_rad: np.ndarray
    cage_angle_rad: np.ndarray
    psi_rad: np.ndarray
    spin_rad: np.ndarray


# ---------------------------------------------------------------------------
# The 4-DOF lumped-parameter model
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class LPMParameters:
    """The 4-DOF model: shaft (inner ring) y, z and pedestal (outer ring, housing) y, z.

    Parameters
    ----------
    geometry : BearingGeometry
    radial_load_N : float
        Radial load F_r on the shaft, along -z [N].
    shaft_speed_Hz : float
        Shaft speed at t = 0 [Hz].
    shaft_mass_kg, pedestal_mass_kg : float
        m_s, m_p [kg].
    pedestal_stiffness_N_per_m : float
        k_p, pedestal to ground [N/m].
    bearing_damping_N_s_per_m : float
        c_b, viscous damping on the shaft-to-pedestal velocity [N s/m].
    pedestal_damping_N_s_per_m : float
        c_p, pedestal to ground [N s/m].
    start_angle_rad : float
        Angle of roller 0 at t = 0, from the load direction [rad].
    defects : tuple of Defect
        Local defects (any number, any type); empty for the healthy bearing.
    cage_slip : float
        Mean cage slip s [-]: the cage turns at (1 - s) of the rolling kinematics.
    slip_jitter : float
        Standard deviation of the slip from one roller passage (one roller
        pitch of cage travel) to the next [-]; each passage draws its own slip.
    speed_ramp_Hz_per_s : float
        Shaft acceleration [Hz/s]: f(t) = shaft_speed_Hz + ramp t (0: constant speed).
    roller_diameter_deviation_m : tuple of float
        Each roller's diameter minus the nominal D_r [m] (empty: all nominal).
        A larger roller closes its gap by the difference.
    seed : int
        Seed of the per-passage slip draws.
    surfaces : Surfaces or None
        The healthy bearing's floor, one realisation (:mod:`piezobearing.bearing.surface`: roughness and
        waviness of the raceways and rollers, the shaft's unbalance); None: ideal surfaces, no unbalance.
    """

    geometry: BearingGeometry
    radial_load_N: float
    shaft_speed_Hz: float
    shaft_mass_kg: float
    pedestal_mass_kg: float
    pedestal_stiffness_N_per_m: float
    bearing_damping_N_s_per_m: float
    pedestal_damping_N_s_per_m: float
    start_angle_rad: float = 0.0
    defects: tuple[Defect, ...] = ()
    cage_slip: float = 0.0
    slip_jitter: float = 0.0
    speed_ramp_Hz_per_s: float = 0.0
    roller_diameter_deviation_m: tuple[float, ...] = ()
    seed: int = 0
    surfaces: surface.Surfaces | None = None

    @classmethod
    def from_config(cls, bearing: dict, faulty: bool, seed: int = 0, realisation: int = 0) -> LPMParameters:
        """From the ``bearing`` section; ``faulty`` adds its ``defects``; ``seed``: the config's ``seed``.

        The roller diameters scatter by ``roller_diameter_scatter_m`` (standard
        deviation, drawn per roller from the seed: the same in both cases). The
        surfaces' roughness, waviness and the unbalance's phase
        (:mod:`piezobearing.bearing.surface`) are drawn per ``faulty`` and
        ``realisation`` from the seed: each realisation is another bearing.
        """
        b = bearing
        geo = BearingGeometry.from_config(b)
        scatter = b.get("roller_diameter_scatter_m", 0.0)
        dev = ()
        if scatter > 0:
            dev = tuple(float(x) for x in scatter * np.random.default_rng([seed, 1]).standard_normal(geo.n_rollers))
        floor = surface.SurfaceSettings.from_config(b)
        surfaces = None
        if floor.active:
            surfaces = surface.draw(floor, geo, contact_half_widths_m(geo, b["radial_load_N"]), seed, faulty,
                                    realisation)
        return cls(
            geometry=geo,
            radial_load_N=b["radial_load_N"],
            shaft_speed_Hz=b["shaft_speed_rpm"] / 60.0,
            shaft_mass_kg=b["shaft_mass_kg"],
            pedestal_mass_kg=b["pedestal_mass_kg"],
            pedestal_stiffness_N_per_m=b["pedestal_stiffness_N_per_m"],
            bearing_damping_N_s_per_m=b["bearing_damping_N_s_per_m"],
            pedestal_damping_N_s_per_m=b["pedestal_damping_N_s_per_m"],
            start_angle_rad=np.radians(b["start_angle_deg"]),
            defects=defects_from_config(b) if faulty else (),
            cage_slip=b.get("cage_slip", 0.0),
            slip_jitter=b.get("slip_jitter", 0.0),
            speed_ramp_Hz_per_s=b.get("speed_ramp_rpm_per_s", 0.0) / 60.0,
            roller_diameter_deviation_m=dev,
            seed=int(seed),
            surfaces=surfaces,
        )

    @property
    def k_contact(self) -> float:
        """K of the roller contacts [N / m^(10/9)]."""
        return line_contact_stiffness(self.geometry.roller_length_m)

    @property
    def gap_m(self) -> float:
        """Gap of each roller with concentric rings, P_d / 2 [m]."""
        return 0.5 * self.geometry.radial_clearance_m

    @property
    def cage_speed_rad_per_s(self) -> float:
        """Mean angular speed of the cage at t = 0, 2 pi FTF with the mean slip [rad/s]."""
        return 2 * np.pi * kinematic_frequencies(self.geometry, self.shaft_speed_Hz, self.cage_slip).ftf_Hz

    def shaft_speed_at(self, t_s: np.ndarray) -> np.ndarray:
        """Shaft speed f(t) = f_0 + ramp t [Hz]."""
        return self.shaft_speed_Hz + self.speed_ramp_Hz_per_s * np.asarray(t_s, dtype=float)

    def shaft_angle(self, t_s: np.ndarray) -> np.ndarray:
        """Angle the shaft has turned since t = 0, 2 pi (f_0 t + ramp t^2 / 2) [rad]."""
        t = np.asarray(t_s, dtype=float)
        return 2 * np.pi * (self.shaft_speed_Hz * t + 0.5 * self.speed_ramp_Hz_per_s * t * t)

    def _passage_slips(self, n: int, forward: bool) -> np.ndarray:
        """Slips of the passages 0, 1, ..., n-1 (forward) or -1, -2, ..., -n (backward) [-].

        Each direction is one random stream from the seed, read from passage 0
        outwards, so a passage's slip does not depend on the time grid.
        """
        rng = np.random.default_rng([self.seed, 2 if forward else 3])
        return self.cage_slip + self.slip_jitter * rng.standard_normal(n)

    def cage_angle(self, t_s: np.ndarray) -> np.ndarray:
        """Angle the cage has turned since t = 0, with the mean slip and its per-passage jitter [rad].

        Without slip the cage turns by (1 - g)/2 of the shaft's angle. With
        slip s_k during passage k (the cage's travel from k to k + 1 roller
        pitches) it turns (1 - s_k) times as far: the cage angle is piecewise
        linear in the no-slip cage angle, with breaks at whole pitches.
        """
        theta0 = 0.5 * (1 - self.geometry.diameter_ratio) * self.shaft_angle(t_s)
        if self.slip_jitter == 0:
            return (1 - self.cage_slip) * theta0
        pitch = self.geometry.roller_pitch_rad
        lo, hi = float(np.min(theta0, initial=0.0)), float(np.max(theta0, initial=0.0))
        n_up = int(np.ceil(hi / pitch * 1.2)) + 2
        n_dn = int(np.ceil(-lo / pitch * 1.2)) + 2
        while True:
            up = np.concatenate([[0.0], np.cumsum(pitch / (1 - self._passage_slips(n_up, True)))])
            dn = -np.cumsum(pitch / (1 - self._passage_slips(n_dn, False)))
            if up[-1] >= hi and dn[-1] <= lo:
                break
            n_up, n_dn = 2 * n_up, 2 * n_dn
        theta_k = np.concatenate([dn[::-1], up])
        phi_k = pitch * np.arange(-n_dn, n_up + 1)
        return np.interp(theta0, theta_k, phi_k)

    def motion(self, t_s: np.ndarray) -> Motion:
        """Shaft, cage, roller and roller-spin angles at the instants t [s] (:class:`Motion`)."""
        g = self.geometry
        t = np.asarray(t_s, dtype=float)
        phi = self.cage_angle(t)
        psi = self.start_angle_rad + g.roller_pitch_rad * np.arange(g.n_rollers)[None, :] + phi[:, None]
        return Motion(t, self.shaft_angle(t), phi, _wrap(psi), g.spin_per_cage_angle * phi)

    def roller_angles(self, t_s: np.ndarray) -> np.ndarray:
        """Roller angles psi_j(t) from the load direction, wrapped to [-pi, pi) [rad], shape (n_t, Z)."""
        return self.motion(t_s).psi_rad

    def drops(self, motion: Motion) -> np.ndarray:
        """How far each roller sinks into the defects (all of them, both races) [m], shape (n_t, Z).

        Outer race: the groove stands still at its angle; inner race: it turns
        with the shaft, so it meets the rollers at BPFI and is loaded only
        while in the load zone; rolling element: the flat on one roller meets
        the outer race when its spin angle is the defect's angle and the inner
        race half a spin later (2 BSF), loaded only while that roller is in the
        load zone (FTF modulation). Each uses the relative radius of its
        contact (concave outer, convex inner raceway).
        """
        g = self.geometry
        out = np.zeros_like(motion.psi_rad)
        r = 0.5 * g.roller_diameter_m
        for d in self.defects:
            if d.kind == "outer_race":
                arc = g.outer_raceway_radius_m * _wrap(motion.psi_rad - d.angle_rad)
                out += chord_drop_m(arc, d.width_m, d.depth_m, g.relative_radius_m("outer"), d.edge_radius_m)
            elif d.kind == "inner_race":
                pos = d.angle_rad + motion.shaft_angle_rad[:, None]
                arc = g.inner_raceway_radius_m * _wrap(motion.psi_rad - pos)
                out += chord_drop_m(arc, d.width_m, d.depth_m, g.relative_radius_m("inner"), d.edge_radius_m)
            else:
                j = d.roller % g.n_rollers
                chi = motion.spin_rad - d.angle_rad
                out[:, j] += chord_drop_m(r * _wrap(chi), d.width_m, d.depth_m, g.relative_radius_m("outer"),
                                          d.edge_radius_m)
                out[:, j] += chord_drop_m(
                    r * _wrap(chi - np.pi), d.width_m, d.depth_m, g.relative_radius_m("inner"), d.edge_radius_m
                )
        return out

    def contact_offsets(self, motion: Motion) -> np.ndarray:
        """What each roller's overlap loses besides the rings' offset: defect drops minus diameter excess,
        minus the surfaces' heights where roughness or waviness is on [m]."""
        off = self.drops(motion)
        if self.roller_diameter_deviation_m:
            off = off - np.asarray(self.roller_diameter_deviation_m)[None, :]
        if self.surfaces is not None and (self.surfaces.outer.profile_m.size or self.surfaces.outer.orders.size):
            off = off - self.surfaces.heights_m(motion.psi_rad, motion.shaft_angle_rad, motion.spin_rad)
        return off

    def unbalance_force_N(self, t_s: np.ndarray) -> np.ndarray | None:
        """The unbalance's force on the shaft (n, 2) (y, z) at the instants t [N]; None without unbalance."""
        if self.surfaces is None or self.surfaces.unbalance_kg_m == 0:
            return None
        return surface.unbalance_force_N(self.surfaces.unbalance_kg_m, self.surfaces.unbalance_phase_rad,
                                         self.shaft_angle(t_s), self.shaft_speed_at(t_s))

    def defect_max_drops_m(self) -> list[float]:
        """Deepest drop of each defect [m] (a flat: the deeper of its two contacts, the convex inner race)."""
        g = self.geometry
        race = {"outer_race": "outer", "inner_race": "inner", "rolling_element": "inner"}
        return [d.max_drop_m(g.relative_radius_m(race[d.kind])) for d in self.defects]

    def tachometer_times(self, t0_s: float, t1_s: float, pulses_per_rev: int) -> np.ndarray:
        """Instants of a shaft tachometer's pulses in [t0, t1] [s] (pulse k at shaft angle 2 pi k / ppr)."""
        f0, a = self.shaft_speed_Hz, self.speed_ramp_Hz_per_s
        rev = self.shaft_angle(np.array([t0_s, t1_s])) / (2 * np.pi) * pulses_per_rev
        k = np.arange(np.ceil(rev[0]), np.floor(rev[1]) + 1) / pulses_per_rev
        if a == 0:
            return k / f0
        return (-f0 + np.sqrt(f0 * f0 + 2 * a * k)) / a


def roller_deflections(e_m: np.ndarray, psi_rad: np.ndarray, gap_m: float, drop_m: np.ndarray) -> np.ndarray:
    """delta_j = e . n(psi_j) - P_d/2 - drop_j for a shaft offset e = (y, z) relative to the pedestal [m]."""
    return e_m[..., 0:1] * np.sin(psi_rad) - e_m[..., 1:2] * np.cos(psi_rad) - gap_m - drop_m


def bearing_force(
    e_m: np.ndarray, psi_rad: np.ndarray, gap_m: float, drop_m: np.ndarray, k_contact: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Resultant of the roller loads on the pedestal, sum Q_j n_j, and its Jacobian.

    Parameters
    ----------
    e_m : ndarray (2,)
        Shaft displacement relative to the pedestal (y, z) [m].
    psi_rad, drop_m : ndarray (Z,)
        Roller angles [rad] and defect drops [m].
    gap_m : float
        P_d / 2 [m].
    k_contact : float
        K [N / m^(10/9)].

    Returns
    -------
    f_N : ndarray (2,)
        Force of the rollers on the pedestal (and minus that on the shaft) [N].
    jac_N_per_m : ndarray (2, 2)
        d f / d e [N/m].
    q_N : ndarray (Z,)
        Roller loads [N].
    """
    s, c = np.sin(psi_rad), -np.cos(psi_rad)
    delta = e_m[0] * s + e_m[1] * c - gap_m - drop_m
    q, dq = contact_law(delta, k_contact)
    f = np.array([q @ s, q @ c])
    jac = np.array([[dq @ (s * s), dq @ (s * c)], [dq @ (s * c), dq @ (c * c)]])
    return f, jac, q


def static_offset(
    load_N: np.ndarray, psi_rad: np.ndarray, gap_m: float, drop_m: np.ndarray, k_contact: float
) -> np.ndarray:
    """Shaft offset e = (y, z) relative to the pedestal at which the rollers carry ``load_N``.

    Solves sum_j Q_j(e) n_j = load_N by Newton's method with backtracking,
    starting from the offset at which the most loaded roller alone carries the
    load (an overestimate, from which the convex contact law converges).

    Parameters
    ----------
    load_N : ndarray (2,)
        Force of the shaft on the bearing (y, z) [N]; (0, -F_r) for a load along -z.

    Returns
    -------
    ndarray (2,)
        e [m].
    """
    load = np.asarray(load_N, dtype=float)
    mag = float(np.hypot(*load))
    if mag == 0:
        return np.zeros(2)
    u = load / mag
    e = u * (gap_m + float(np.max(drop_m, initial=0.0)) + (mag / k_contact) ** 0.9)
    for _ in range(200):
        f, jac, _ = bearing_force(e, psi_rad, gap_m, drop_m, k_contact)
        r = f - load
        if np.linalg.norm(r) < 1e-10 * mag:
            return e
        if abs(np.linalg.det(jac)) < 1e-30 * max(np.abs(jac).max(), 1.0) ** 2:
            step = np.linalg.lstsq(jac + 1e-3 * np.abs(jac).max() * np.eye(2), -r, rcond=None)[0]
        else:
            step = np.linalg.solve(jac, -r)
        lam = 1.0
        while lam > 1e-6:
            f2, _, _ = bearing_force(e + lam * step, psi_rad, gap_m, drop_m, k_contact)
            if np.linalg.norm(f2 - load) < np.linalg.norm(r):
                break
            lam *= 0.5
        e = e + lam * step
    raise RuntimeError(
        f"static_offset: no equilibrium for the load {load} N (residual {np.linalg.norm(r):.3g} N)"
    )


def harris_discrete_loads(
    radial_load_N: float, psi_rad: np.ndarray, gap_m: float, k_contact: float
) -> tuple[np.ndarray, float]:
    """Harris's discrete load distribution of a radially loaded bearing.

    For roller positions symmetric about the load line the rings shift only
    along the load by delta_r, and each roller carries
    Q_j = K (delta_r cos psi_j - P_d/2)^(10/9); delta_r follows from
    F_r = sum_j Q_j cos psi_j (Harris & Kotzalas, Sec. 7.2), solved here by
    bracketing. An independent implementation for testing the LPM.

    Returns
    -------
    q_N : ndarray
        Roller loads [N].
    delta_r_m : float
        Ring shift along the load [m].
    """
    cos = np.cos(psi_rad)

    def residual(dr):
        return float(np.sum(k_contact * np.maximum(dr * cos - gap_m, 0.0) ** (10 / 9) * cos)) - radial_load_N

    hi = gap_m / cos.max() + (radial_load_N / k_contact) ** 0.9 / cos.max() * 2 + 1e-12
    while residual(hi) < 0:
        hi *= 2
    dr = brentq(residual, gap_m / cos.max(), hi, xtol=1e-18, rtol=1e-14)
    return k_contact * np.maximum(dr * cos - gap_m, 0.0) ** (10 / 9), dr


def contact_half_widths_m(geometry: BearingGeometry, radial_load_N: float) -> dict[str, float]:
    """Hertzian half-width b of the most loaded roller's contacts, outer and inner race [m].

    The most loaded roller's load from Harris's discrete distribution with a roller on the load line
    (:func:`harris_discrete_loads`); b by :func:`piezobearing.bearing.surface.contact_half_width_m`. For the
    N 305 at 500 N: 51 um outside, 41 um inside.
    """
    psi = geometry.roller_pitch_rad * np.arange(geometry.n_rollers)
    k = line_contact_stiffness(geometry.roller_length_m)
    q = float(np.max(harris_discrete_loads(radial_load_N, psi, 0.5 * geometry.radial_clearance_m, k)[0]))
    return {race: surface.contact_half_width_m(q, geometry.relative_radius_m(race), geometry.roller_length_m)
            for race in ("outer", "inner")}


@dataclass(frozen=True)
class LPMResult:
    """Time history of the lumped-parameter model on its integration grid.

    Attributes
    ----------
    time_s : ndarray (n,)
    psi_rad : ndarray (n, Z)
        Roller angles from the load direction [rad].
    load_N : ndarray (n, Z)
        Roller contact loads Q_j [N].
    shaft_m, pedestal_m : ndarray (n, 2)
        Displacements (y, z) of shaft and pedestal [m].
    newton_iterations : int
        Total Newton iterations of the run.
    """

    time_s: np.ndarray
    psi_rad: np.ndarray
    load_N: np.ndarray
    shaft_m: np.ndarray
    pedestal_m: np.ndarray
    newton_iterations: int


def shaft_pedestal_matrices(shaft_mass_kg: float, pedestal_mass_kg: float, bearing_damping_N_s_per_m: float,
                            pedestal_damping_N_s_per_m: float, pedestal_stiffness_N_per_m: float
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass [kg], damping [N s/m] and linear stiffness [N/m] of the 4 DOFs (y_s, z_s, y_p, z_p): the shaft on
    the bearing's damping to the pedestal, the pedestal on its spring and damper (the contacts are the nonlinear
    rest)."""
    i2 = np.eye(2)
    m = np.diag([shaft_mass_kg] * 2 + [pedestal_mass_kg] * 2)
    cb, cp = bearing_damping_N_s_per_m, pedestal_damping_N_s_per_m
    c = np.block([[cb * i2, -cb * i2], [-cb * i2, (cb + cp) * i2]])
    k = np.block([[0 * i2, 0 * i2], [0 * i2, pedestal_stiffness_N_per_m * i2]])
    return m, c, k


def _matrices(p: LPMParameters) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and linear stiffness of the 4 DOFs (y_s, z_s, y_p, z_p) of ``p``."""
    return shaft_pedestal_matrices(p.shaft_mass_kg, p.pedestal_mass_kg, p.bearing_damping_N_s_per_m,
                                   p.pedestal_damping_N_s_per_m, p.pedestal_stiffness_N_per_m)


def lpm_rhs(p: LPMParameters):
    """First-order form y' = f(t, y), y = (u, v) of the 4 DOFs, and its Jacobian, for solve_ivp.

    Returns ``(fun, jac)``; used to cross-check :func:`simulate_lpm` with
    scipy's Radau. ``fun`` builds no Jacobian (Radau calls it about seven
    times as often as ``jac``), and both reuse the roller angles and contact
    offsets of the last instant asked for (``jac`` is evaluated at an instant
    ``fun`` has just seen): the same numbers as before, in 0.45x the CPU.
    """
    m, c, k = _matrices(p)
    minv = np.linalg.inv(m)
    minv_c = minv @ c
    fext = np.array([0.0, -p.radial_load_N, 0.0, 0.0])
    kc, gap = p.k_contact, p.gap_m
    last: list = [None, None, None]  # t, psi, offsets

    def at(t):
        if last[0] != t:
            mo = p.motion(np.array([t]))
            last[:] = t, mo.psi_rad[0], p.contact_offsets(mo)[0]
        return last[1], last[2]

    def fun(t, y):
        u, v = y[:4], y[4:]
        psi, off = at(t)
        f = bearing_force(u[:2] - u[2:], psi, gap, off, kc)[0]
        unbalance = p.unbalance_force_N(np.array([t]))
        fe = fext if unbalance is None else fext + np.r_[unbalance[0], 0.0, 0.0]
        return np.concatenate((v, minv @ (fe - c @ v - k @ u - np.concatenate((f, -f)))))

    def jac(t, y):
        u = y[:4]
        psi, off = at(t)
        dj = bearing_force(u[:2] - u[2:], psi, gap, off, kc)[1]
        dg = np.block([[dj, -dj], [-dj, dj]])
        return np.block([[np.zeros((4, 4)), np.eye(4)], [-minv @ (k + dg), -minv_c]])

    return fun, jac


def simulate_lpm(
    p: LPMParameters,
    t_start_s: float,
    n_steps: int,
    step_s: float,
    tol_m: float = 1e-16,
    method: str = "compiled",
    base_acceleration_m_per_s2: np.ndarray | None = None,
) -> LPMResult:
    """Integrate the 4-DOF model with the implicit trapezoidal rule (Newmark, beta = 1/4, gamma = 1/2).

    .. math::
        m_s \\ddot u_s + c_b(\\dot u_s - \\dot u_p) = F - \\sum_j Q_j n_j - m_s a_b(t), \\qquad
        m_p \\ddot u_p - c_b(\\dot u_s - \\dot u_p) + c_p \\dot u_p + k_p u_p = \\sum_j Q_j n_j - m_p a_b(t)

    with Q_j = K <(u_s - u_p) . n_j - P_d/2 - drop_j>^(10/9) and n_j the
    outward normal at roller j. The contact makes the system stiff (the
    shaft on its rollers rings at ~2 kHz, the pedestal at ~6 kHz, against a
    record of seconds) and non-smooth (contacts open and close; the defect's
    edges): an explicit scheme needs error-controlled tiny steps, so the
    rule here is implicit and A-stable, second order, without numerical
    damping, on a fixed step that resolves the defect passage (~75 steps) and
    the contact resonance (~40 steps a period). Each step solves the 4
    nonlinear equations by Newton's method with the analytic tangent
    (vectorised over the rollers). The run starts from static equilibrium.

    Parameters
    ----------
    p : LPMParameters
    t_start_s : float
        Time of the first sample [s] (negative to let the model settle).
    n_steps : int
        Number of steps; the result has n_steps + 1 samples.
    step_s : float
        Integration step h [s].
    tol_m : float
        Newton tolerance on the displacement update [m].
    method : {"compiled", "python"}
        ``compiled``: the step loop in :mod:`.lpm_kernel` (numba); ``python``:
        the same algorithm as a numpy loop (the reference, ~50x slower; kept
        for the benchmark and as the check of the kernel).
    base_acceleration_m_per_s2 : ndarray (n_steps + 1, 2), optional
        Acceleration a_b (y, z) of the ground (the machine frame under the
        housing's foot) at every step [m/s^2]. The displacements are then
        relative to the ground: the pedestal's spring and damper and the
        radial load's support move with it, each mass feels the inertial
        load -m a_b, and the shaft's pushes on the rollers (the shaft is
        held radially by this bearing only: ``shaft_mass_kg`` is the mass
        it carries). None: a ground at rest.
    """
    if method not in ("compiled", "python"):
        raise ValueError(f"simulate_lpm: method must be 'compiled' or 'python', got {method!r}")
    m, c, k = _matrices(p)
    fext = np.tile(np.array([0.0, -p.radial_load_N, 0.0, 0.0]), (n_steps + 1, 1))
    if base_acceleration_m_per_s2 is not None:
        ab = np.asarray(base_acceleration_m_per_s2, dtype=float)
        if ab.shape != (n_steps + 1, 2):
            raise ValueError(f"simulate_lpm: base acceleration of shape {ab.shape}, expected ({n_steps + 1}, 2)")
        fext[:, :2] -= p.shaft_mass_kg * ab
        fext[:, 2:] -= p.pedestal_mass_kg * ab
    kc, gap = p.k_contact, p.gap_m
    t = t_start_s + step_s * np.arange(n_steps + 1)
    unbalance = p.unbalance_force_N(t)
    if unbalance is not None:
        fext[:, :2] += unbalance
    mo = p.motion(t)
    psi = mo.psi_rad
    drop = p.contact_offsets(mo)
    sn, cn = np.sin(psi), -np.cos(psi)

    # static start: the rollers carry the shaft's load, the pedestal spring the shaft's and its own
    e0 = static_offset(fext[0, :2], psi[0], gap, drop[0], kc)
    up0 = (fext[0, :2] + fext[0, 2:]) / p.pedestal_stiffness_N_per_m
    u = np.r_[up0 + e0, up0]
    if method == "compiled":
        us, q_out, n_iter, failed = newmark_lpm(
            np.ascontiguousarray(sn), np.ascontiguousarray(cn), gap + drop, m, c, k, fext, u, step_s, kc, tol_m, 50
        )
        if failed >= 0:
            raise RuntimeError(f"simulate_lpm: Newton did not converge at t = {t[failed]:.6g} s")
        return LPMResult(t, psi, q_out, us[:, :2], us[:, 2:], int(n_iter))
    v = np.zeros(4)
    a = np.zeros(4)

    h = step_s
    beta, gamma = 0.25, 0.5
    a0, a1 = 1 / (beta * h * h), gamma / (beta * h)
    k_eff_lin = a0 * m + a1 * c + k
    us = np.empty((n_steps + 1, 4))
    q_out = np.empty((n_steps + 1, psi.shape[1]))
    us[0] = u
    q_out[0] = contact_law(e0[0] * sn[0] + e0[1] * cn[0] - gap - drop[0], kc)[0]
    n_iter = 0
    for n in range(1, n_steps + 1):
        s_n, c_n, d_n = sn[n], cn[n], drop[n]
        # Newmark: a(u) = a0 (u - u_n) - a0 h v_n - (1/(2 beta) - 1) a_n, v(u) = v_n + h((1-g) a_n + g a(u))
        ustar = u + h * v + 0.5 * h * h * a
        rhs_const = m @ (a0 * u + a0 * h * v + (0.5 / beta - 1) * a) + c @ (
            a1 * u + (gamma / beta - 1) * v + h * (0.5 * gamma / beta - 1) * a
        )
        x = ustar
        for _ in range(50):
            ey, ez = x[0] - x[2], x[1] - x[3]
            q, dq = contact_law(ey * s_n + ez * c_n - gap - d_n, kc)
            fy, fz = q @ s_n, q @ c_n
            jss, jsc, jcc = dq @ (s_n * s_n), dq @ (s_n * c_n), dq @ (c_n * c_n)
            g = np.array([fy, fz, -fy, -fz])
            r = k_eff_lin @ x - rhs_const + g - fext[n]
            jg = np.array([[jss, jsc], [jsc, jcc]])
            kt = k_eff_lin + np.block([[jg, -jg], [-jg, jg]])
            dx = np.linalg.solve(kt, -r)
            x = x + dx
            n_iter += 1
            if np.abs(dx).max() < tol_m:
                break
        else:
            raise RuntimeError(f"simulate_lpm: Newton did not converge at t = {t[n]:.6g} s")
        a_new = a0 * (x - u) - a0 * h * v - (0.5 / beta - 1) * a
        v = v + h * ((1 - gamma) * a + gamma * a_new)
        a, u = a_new, x
        us[n] = u
        e = u[:2] - u[2:]
        q_out[n] = contact_law(e[0] * s_n + e[1] * c_n - gap - d_n, kc)[0]
    return LPMResult(t, psi, q_out, us[:, :2], us[:, 2:], n_iter)


def resample_loads(
    time_s: np.ndarray, load_N: np.ndarray, t_out_s: np.ndarray, step_s: float, mode: str = "average"
) -> np.ndarray:
    """Roller loads at the FEM's time samples.

    Parameters
    ----------
    time_s, load_N : ndarray (n,), (n, Z)
        The LPM's fine integration grid and roller loads [s, N].
    t_out_s : ndarray (m,)
        Output instants [s]; the fine grid must cover t +- step/2.
    step_s : float
        Output step [s].
    mode : {"average", "sample"}
        ``average``: mean over [t - step/2, t + step/2] (a box filter: it
        keeps the impulse, the integral of the load, of events shorter than
        a step, and damps what would alias); ``sample``: the value at t.

    Returns
    -------
    ndarray (m, Z) [N]
    """
    if mode == "sample":
        return np.stack([np.interp(t_out_s, time_s, q) for q in load_N.T], axis=1)
    if mode != "average":
        raise ValueError(f"config bearing.resample must be 'average' or 'sample', got {mode!r}")
    if t_out_s[0] - step_s / 2 < time_s[0] - 1e-12 or t_out_s[-1] + step_s / 2 > time_s[-1] + 1e-12:
        raise ValueError("resample_loads: the fine grid does not cover the averaging windows")
    h = np.diff(time_s)[:, None]
    cum = np.concatenate(
        [np.zeros((1, load_N.shape[1])), np.cumsum(0.5 * h * (load_N[1:] + load_N[:-1]), axis=0)]
    )
    lo, hi = t_out_s - step_s / 2, t_out_s + step_s / 2
    return np.stack([(np.interp(hi, time_s, c) - np.interp(lo, time_s, c)) / step_s for c in cum.T], axis=1)
