"""The bearing: geometry, kinematic frequencies and the 4-DOF lumped-parameter model.

SKF N 305 ECP cylindrical roller bearing (paper Sec. III-A, IV): 11 rollers,
outer ring stationary in the housing, inner ring turning with the shaft.

Angles
------
Roller and defect positions are angles psi [rad] in the bearing's plane,
measured from the direction of the radial load (the bottom of the bearing,
-z) and increasing with the sense of rotation. The outward unit normal of the
outer raceway at psi is ``n(psi) = (sin psi, -cos psi)`` in the (y, z) plane
of the housing model (y horizontal, z up, x along the shaft).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Palmgren's line-contact constant: delta = 3.84e-5 Q^0.9 / l^0.8 with delta,
#: l in mm and Q in N (Harris & Kotzalas, Rolling Bearing Analysis, Eq. 6.41),
#: converted to SI: delta [m] = PALMGREN_SI * Q^0.9 * l^-0.8 with l in m.
PALMGREN_SI = 3.84e-5 * 1e-3 * 1e3**-0.8


@dataclass(frozen=True)
class BearingGeometry:
    """Geometry of a cylindrical roller bearing.

    Parameters
    ----------
    n_rollers : int
        Number of rollers Z [-].
    roller_diameter_m : float
        Roller diameter D_r [m].
    pitch_diameter_m : float
        Pitch (cage) diameter D_p [m].
    roller_length_m : float
        Effective contact length l of a roller [m].
    radial_clearance_m : float
        Radial internal clearance P_d [m]: the total radial play of one ring
        against the other (ISO 5753-1; Harris's diametral clearance). Each
        roller sees the gap P_d / 2 when the rings are concentric.
    outer_diameter_m : float
        Outer diameter of the outer ring D [m].
    width_m : float
        Width of the bearing B [m].
    contact_angle_deg : float
        Contact angle alpha [deg]; 0 for a cylindrical roller bearing.
    """

    n_rollers: int
    roller_diameter_m: float
    pitch_diameter_m: float
    roller_length_m: float
    radial_clearance_m: float
    outer_diameter_m: float
    width_m: float
    contact_angle_deg: float = 0.0

    @classmethod
    def from_config(cls, bearing: dict) -> BearingGeometry:
        """From the ``bearing`` section of the config."""
        keys = (
            "n_rollers roller_diameter_m pitch_diameter_m roller_length_m radial_clearance_m "
            "outer_diameter_m width_m contact_angle_deg"
        ).split()
        geo = cls(**{k: bearing[k] for k in keys})
        if geo.outer_raceway_radius_m >= geo.outer_diameter_m / 2:
            raise ValueError(
                "config bearing: pitch_diameter_m + roller_diameter_m must be smaller than outer_diameter_m "
                "(the outer raceway must lie inside the outer ring)"
            )
        return geo

    @property
    def diameter_ratio(self) -> float:
        """D_r cos(alpha) / D_p [-]."""
        return float(
            self.roller_diameter_m * np.cos(np.radians(self.contact_angle_deg)) / self.pitch_diameter_m
        )

    @property
    def outer_raceway_radius_m(self) -> float:
        """Radius of the outer raceway, (D_p + D_r) / 2 [m]."""
        return 0.5 * (self.pitch_diameter_m + self.roller_diameter_m)

    @property
    def roller_pitch_rad(self) -> float:
        """Angle between neighbouring rollers, 2 pi / Z [rad]."""
        return 2 * np.pi / self.n_rollers


@dataclass(frozen=True)
class KinematicFrequencies:
    """Kinematic frequencies of a bearing with a stationary outer ring [Hz].

    Attributes
    ----------
    shaft_Hz : float
        Shaft (inner ring) rotation frequency f_r.
    ftf_Hz : float
        Fundamental train (cage) frequency, f_r / 2 (1 - D_r cos a / D_p).
    bpfo_Hz : float
        Ball (roller) pass frequency on the outer race, Z * FTF.
    bpfi_Hz : float
        Roller pass frequency on the inner race, Z (f_r - FTF).
    bsf_Hz : float
        Roller spin frequency, D_p / (2 D_r) f_r (1 - (D_r cos a / D_p)^2).
    """

    shaft_Hz: float
    ftf_Hz: float
    bpfo_Hz: float
    bpfi_Hz: float
    bsf_Hz: float

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")}


def kinematic_frequencies(geometry: BearingGeometry, shaft_speed_Hz: float) -> KinematicFrequencies:
    """Kinematic frequencies for rolling without slip, outer ring fixed.

    Parameters
    ----------
    geometry : BearingGeometry
    shaft_speed_Hz : float
        Rotation frequency of the shaft and inner ring [Hz].

    Returns
    -------
    KinematicFrequencies
        shaft, FTF (cage), BPFO, BPFI and BSF [Hz]. For the N 305 ECP at
        1000 rpm (Z = 11, D_r / D_p = 10 / 44) the BPFO is 70.83 Hz.
    """
    g, z = geometry.diameter_ratio, geometry.n_rollers
    fr = float(shaft_speed_Hz)
    ftf = 0.5 * fr * (1 - g)
    return KinematicFrequencies(
        shaft_Hz=fr,
        ftf_Hz=ftf,
        bpfo_Hz=z * ftf,
        bpfi_Hz=z * (fr - ftf),
        bsf_Hz=0.5 * geometry.pitch_diameter_m / geometry.roller_diameter_m * fr * (1 - g**2),
    )


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
    d19 = d ** (1 / 9)
    return k_contact * d * d19, (10 / 9) * k_contact * d19


@dataclass(frozen=True)
class Defect:
    """A local defect of the outer raceway: a transverse groove with sharp edges.

    Parameters
    ----------
    angle_rad : float
        Centre of the defect, from the load direction [rad].
    width_m : float
        Circumferential width w [m].
    depth_m : float
        Depth of the removed material [m].
    """

    angle_rad: float
    width_m: float
    depth_m: float

    def max_drop_m(self, roller_radius_m: float) -> float:
        """Deepest a roller of radius r can sink: min(depth, r - sqrt(r^2 - (w/2)^2)) [m]."""
        r, hw = roller_radius_m, 0.5 * self.width_m
        if hw >= r:
            return self.depth_m
        return min(self.depth_m, r - np.sqrt(r * r - hw * hw))

    def drop_m(self, psi_rad: np.ndarray, roller_radius_m: float, raceway_radius_m: float) -> np.ndarray:
        """Radial drop of roller centres at angles psi into the groove [m].

        A roller whose centre is the arc length u past the entry edge (0 <= u
        <= w) rests on the nearer of the two edges: its centre sinks by
        ``r - sqrt(r^2 - min(u, w - u)^2)``, capped at the depth. Entry and
        exit are the two circular flanks of this profile; the drop is 0 outside
        the groove and greatest, :meth:`max_drop_m`, at the centre.
        """
        dpsi = np.angle(np.exp(1j * (np.asarray(psi_rad) - self.angle_rad)))
        u = raceway_radius_m * dpsi + 0.5 * self.width_m
        inside = (u > 0) & (u < self.width_m)
        m = np.minimum(u, self.width_m - u)
        r = roller_radius_m
        drop = r - np.sqrt(np.maximum(r * r - m * m, 0.0))
        return np.where(inside, np.minimum(drop, self.depth_m), 0.0)


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
        Shaft speed [Hz].
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
    defect : Defect or None
        The outer-race defect; None for the healthy bearing.
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
    defect: Defect | None = None

    @classmethod
    def from_config(cls, bearing: dict, faulty: bool) -> LPMParameters:
        """From the ``bearing`` section; ``faulty`` adds its defect."""
        b = bearing
        defect = None
        if faulty:
            defect = Defect(np.radians(b["defect_angle_deg"]), b["defect_width_m"], b["defect_depth_m"])
        return cls(
            geometry=BearingGeometry.from_config(b),
            radial_load_N=b["radial_load_N"],
            shaft_speed_Hz=b["shaft_speed_rpm"] / 60.0,
            shaft_mass_kg=b["shaft_mass_kg"],
            pedestal_mass_kg=b["pedestal_mass_kg"],
            pedestal_stiffness_N_per_m=b["pedestal_stiffness_N_per_m"],
            bearing_damping_N_s_per_m=b["bearing_damping_N_s_per_m"],
            pedestal_damping_N_s_per_m=b["pedestal_damping_N_s_per_m"],
            start_angle_rad=np.radians(b["start_angle_deg"]),
            defect=defect,
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
        """Angular speed of the cage, 2 pi FTF [rad/s]."""
        return 2 * np.pi * kinematic_frequencies(self.geometry, self.shaft_speed_Hz).ftf_Hz

    def roller_angles(self, t_s: np.ndarray) -> np.ndarray:
        """Roller angles psi_j(t) from the load direction, wrapped to [-pi, pi) [rad], shape (n_t, Z)."""
        g = self.geometry
        psi = (
            self.start_angle_rad
            + g.roller_pitch_rad * np.arange(g.n_rollers)[None, :]
            + self.cage_speed_rad_per_s * np.asarray(t_s, dtype=float)[:, None]
        )
        return np.mod(psi + np.pi, 2 * np.pi) - np.pi

    def drops(self, psi_rad: np.ndarray) -> np.ndarray:
        """Defect drop of every roller [m] (zeros when healthy)."""
        if self.defect is None:
            return np.zeros_like(psi_rad)
        g = self.geometry
        return self.defect.drop_m(psi_rad, 0.5 * g.roller_diameter_m, g.outer_raceway_radius_m)


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
    from scipy.optimize import brentq

    cos = np.cos(psi_rad)

    def residual(dr):
        return float(np.sum(k_contact * np.maximum(dr * cos - gap_m, 0.0) ** (10 / 9) * cos)) - radial_load_N

    hi = gap_m / cos.max() + (radial_load_N / k_contact) ** 0.9 / cos.max() * 2 + 1e-12
    while residual(hi) < 0:
        hi *= 2
    dr = brentq(residual, gap_m / cos.max(), hi, xtol=1e-18, rtol=1e-14)
    return k_contact * np.maximum(dr * cos - gap_m, 0.0) ** (10 / 9), dr


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


def _matrices(p: LPMParameters) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and linear stiffness of the 4 DOFs (y_s, z_s, y_p, z_p)."""
    i2 = np.eye(2)
    m = np.diag([p.shaft_mass_kg] * 2 + [p.pedestal_mass_kg] * 2)
    cb, cp = p.bearing_damping_N_s_per_m, p.pedestal_damping_N_s_per_m
    c = np.block([[cb * i2, -cb * i2], [-cb * i2, (cb + cp) * i2]])
    k = np.block([[0 * i2, 0 * i2], [0 * i2, p.pedestal_stiffness_N_per_m * i2]])
    return m, c, k


def lpm_rhs(p: LPMParameters):
    """First-order form y' = f(t, y), y = (u, v) of the 4 DOFs, and its Jacobian, for solve_ivp.

    Returns ``(fun, jac)``; used to cross-check :func:`simulate_lpm` with
    scipy's Radau.
    """
    m, c, k = _matrices(p)
    minv = np.linalg.inv(m)
    fext = np.array([0.0, -p.radial_load_N, 0.0, 0.0])
    kc, gap = p.k_contact, p.gap_m

    def forces(t, u):
        psi = p.roller_angles(np.array([t]))[0]
        f, jac, _ = bearing_force(u[:2] - u[2:], psi, gap, p.drops(psi), kc)
        g = np.r_[f, -f]
        dg = np.block([[jac, -jac], [-jac, jac]])
        return g, dg

    def fun(t, y):
        u, v = y[:4], y[4:]
        g, _ = forces(t, u)
        return np.r_[v, minv @ (fext - c @ v - k @ u - g)]

    def jac(t, y):
        _, dg = forces(t, y[:4])
        return np.block([[np.zeros((4, 4)), np.eye(4)], [-minv @ (k + dg), -minv @ c]])

    return fun, jac


def simulate_lpm(
    p: LPMParameters,
    t_start_s: float,
    n_steps: int,
    step_s: float,
    tol_m: float = 1e-16,
    method: str = "compiled",
) -> LPMResult:
    """Integrate the 4-DOF model with the implicit trapezoidal rule (Newmark, beta = 1/4, gamma = 1/2).

    .. math::
        m_s \\ddot u_s + c_b(\\dot u_s - \\dot u_p) = F - \\sum_j Q_j n_j, \\qquad
        m_p \\ddot u_p - c_b(\\dot u_s - \\dot u_p) + c_p \\dot u_p + k_p u_p = \\sum_j Q_j n_j

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
    """
    if method not in ("compiled", "python"):
        raise ValueError(f"simulate_lpm: method must be 'compiled' or 'python', got {method!r}")
    m, c, k = _matrices(p)
    fext = np.array([0.0, -p.radial_load_N, 0.0, 0.0])
    kc, gap = p.k_contact, p.gap_m
    t = t_start_s + step_s * np.arange(n_steps + 1)
    psi = p.roller_angles(t)
    drop = p.drops(psi)
    sn, cn = np.sin(psi), -np.cos(psi)

    # static start: rollers carry F_r, the pedestal spring carries F_r
    e0 = static_offset(fext[:2], psi[0], gap, drop[0], kc)
    up0 = fext[:2] / p.pedestal_stiffness_N_per_m
    u = np.r_[up0 + e0, up0]
    if method == "compiled":
        from .lpm_kernel import newmark_lpm

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
            r = k_eff_lin @ x - rhs_const + g - fext
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
