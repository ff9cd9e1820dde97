r"""The fast forward model of the running bearing: quasi-static load distribution times influence line.

Where the housing is quasi-static (its first mode well above the band the
record holds, see docs/theory/bearing_housing.md), the sensor force is

.. math::  F_s(t) = \sum_{j=1}^{Z} Q_j(t)\, g(\psi_j(t)),

the roller loads Q_j times the housing's influence line g (sensor force per
newton of outward radial roller load at the angle psi; one solve of the
housing FEM by reciprocity, :meth:`piezobearing.housing.fem.HousingModel.influence_line`).
The roller loads come from the quasi-static equilibrium of the rings,

.. math::  \sum_j Q_j(e)\, n(\psi_j) = (0, -F_r),\qquad
           Q_j = K \langle e \cdot n(\psi_j) - P_d/2 - d_j \rangle^{10/9},

solved for the shaft offset e by Newton's method, vectorised over all time
samples at once; d_j is the defect's drop of roller j (0 when healthy). The
LPM's inertia and damping are left out: its shaft-on-rollers mode (~2 kHz)
is what this model cannot carry (checked against the full LPM + housing
chain in ``benchmarks/bench_surrogate.py``, numbers in docs/theory/bearing_housing.md).

Healthy, and with an outer-race defect (stationary, like the sensor), the
whole configuration repeats every roller pitch of cage angle, so F_s is a
periodic function of the cage phase phi alone: it is tabulated once over one
pitch, and a record at any speed, slip, start phase or tachometer profile is
a table look-up. A DAQ sample is the mean of F_s over its interval (a box
filter, as the workflow averages the LPM's loads), computed exactly from the
table's running integral. Defects that move with the shaft or a roller
(inner race, rolling element) are solved on a fine time grid where they
touch a roller, the healthy table elsewhere.

Size. Over 600 lines as one module: the equilibrium (Newton's method and its soft-direction step,
with the compiled kernel's entry), the load tables and the defect geometries are read together when a
table is wrong; the defect drop functions are candidates to move to a module of their own.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, NamedTuple

import numpy as np

from .geometry import BearingGeometry, kinematic_frequencies
from .lpm import chord_drop_m, contact_law, line_contact_stiffness
from .surrogate_kernel import newton_rows

#: Points of the cage-phase table over one roller pitch.
TABLE_POINTS = 4096
#: Relative force tolerance of a groove-free table's equilibrium. A fit's finite-difference step (a roller's
#: offset by 3e-14 m) moves the loads by about 1e-8 F_r: the table's error must be far below that, and the
#: same whether it was solved from the nominal start or from a nearby table's offsets (:data:`WARM_START_REL`).
TABLE_TOL = 1e-12
#: A groove-free table whose load, clearance and roller offsets are within this share (of the load, and of the
#: clearance) of an earlier table's starts Newton's method at that table's shaft offsets: 2-3 evaluations of
#: the equilibrium instead of 6-17 for a fit's finite-difference step, 5-10 instead of 29-43 for a trial load
#: near 180 N (few rollers loaded); farther away the nominal start is as fast, at 30% of clearance 3x faster.
WARM_START_REL = 1e-2
#: A table with a drop function other than an :class:`OuterGroove` is this many times finer (the groove's
#: edges are kinks that a coarse table would put at grid points: a bias of the fitted angle of about one
#: table step); over a cage turn (with roller scatter) twice.
GROOVE_REFINE = 16
#: Points per roller pitch of the table over a cage turn (roller scatter, no groove).
SCATTER_POINTS = 256
#: The table's points across one roller's passage over an outer-race groove (edges and centre included:
#: the drop's kinks) are this share of the healthy table's spacing apart, and at least 257 (321 across a
#: 0.6 mm groove: the record's voltage within 2.4e-6 of its rms of a table 8 times finer, 2e-5 with 129;
#: box averages within 1e-4 of the groove's dip of a uniform table 16 times finer, tests/test_surrogate.py).
GROOVE_SPACING = 0.5


@dataclass(frozen=True)
class InfluenceLine:
    """Sensor force per newton of outward radial roller load against the roller's angle.

    Parameters
    ----------
    angle_rad : ndarray
        Angles from the load direction (the sensor is at 0) [rad], any order, within one turn.
    sensor_per_radial_load : ndarray
        g(psi) [N/N].
    """

    angle_rad: np.ndarray
    sensor_per_radial_load: np.ndarray
    _sorted: tuple = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        a = np.mod(np.asarray(self.angle_rad, dtype=float), 2 * np.pi)
        order = np.argsort(a)
        a, g = a[order], np.asarray(self.sensor_per_radial_load, dtype=float)[order]
        # periodic closure for np.interp
        a = np.concatenate([a[-1:] - 2 * np.pi, a, a[:1] + 2 * np.pi])
        g = np.concatenate([g[-1:], g, g[:1]])
        object.__setattr__(self, "_sorted", (a, g))

    def __call__(self, psi_rad: np.ndarray) -> np.ndarray:
        """g(psi) [N/N], periodic in psi."""
        a, g = self._sorted
        return np.interp(np.mod(psi_rad, 2 * np.pi), a, g)


@dataclass(frozen=True)
class Operating:
    """The operating point the surrogate runs at.

    Parameters
    ----------
    radial_load_N : float
        Radial load F_r on the shaft, along -z [N].
    radial_clearance_m : float
        Radial internal clearance P_d (total play) [m].
    """

    radial_load_N: float
    radial_clearance_m: float


class NoEquilibriumError(RuntimeError):
    """Newton's method left rows of :func:`quasi_static_loads` short of the equilibrium after its steps.

    The potential is convex and grows in every direction (rollers all round), so an equilibrium exists at
    every load and clearance; this says the iteration failed. The diagnosis's fit treats the point as
    infeasible (the search steps back) instead of stopping.
    """


def _normals(psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.sin(psi), -np.cos(psi)


def quasi_static_loads(
    psi_rad: np.ndarray,
    drop_m: np.ndarray,
    radial_load_N: float,
    gap_m: float,
    k_contact: float,
    tol_N: float = 1e-9,
    e0_m: np.ndarray | None = None,
    return_offset: bool = False,
    normals: tuple[np.ndarray, np.ndarray] | None = None,
    method: str = "compiled",
) -> np.ndarray:
    """Roller loads Q (n, Z) [N] of the quasi-static equilibrium at every row of roller angles.

    The equilibrium sum_j Q_j(e) n_j = (0, -F_r) is the minimum of the
    convex potential

    .. math::  \\Pi(e) = \\sum_j \\tfrac{9}{19} K \\langle\\delta_j(e)\\rangle^{19/9} - L \\cdot e,

    whose gradient is the force residual and whose Hessian sum_j dQ_j n_j n_j^T
    is the contact stiffness. Newton's method with an Armijo line search on
    Pi converges from any start (accepting a step that lowers Pi or the residual; the LPM's :func:`~piezobearing.bearing.lpm.static_offset`,
    which backtracks on the residual's norm, can stall where a roller stands
    in a deep groove at the bottom); it runs vectorised over the rows. Where
    the Hessian is singular (the shaft on one roller, or on none), Pi is
    linear along the soft direction up to the next roller's contact, and the
    step goes there (:func:`_newton_step`). Rows still short of the tolerance
    after 200 steps raise :class:`NoEquilibriumError`.

    Parameters
    ----------
    psi_rad, drop_m : ndarray (n, Z)
        Roller angles from the load direction [rad] and extra gaps (defect drops, smaller rollers) [m].
    radial_load_N : float
        F_r [N].
    gap_m : float
        P_d / 2 [m].
    k_contact : float
        K [N / m^(10/9)].
    tol_N : float
        Relative force tolerance of the equilibrium [-].
    e0_m : ndarray (n, 2), optional
        Start offsets (e.g. the healthy equilibrium next to a defect's) [m].
    return_offset : bool
        Also return the shaft offsets e (n, 2) [m].
    normals : (ndarray, ndarray), optional
        sin psi and -cos psi when the caller holds them (a table's fixed grid).
    method : {"compiled", "numpy"}
        ``compiled``: each row's Newton loop in :mod:`.surrogate_kernel` (numba, the same steps; loads within
        the tolerance, benchmarks/bench_surrogate.py); ``numpy``: vectorised over the
        rows (the reference, kept for the benchmark and as the check of the kernel).
    """
    if method not in ("compiled", "numpy"):
        raise ValueError(f"quasi_static_loads: method must be 'compiled' or 'numpy', got {method!r}")
    psi = np.atleast_2d(psi_rad)
    drop = np.broadcast_to(drop_m, psi.shape)
    s, c = _normals(psi) if normals is None else normals
    load = np.array([0.0, -radial_load_N])
    n = psi.shape[0]
    e = np.zeros((n, 2))
    d1 = (radial_load_N / k_contact) ** 0.9  # one roller's deflection under F_r [m]
    # the cold start: the shaft on the bottom roller (on the load line with a preload, gap < 0: its equilibrium
    # is within a deflection of the centre); the longest Newton step: twice the gap, drops and deflection (twice
    # the cold start's distance from the centre where the gap and the drops are >= 0) [m]
    e[:, 1] = -(max(gap_m, 0.0) + drop.max(axis=1) + d1)
    reach = 2.0 * (abs(gap_m) + np.abs(drop).max(axis=1) + d1)
    if e0_m is not None:
        e = np.array(e0_m, dtype=float).reshape(n, 2)
    if method == "compiled":
        return _compiled(s, c, drop, e, reach, radial_load_N, gap_m, k_contact, tol_N, return_offset)
    f, q, dq, pot = _state(e, s, c, drop, gap_m, k_contact, load)
    for _ in range(200):
        norm = np.hypot(f[:, 0], f[:, 1])
        active = norm > tol_N * radial_load_N
        n_active = int(np.count_nonzero(active))
        if not n_active:
            return (q, e) if return_offset else q
        idx = ALL if n_active == n else np.flatnonzero(active)  # all rows: views, not copies (the same numbers)
        si, ci, di = s[idx], c[idx], drop[idx]  # the rows' copies once per step, not once per trial
        dqs, dqc = dq[idx] * si, dq[idx] * ci
        a = np.sum(dqs * si, 1)
        b = np.sum(dqs * ci, 1)
        d = np.sum(dqc * ci, 1)
        fy, fz = f[idx, 0], f[idx, 1]
        step = _newton_step(a, b, d, fy, fz, e[idx], si, ci, di, gap_m, k_contact, radial_load_N)
        # at most twice the reach of the start (a roller lifted into a groove leaves only the regularisation's
        # stiffness along it: a Newton step of millimetres, halved ten times by the line search)
        length = np.hypot(step[:, 0], step[:, 1])
        step *= np.minimum(1.0, reach[idx] / np.maximum(length, 1e-300))[:, None]
        slope = np.sum(f[idx] * step, 1)  # directional derivative of Pi, < 0
        trial, ft, qt, dqt, pt = _line_search(e[idx], step, slope, pot[idx], norm[idx], si, ci, di, gap_m, k_contact,
                                              load)
        e[idx] = trial
        f[idx], q[idx], dq[idx], pot[idx] = ft, qt, dqt, pt
    norm = np.hypot(f[:, 0], f[:, 1])
    raise NoEquilibriumError(
        f"quasi_static_loads: no equilibrium for {int((norm > tol_N * radial_load_N).sum())} of {n} roller "
        f"configurations at F_r = {radial_load_N} N"
    )


#: Condition of the contact stiffness (Hessian) above which a row is treated as singular (a shaft resting on one
#: roller, a roller lifted into a groove, no roller in contact): :func:`_newton_step`.
SINGULAR = 1e-6


def _newton_step(a, b, d, fy, fz, e, si, ci, drop, gap_m, k_contact, radial_load_N):
    """The rows' Newton steps (n, 2) [m] for the contact stiffness [[a, b], [b, d]] and the force residual (fy, fz).

    Where the stiffness is regular, the exact Newton step. Where it is near singular (a shaft resting on one
    roller: no stiffness across that roller's normal; no roller in contact: none at all), the potential along
    the soft direction is linear until the next roller engages, and a Newton step of a regularised Hessian
    creeps along it (a step of 12 nm where 3 um are needed at 11.8 N: no equilibrium in 200 steps). There the
    step is Newton's along the stiff direction, plus a move down the soft direction to just past the first
    roller it brings into contact (by one roller's deflection under F_r, at most as far again): the next step
    has two rollers and is regular.
    """
    tr = a + d
    det = a * d - b * b
    regular = det > SINGULAR * tr * tr
    out = np.empty((a.size, 2))
    safe = np.where(regular, det, 1.0)
    out[:, 0] = -(d * fy - b * fz) / safe
    out[:, 1] = -(-b * fy + a * fz) / safe
    sing = np.flatnonzero(~regular)
    if sing.size:
        step, found = _soft_step(a[sing], b[sing], d[sing], fy[sing], fz[sing], e[sing], si[sing], ci[sing],
                                 drop[sing], gap_m, k_contact, radial_load_N)
        # no roller ahead (not for rollers all round): a floor of stiffness, the step capped by the caller's reach
        reg = 1e-9 * tr[sing] + 1e-3 * k_contact * 1e-6 ** (1 / 9)
        ar, dr, bs = a[sing] + reg, d[sing] + reg, b[sing]
        dt = ar * dr - bs * bs
        fys, fzs = fy[sing], fz[sing]
        fallback = -np.stack([(dr * fys - bs * fzs) / dt, (-bs * fys + ar * fzs) / dt], 1)
        out[sing] = np.where(found[:, None], step, fallback)
    return out


def _soft_step(a, b, d, fy, fz, e, si, ci, drop, gap_m, k_contact, radial_load_N):
    """:func:`_newton_step` of the near-singular rows (n, 2) [m], and whether a roller ahead was found (n,)."""
    tr = a + d
    lam = 0.5 * tr + np.sqrt(0.25 * (a - d) ** 2 + b * b)  # the stiff eigenvalue [N/m]
    # its unit eigenvector (lam - d, b) or (b, lam - a), whichever is longer; (1, 0) without any stiffness
    u1 = np.where(np.abs(lam - d) >= np.abs(lam - a), lam - d, b)
    u2 = np.where(np.abs(lam - d) >= np.abs(lam - a), b, lam - a)
    nu = np.hypot(u1, u2)
    none = nu <= 0.0
    u1, u2 = np.where(none, 1.0, u1 / np.where(none, 1.0, nu)), np.where(none, 0.0, u2 / np.where(none, 1.0, nu))
    stiff = np.where(lam > 0.0, (fy * u1 + fz * u2) / np.where(lam > 0.0, lam, 1.0), 0.0)
    base = -stiff[:, None] * np.stack([u1, u2], 1)
    # down the soft direction v (the force along it): without stiffness at all, down the whole force
    v1, v2 = -u2, u1
    gv = fy * v1 + fz * v2
    sign = -np.sign(gv)
    dy, dz = np.where(lam > 0.0, sign * v1, -fy), np.where(lam > 0.0, sign * v2, -fz)
    dn = np.hypot(dy, dz)
    dn = np.where(dn > 0.0, dn, 1.0)
    dy, dz = dy / dn, dz / dn
    ey, ez = e[:, :1] + base[:, :1], e[:, 1:] + base[:, 1:]
    delta = ey * si + ez * ci - gap_m - drop  # the rollers' overlap after the stiff part [m]
    rate = dy[:, None] * si + dz[:, None] * ci  # d delta / d t along the soft direction [-]
    t = np.where((delta < 0.0) & (rate > 0.0), -delta / np.where(rate > 0.0, rate, 1.0), np.inf)
    j = np.argmin(t, axis=1)
    rows = np.arange(t.shape[0])
    t_in, r_in = t[rows, j], rate[rows, j]
    d1 = (radial_load_N / k_contact) ** 0.9  # one roller's deflection under F_r [m]
    past = np.minimum(d1 / np.where(r_in > 0.0, r_in, 1.0), np.where(np.isfinite(t_in), t_in, 0.0))
    moving = (gv != 0.0) | (lam <= 0.0)  # a force along the soft direction (or no stiffness at all)
    found = np.isfinite(t_in) | ~moving
    length = np.where(moving & np.isfinite(t_in), t_in + past, 0.0)
    return base + length[:, None] * np.stack([dy, dz], 1), found


def _compiled(s, c, drop, e, reach, radial_load_N, gap_m, k_contact, tol_N, return_offset):
    """:func:`quasi_static_loads` by :func:`.surrogate_kernel.newton_rows` (one compiled signature: contiguous,
    writable float arrays)."""
    def arr(x):
        x = np.ascontiguousarray(x, dtype=float)
        return x if x.flags.writeable else x.copy()

    s, c, drop, e = arr(s), arr(c), arr(drop), arr(e)  # e: the caller's own copy, overwritten
    q = np.empty(s.shape)
    thr = tol_N * radial_load_N
    norm, _ = newton_rows(s, c, drop, e, arr(reach), float(gap_m), float(k_contact), float(radial_load_N), thr,
                          1e-3 * k_contact * 1e-6 ** (1 / 9), q)
    if not np.any(norm > thr):
        return (q, e) if return_offset else q
    raise NoEquilibriumError(
        f"quasi_static_loads: no equilibrium for {int((norm > thr).sum())} of {e.shape[0]} roller "
        f"configurations at F_r = {radial_load_N} N"
    )


def _line_search(e, step, slope, pot, norm, si, ci, drop, gap_m, k_contact, load):
    """The rows' Newton trials e + lam step and their :func:`_state`: Armijo on Pi, or a smaller residual
    (near the solution Pi's rounding hides the decrease). A rejected full step is next tried at
    :func:`_engage_cut`, then halved; each trial solves only the rows still rejected (the others keep theirs)."""
    lam = np.ones(e.shape[0])
    trial = e + step
    ft, qt, dqt, pt = _state(trial, si, ci, drop, gap_m, k_contact, load)
    bad = (pt > pot + 1e-4 * lam * slope) & (np.hypot(ft[:, 0], ft[:, 1]) >= norm)
    cut = None
    for _ in range(59):
        if not bad.any():
            break
        if cut is None:
            cut = _engage_cut(e, step, si, ci, drop, gap_m)
        lam = np.where(bad, cut * lam, lam)
        cut = 0.5
        r = np.flatnonzero(bad)
        trial[r] = e[r] + lam[r, None] * step[r]
        ft[r], qt[r], dqt[r], pt[r] = _state(trial[r], si[r], ci[r], drop[r], gap_m, k_contact, load)
        bad[:] = False
        bad[r] = (pt[r] > pot[r] + 1e-4 * lam[r] * slope[r]) & (np.hypot(ft[r, 0], ft[r, 1]) >= norm[r])
    return trial, ft, qt, dqt, pt


def _engage_cut(e, step, si, ci, drop, gap_m):
    """The share of a rejected full Newton step to try next (rows): just past the first roller the step brings
    into contact (x 1.1), within [0.01, 0.5] [-].

    Newton's Hessian knows only the rollers loaded at e; a step that presses on unloaded ones overshoots (a
    roller lifted into a groove: 4-5 halvings of the line search per step, one cut with this).
    """
    sn = step[:, :1] * si + step[:, 1:] * ci  # d delta / d lam [m]
    d0 = e[:, :1] * si + e[:, 1:] * ci - gap_m - drop
    engage = np.where((d0 < 0) & (sn > 0), -d0 / np.where(sn > 0, sn, 1.0), np.inf).min(1)
    return np.clip(1.1 * engage, 0.01, 0.5)


#: Every row (an index of the Newton loop that takes views, not copies).
ALL = slice(None)


def _state(e, si, ci, drop, gap_m, k_contact, load):
    """Force residual, loads, slopes and potential at offsets e (n, 2) of rows with normals si, ci and extra
    gaps drop (n, Z)."""
    delta = e[:, :1] * si + e[:, 1:] * ci - gap_m - drop
    q, dq = contact_law(delta, k_contact)
    pot = np.sum(q * delta, 1) * (9 / 19) - e @ load  # q = 0 where delta <= 0: q <delta> bit for bit
    return np.stack([np.sum(q * si, 1), np.sum(q * ci, 1)], 1) - load, q, dq, pot


class Table(NamedTuple):
    """F_s tabulated over one period of cage phase (closed: the last point is the first, a period on).

    Attributes
    ----------
    force : ndarray
        F_s at the phases [N].
    integral : ndarray
        Its running integral from phase 0 (trapezoidal, exact for the linear table) [N rad].
    period : float
        A roller pitch, or a cage turn with roller scatter [rad].
    phase : ndarray
        The table's cage phases, increasing from 0 to the period [rad].
    loaded, offset : ndarray or None
        Without a groove: which rollers carry load (n, Z) and the shaft offset (n, 2) [m] at the phases.
    """

    force: np.ndarray
    integral: np.ndarray
    period: float
    phase: np.ndarray
    loaded: np.ndarray | None = None
    offset: np.ndarray | None = None


def running_integral(phase: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Trapezoidal running integral of f over the phases, 0 at the first [N rad]."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(phase))])


@dataclass(frozen=True)
class Surrogate:
    """The quasi-static model of one bearing in one housing.

    Parameters
    ----------
    geometry : BearingGeometry
    influence : InfluenceLine
    table_points : int
        Points of the cage-phase table over one roller pitch.
    """

    geometry: BearingGeometry
    influence: InfluenceLine
    table_points: int = TABLE_POINTS
    _cache: dict = field(default_factory=dict, compare=False, repr=False, hash=False)
    #: The healthy table's phase grid: phases, roller angles, their normals and influence (the same at every
    #: operating point).
    _grid: dict = field(default_factory=dict, compare=False, repr=False, hash=False)

    @property
    def k_contact(self) -> float:
        return line_contact_stiffness(self.geometry.roller_length_m)

    def roller_angles(self, cage_phase_rad: np.ndarray) -> np.ndarray:
        """psi_j = phi + j 2 pi / Z for cage phases phi (n,) -> (n, Z) [rad]."""
        z = self.geometry.n_rollers
        return np.asarray(cage_phase_rad, dtype=float)[:, None] + self.geometry.roller_pitch_rad * np.arange(z)

    def sensor_force_at(
        self, cage_phase_rad: np.ndarray, op: Operating, drop_m: np.ndarray | float = 0.0, e0_m=None, tol_N=1e-9
    ) -> tuple[np.ndarray, np.ndarray]:
        """Sensor force [N] and roller loads (n, Z) [N] at cage phases phi (roller 0 at phi)."""
        psi = self.roller_angles(cage_phase_rad)
        q = quasi_static_loads(
            psi, drop_m, op.radial_load_N, 0.5 * op.radial_clearance_m, self.k_contact, tol_N, e0_m=e0_m
        )
        return np.sum(q * self.influence(psi), axis=1), q

    def table(
        self,
        op: Operating,
        outer_drop: Callable[[np.ndarray], np.ndarray] | None = None,
        key=None,
        offsets_m: tuple[float, ...] | None = None,
    ) -> Table:
        """F_s over one period of cage phase and its running integral (a :class:`Table`).

        ``outer_drop(psi)`` is the drop [m] of a stationary (outer-race)
        defect at roller angles psi; ``key`` identifies it for the cache.
        ``offsets_m`` (Z,) are per-roller reductions of the roller diameter
        (roller scatter, [m]; an oversize roller is negative): they add to
        each roller's gap, and the period becomes a whole cage turn instead
        of one roller pitch. The table is closed (its last point, at the
        period, equals the first) and linear between its points.

        Without a groove the phases are uniform. With an :class:`OuterGroove`
        the phases at which a roller stands in the groove are replaced by
        :data:`GROOVE_SPACING` points across each passage, aligned with the
        groove: its edges and its centre (the kinks of the drop) are table
        points, so a change of the groove's angle or width moves the table
        smoothly (no bias of a grid step, smooth finite differences). Any
        other drop function: a uniform grid :data:`GROOVE_REFINE` times finer.
        """
        offsets = None if offsets_m is None or not np.any(offsets_m) else tuple(float(o) for o in offsets_m)
        ck = ("table", op, key, offsets)
        hit = self._cache.get(ck)
        if hit is not None:
            return hit
        if outer_drop is None:
            out = self._healthy_table(op, offsets)
        else:
            out = self._groove_table(op, outer_drop, offsets)
        self._cache[ck] = out
        while len(self._cache) > 16:
            self._cache.pop(next(iter(self._cache)))
        return out

    def _healthy_grid(self, period: float, m: int) -> tuple:
        """Phases (m + 1), roller angles, their normals and the influence line at them, kept per grid."""
        key = (period, m)
        hit = self._grid.get(key)
        if hit is None:
            phi = np.linspace(0.0, period, m + 1)
            psi = self.roller_angles(phi)
            hit = (phi, psi, _normals(psi), self.influence(psi))
            self._grid[key] = hit
        return hit

    def _near_table(self, op: Operating, offsets: tuple | None) -> Table | None:
        """The latest groove-free table within :data:`WARM_START_REL` of ``op`` and ``offsets`` (both None, or
        both a roller's each), or None."""
        for (what, o, key, offs), t in reversed(self._cache.items()):
            if what != "table" or key is not None or t.offset is None or (offs is None) != (offsets is None):
                continue
            pd = max(abs(op.radial_clearance_m), 1e-12)
            change = max(abs(o.radial_load_N - op.radial_load_N) / abs(op.radial_load_N),
                         abs(o.radial_clearance_m - op.radial_clearance_m) / pd)
            if offsets is not None:
                change = max(change, float(np.max(np.abs(np.subtract(offs, offsets)))) / pd)
            if change <= WARM_START_REL:
                return t
        return None

    def _healthy_table(self, op: Operating, offsets: tuple | None) -> Table:
        z = self.geometry.n_rollers
        period = self.geometry.roller_pitch_rad if offsets is None else 2 * np.pi
        base = np.zeros(z) if offsets is None else np.asarray(offsets)
        # with scatter the table spans a cage turn: a coarser grid, the loads smooth without a groove
        m = self.table_points if offsets is None else SCATTER_POINTS * z
        phi, psi, normals, g = self._healthy_grid(period, m)
        near = self._near_table(op, offsets)
        e0 = None if near is None else near.offset
        if e0 is None and offsets is not None:  # start from the equal rollers' equilibrium
            ft = self.table(op)
            e0 = np.stack([np.interp(np.mod(phi, ft.period), ft.phase, ft.offset[:, i]) for i in (0, 1)], 1)
        q, e = quasi_static_loads(
            psi, np.broadcast_to(base, psi.shape), op.radial_load_N, 0.5 * op.radial_clearance_m,
            self.k_contact, TABLE_TOL, e0_m=e0, return_offset=True, normals=normals,
        )
        f = np.sum(q * g, axis=1)
        f[-1] = f[0]
        return Table(f, running_integral(phi, f), period, phi, q > 0, e)

    def _groove_table(self, op: Operating, outer_drop, offsets: tuple | None) -> Table:
        """Only the phases at which a roller stands in the groove differ from the table without it."""
        z = self.geometry.n_rollers
        bt = self.table(op, None, None, offsets)
        period = bt.period
        base = np.zeros(z) if offsets is None else np.asarray(offsets)
        if hasattr(outer_drop, "passages"):
            spans = outer_drop.passages(period)
            step = GROOVE_SPACING * period / (bt.phase.size - 1)
            nodes = np.linspace(-1.0, 1.0, 2 * max(128, int(np.ceil(spans[0][1] / step))) + 1) if spans else None
            local = np.concatenate([c + h * nodes for c, h in spans]) if spans else np.zeros(0)
            local = local[(local >= 0.0) & (local <= period)]
            inside = np.zeros(bt.phase.size, dtype=bool)
            for c, h in spans:
                inside |= np.abs(bt.phase - c) < h
            inside[[0, -1]] = False
            phi = np.unique(np.concatenate([bt.phase[~inside], local]))
            rows = np.searchsorted(phi, local)
        else:
            m = (GROOVE_REFINE * self.table_points) if offsets is None else (2 * self.table_points * z)
            phi = np.linspace(0.0, period, m + 1)
            rows = np.arange(phi.size)
        f = np.interp(phi, bt.phase, bt.force)
        drop = outer_drop(self.roller_angles(phi[rows]))
        hit = drop.max(axis=1) > 0
        rows, drop = rows[hit], drop[hit]
        if rows.size:
            k = np.rint(phi[rows] / period * (bt.phase.size - 1)).astype(int)
            f[rows] = self.sensor_force_at(phi[rows], op, drop + base[None, :], e0_m=bt.offset[k])[0]
        f[-1] = f[0]
        return Table(f, running_integral(phi, f), period, phi)

    def box_average(
        self, phase_edges_rad: np.ndarray, op: Operating, outer_drop=None, key=None, offsets_m=None
    ) -> np.ndarray:
        """Mean of F_s over each interval of cage phase [phi_k, phi_k+1] (the DAQ's sample windows) [N].

        Exact for the table (linear between its points): the periodic running
        integral G(phi) = (phi // P) G(P) + G(phi mod P) is differenced at the
        window edges. A zero-length window gives F_s there.
        """
        t = self.table(op, outer_drop, key, offsets_m)
        period, g = t.period, t.integral

        def big_g(p):
            k = np.floor(p / period)
            return k * g[-1] + np.interp(p - k * period, t.phase, g)

        edges = np.asarray(phase_edges_rad, dtype=float)
        width = np.diff(edges)
        ok = np.abs(width) > 1e-12 * period
        ge = big_g(edges)
        if ok.all():  # every window has a length (a turning bearing): no masks
            return (ge[1:] - ge[:-1]) / width
        out = np.empty(width.size)
        out[ok] = (ge[1:][ok] - ge[:-1][ok]) / width[ok]
        mid = 0.5 * (edges[1:] + edges[:-1])
        out[~ok] = np.interp(np.mod(mid[~ok], period), t.phase, t.force)
        return out

    def table_force(self, phase_rad: np.ndarray, op: Operating, outer_drop=None, key=None, offsets_m=None) -> np.ndarray:
        """F_s [N] at cage phases (n,) from the table (linear between its points), no moving defect."""
        t = self.table(op, outer_drop, key, offsets_m)
        return np.interp(np.mod(np.asarray(phase_rad, dtype=float), t.period), t.phase, t.force)

    def fine_change(
        self, phase_rad: np.ndarray, op: Operating, drop_m: np.ndarray, outer_drop=None, key=None, offsets_m=None
    ) -> np.ndarray:
        """What the extra drops (n, Z) of a moving defect change in F_s [N] at cage phases (n,).

        The equilibrium is solved where a roller that carries load stands in the moving defect; elsewhere
        nothing changes (0). With the table's F_s added it is F_s with the defect (and any outer-race defect
        and roller scatter).
        """
        period = self.table(op, outer_drop, key, offsets_m).period
        bt = self.table(op, None, None, offsets_m)
        loaded, e_tab = bt.loaded, bt.offset
        phi = np.asarray(phase_rad, dtype=float)
        out = np.zeros(phi.size)
        # a drop under a roller that carries nothing changes nothing: solve only where a loaded roller drops
        # (loaded at the nearest table phase or either neighbour)
        m = loaded.shape[0] - 1
        k = np.rint(np.mod(phi, period) / period * m).astype(int) % m
        # the record's roller j stands where the table's roller j + n does, n = whole pitches turned
        # (a pitch: the labels shift by one roller; a cage turn: none); looked up only where a roller drops
        z = loaded.shape[1]
        r, j = np.nonzero(drop_m > 0)
        col = (j + np.floor(phi[r] / period).astype(int) * int(round(z * period / (2 * np.pi)))) % z
        kr = k[r]
        near = loaded[kr, col] | loaded[np.mod(kr - 1, m), col] | loaded[np.mod(kr + 1, m), col]
        rows = np.unique(r[near])
        if rows.size:
            psi = self.roller_angles(phi[rows])
            d = drop_m[rows]
            if outer_drop is not None:
                d = d + outer_drop(psi)
            if offsets_m is not None:
                d = d + np.asarray(offsets_m)[None, :]
            # equilibrium to 1e-7 F_r (50 uN at 500 N, far below any record's noise), from the healthy offset
            f = self.sensor_force_at(phi[rows], op, d, e0_m=e_tab[k[rows]], tol_N=1e-7)[0]
            out[rows] = f - self.table_force(phi[rows], op, outer_drop, key, offsets_m)
        return out


def cage_phase(
    time_s: np.ndarray,
    shaft_speed_Hz: float | np.ndarray,
    geometry: BearingGeometry,
    start_phase_rad: float = 0.0,
    cage_slip: float = 0.0,
) -> np.ndarray:
    """Cage angle phi(t) = phi_0 + integral of 2 pi FTF (1 - slip) dt from the first sample [rad].

    ``shaft_speed_Hz`` is a constant or one value per time sample (a
    tachometer); between samples the speed is taken as linear (trapezoidal
    integration).
    """
    t = np.asarray(time_s, dtype=float)
    fr = np.broadcast_to(np.asarray(shaft_speed_Hz, dtype=float), t.shape)
    ratio = kinematic_frequencies(geometry, 1.0).ftf_Hz * (1.0 - cage_slip)
    w = 2 * np.pi * ratio * fr
    if np.ndim(shaft_speed_Hz) == 0:
        return start_phase_rad + w * (t - t[0])
    return start_phase_rad + np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])


def phase_edges(phase_rad: np.ndarray) -> np.ndarray:
    """Cage phase at the edges of the DAQ's sample windows: midpoints, extended by half a step at the ends [rad]."""
    p = np.asarray(phase_rad, dtype=float)
    return np.concatenate([[1.5 * p[0] - 0.5 * p[1]], 0.5 * (p[1:] + p[:-1]), [1.5 * p[-1] - 0.5 * p[-2]]])


# ---------------------------------------------------------------------------
# Defects that move: inner race (with the shaft) and rolling element (with a roller)
# ---------------------------------------------------------------------------


def groove_drop(u_m: np.ndarray, width_m: float, rho_m: float) -> np.ndarray:
    """Radial drop [m] where a cylinder of relative radius rho bridges a groove of width w, at arc u
    from its centre: the LPM's :func:`~piezobearing.bearing.lpm.chord_drop_m`, without a depth cap
    (the drop of a groove a roller can bridge is far below any groove's depth)."""
    return chord_drop_m(u_m, width_m, np.inf, rho_m)


def wrap(angle_rad: np.ndarray) -> np.ndarray:
    """Angle wrapped to [-pi, pi) [rad]."""
    return np.mod(np.asarray(angle_rad) + np.pi, 2 * np.pi) - np.pi


def outer_race_drop(psi_rad: np.ndarray, angle_rad: float, width_m: float, geometry: BearingGeometry) -> np.ndarray:
    """Drop [m] of rollers at angles psi over a groove on the outer raceway centred at ``angle_rad``.

    The roller bridges the groove on the concave raceway (radius (D_p + D_r)/2)
    with the relative radius 1/(1/r - 1/R_o).
    """
    ro = geometry.outer_raceway_radius_m
    return groove_drop(ro * wrap(np.asarray(psi_rad) - angle_rad), width_m, geometry.relative_radius_m("outer"))


@dataclass(frozen=True)
class OuterGroove:
    """A groove on the outer raceway as the drop function of :meth:`Surrogate.table` (``outer_drop``).

    Calling it gives :func:`outer_race_drop`; :meth:`passages` says at
    which cage phases a roller stands in it, where :meth:`Surrogate.table`
    puts its points.

    Parameters
    ----------
    angle_rad : float
        Groove centre from the sensor [rad].
    width_m : float
        Groove width along the raceway [m].
    geometry : BearingGeometry
    """

    angle_rad: float
    width_m: float
    geometry: BearingGeometry

    def __call__(self, psi_rad: np.ndarray) -> np.ndarray:
        return outer_race_drop(psi_rad, self.angle_rad, self.width_m, self.geometry)

    @property
    def key(self) -> tuple:
        return ("outer", self.width_m, self.angle_rad)

    def passages(self, period_rad: float) -> list[tuple[float, float]]:
        """(centre, half-width) in cage phase of every passage of a roller over the groove that touches
        [0, period] (roller j is centred on it at phi = angle - j pitch + 2 pi k) [rad]."""
        half = 0.5 * self.width_m / self.geometry.outer_raceway_radius_m
        pitch, z = self.geometry.roller_pitch_rad, self.geometry.n_rollers
        out = []
        for j in range(z):
            for k in range(-2, 3):
                c = self.angle_rad - j * pitch + 2 * np.pi * k
                if c + half >= 0.0 and c - half <= period_rad:
                    out.append((float(c), float(half)))
        return out


def inner_race_drop(
    psi_rad: np.ndarray, shaft_angle_rad: np.ndarray, width_m: float, geometry: BearingGeometry
) -> np.ndarray:
    """Drop (n, Z) [m] of rollers over a groove on the inner raceway at the shaft angle theta(t) (n,).

    ``psi_rad`` (n, Z) are the roller angles (psi_j = psi_0 + j 2 pi / Z).
    The groove turns with the shaft; the roller nearest to it, j* =
    round((theta - psi_0) Z / 2 pi) mod Z, is over it when psi_j* - theta is
    within the groove's arc on the inner raceway (radius (D_p - D_r)/2); a
    groove narrower than the roller pitch holds one roller at a time.
    """
    psi0 = np.asarray(psi_rad)[:, 0]
    j, d = inner_race_contact(psi0, shaft_angle_rad, width_m, geometry)
    out = np.zeros((psi0.size, geometry.n_rollers))
    out[np.arange(psi0.size), j] = d
    return out


def inner_race_contact(
    psi0_rad: np.ndarray, shaft_angle_rad: np.ndarray, width_m: float, geometry: BearingGeometry
) -> tuple[np.ndarray, np.ndarray]:
    """The roller nearest to an inner-race groove and its drop [m] at roller 0's angles psi_0 (n,) and the
    shaft angles theta (n,): the one nonzero column of :func:`inner_race_drop` of each row."""
    ri = 0.5 * (geometry.pitch_diameter_m - geometry.roller_diameter_m)
    z, pitch = geometry.n_rollers, geometry.roller_pitch_rad
    psi0 = np.asarray(psi0_rad, dtype=float)
    theta = np.asarray(shaft_angle_rad)
    j = np.mod(np.rint((theta - psi0) / pitch), z).astype(int)
    u = ri * wrap(psi0 + j * pitch - theta)
    return j, groove_drop(u, width_m, geometry.relative_radius_m("inner"))


def rolling_element_drop(
    n_rollers: int, roller: int, spin_rad: np.ndarray, width_m: float, geometry: BearingGeometry
) -> np.ndarray:
    """Drop (n, Z) [m] of a roller with a groove on its surface, at its spin angle beta(t) (n,).

    beta = 0 puts the groove against the outer raceway, beta = pi against
    the inner raceway: the roller sinks twice per spin turn (2 x BSF), by the
    relative radius of each contact.
    """
    d = roller_groove_drop(spin_rad, width_m, geometry)
    out = np.zeros((d.size, n_rollers))
    out[:, roller] = d
    return out


def roller_groove_drop(spin_rad: np.ndarray, width_m: float, geometry: BearingGeometry) -> np.ndarray:
    """Drop [m] of a roller with a groove at its spin angles beta (n,): the one nonzero column of
    :func:`rolling_element_drop`."""
    r = 0.5 * geometry.roller_diameter_m
    beta = np.asarray(spin_rad, dtype=float)
    return groove_drop(r * wrap(beta), width_m, geometry.relative_radius_m("outer")) + groove_drop(
        r * wrap(beta - np.pi), width_m, geometry.relative_radius_m("inner")
    )
