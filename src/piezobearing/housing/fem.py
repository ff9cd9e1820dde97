r"""Transient FEM of outer ring, housing and sensor under the moving roller loads.

Linear elastodynamics on the half model of :mod:`piezobearing.housing.mesh`
(x = 0 a mirror plane, U_x = 0; the foot's underside held):

.. math::
    \int_\Omega \rho\, v \cdot \ddot u \, d\Omega
    + \int_\Omega \varepsilon(v) : D : \varepsilon(u) \, d\Omega
    + k_s (w \cdot v_z)(w \cdot u_z)
    = \sum_j Q_j(t)\, v \cdot p(\psi_j(t)) \quad \forall v

K and M are assembled by sfepy (``dw_lin_elastic``, ``dw_dot``, linear
hexahedra; cast iron for the housing, steel for the ring, Table I); C is
Rayleigh damping. The sensor (alumina tip on the PZT disk, its far end held,
paper Sec. III-A) is a spring of the stack's axial stiffness k_s between the
mean radial displacement of its contact patch on the ring and the ground;
its force, F_s = -k_s w . u_z (compression positive), is the output. The
roller j's load Q_j acts on a small patch of the raceway centred at its angle
psi_j, along the outward normal: a uniform traction over the patch's arc and
the roller's contact length, whose consistent nodal forces are built here
(not by sfepy's surface terms).

Two solution methods:

* ``direct``: sfepy's generalized-alpha time stepper
  (:class:`sfepy.solvers.ts_solvers.GeneralizedAlphaTS`) on the full
  system, one factorisation of the effective matrix, one back-substitution a
  step: the reference.
* ``reduced`` (default): the n lowest modes, integrated exactly for loads
  linear between the samples, plus the static correction of the truncated
  modes (mode acceleration):
  F_s(t) = sum_i c_i q_i(t) + [g(t) - sum_i c_i f_i(t) / omega_i^2], where
  g(t) = c . K^-1 f(t) is the quasi-static sensor force. By reciprocity
  (K symmetric), g(t) = sum_j Q_j(t) (K^-1 c) . p(psi_j): a single solve
  gives the influence line of the sensor for every roller position.

Size. Over 600 lines as one module: the assembly, the modes, the reduced (modal) and the direct
responses, and the base-motion operators with their mounting probes share ``HousingModel`` and its
matrices; the reduced response is checked against the direct solve in the same module's terms. The
base-motion part is the natural first split.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit
from scipy.linalg import expm

from ..numerics import sfepy_setup  # noqa: F401  (before sfepy: without its JAX terms where JAX is absent)

# isort: split
from sfepy.base.base import Struct, output
from sfepy.discrete import Equation, Equations, FieldVariable, Integral, Material, Problem
from sfepy.discrete.fem import FEDomain, Field, Mesh
from sfepy.mechanics.matcoefs import stiffness_from_youngpoisson
from sfepy.solvers.ls import ScipyDirect
from sfepy.solvers.nls import Newton
from sfepy.solvers.ts_solvers import GeneralizedAlphaTS
from sfepy.terms import Term

from ..numerics import sparse_solve
from ..sensor.materials import IsotropicMaterial, PiezoMaterial
from .mesh import GROUP_HOUSING, GROUP_RING, HousingMesh, nested_dissection_order

# ---------------------------------------------------------------------------
# The sensor as a spring
# ---------------------------------------------------------------------------


def pzt_axial_modulus(pzt: PiezoMaterial, electrical: str = "open") -> float:
    """Young's modulus of a poled PZT bar under uniaxial stress along 3 [Pa].

    ``short``: 1 / s33^E (electrodes shorted); ``open``: 1 / s33^D with
    s33^D = s33^E - d33^2 / eps33^T (no charge flows). The sensor works into
    R = 50 MOhm: above ~30 Hz it is close to open circuit (paper Sec. III-C).
    """
    s = np.linalg.inv(pzt.c_E_Pa)
    s33 = s[2, 2]
    if electrical == "short":
        return float(1 / s33)
    if electrical == "open":
        return float(1 / (s33 - pzt.d33_C_per_N**2 / pzt.eps33_T_F_per_m))
    raise ValueError(f"config housing.sensor_electrical must be 'open' or 'short', got {electrical!r}")


def sensor_stiffness(
    pzt: PiezoMaterial,
    pzt_diameter_m: float,
    pzt_height_m: float,
    tip: IsotropicMaterial,
    tip_diameter_m: float,
    tip_height_m: float,
    electrical: str = "open",
    adhesive: IsotropicMaterial | None = None,
    adhesive_height_m: float = 0.0,
) -> float:
    """Axial stiffness of the sensor stack: the alumina tip, its bond layer and the PZT disk in series [N/m].

    k_s = 1 / (t / (E_tip A_tip) + t_a / (E_a A_a) + h / (E_3 A_pzt)), the bond
    layer (if any, ``adhesive_height_m`` > 0) over the smaller of the tip's and
    the PZT's areas. The far alumina disk is left out, as the paper holds the
    PZT's far face (U_z = 0). The stack's first resonance (1.2e5 Hz) lies far
    above the FEM's band, so its mass is negligible and a spring represents it.
    """
    a_tip = np.pi * tip_diameter_m**2 / 4
    a_pzt = np.pi * pzt_diameter_m**2 / 4
    e3 = pzt_axial_modulus(pzt, electrical)
    compliance = tip_height_m / (tip.young_Pa * a_tip) + pzt_height_m / (e3 * a_pzt)
    if adhesive_height_m > 0.0:
        if adhesive is None:
            raise ValueError("an adhesive layer needs its material")
        compliance += adhesive_height_m / (adhesive.young_Pa * min(a_tip, a_pzt))
    return float(1 / compliance)


# ---------------------------------------------------------------------------
# Consistent nodal weights of a uniform load over an interval
# ---------------------------------------------------------------------------


def _hat_antiderivative(sig: np.ndarray, left: np.ndarray, node: np.ndarray, right: np.ndarray) -> np.ndarray:
    """int_{-inf}^{sig} of the hat function (left, node, right), elementwise."""
    hl = node - left
    hr = right - node
    out = np.zeros(np.broadcast_shapes(sig.shape, node.shape))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(hl > 0, (np.clip(sig, left, node) - left) ** 2 / (2 * hl), 0.0)
        b = np.where(hr > 0, hr / 2 - (right - np.clip(sig, node, right)) ** 2 / (2 * hr), 0.0)
    out = a + np.where(sig > node, b, 0.0)
    return out


def box_weights(nodes: np.ndarray, lo: np.ndarray, hi: np.ndarray, period: float | None = None) -> np.ndarray:
    """Consistent nodal weights of a unit load spread uniformly over [lo, hi] on 1D linear elements.

    w_k = (1 / (hi - lo)) int_lo^hi N_k(s) ds, with N_k the hat functions of
    the sorted ``nodes`` (the first and last hats are halves unless
    ``period`` closes the line into a circle). The weights sum to 1 for an
    interval inside the mesh. For hi == lo the weights are N_k(lo), a point load.

    Parameters
    ----------
    nodes : ndarray (nk,)
        Sorted node positions [m].
    lo, hi : ndarray (n,)
        Intervals [m].
    period : float, optional
        Length of the closed line [m].

    Returns
    -------
    ndarray (n, nk)
    """
    s = np.asarray(nodes, dtype=float)
    lo = np.atleast_1d(np.asarray(lo, dtype=float))
    hi = np.atleast_1d(np.asarray(hi, dtype=float))
    if period is None:
        left = np.r_[s[0], s[:-1]]
        right = np.r_[s[1:], s[-1]]
        node, lft, rgt = s[None, :], left[None, :], right[None, :]
    else:
        left = np.r_[s[-1] - period, s[:-1]]
        right = np.r_[s[1:], s[0] + period]
        c = 0.5 * (lo + hi)
        # node positions relative to each interval's centre, wrapped into [-P/2, P/2)
        shift = np.mod(s[None, :] - c[:, None] + period / 2, period) - period / 2 - (s[None, :] - c[:, None])
        node, lft, rgt = s[None, :] + shift, left[None, :] + shift, right[None, :] + shift
    return _box_weights(node, lft, rgt, lo[:, None], hi[:, None])


def _box_weights(node: np.ndarray, lft: np.ndarray, rgt: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`box_weights` elementwise: the weight of the hat (lft, node, rgt) for the interval [a, b]."""
    width = b - a
    point = width <= 1e-15
    with np.errstate(divide="ignore", invalid="ignore"):
        box = (_hat_antiderivative(b, lft, node, rgt) - _hat_antiderivative(a, lft, node, rgt)) / np.where(
            point, 1.0, width
        )
        hl, hr = node - lft, rgt - node
        hat = np.where(
            a <= node,
            np.where(hl > 0, np.clip((a - lft) / hl, 0, 1), 1.0 * (a == node)),
            np.where(hr > 0, np.clip((rgt - a) / hr, 0, 1), 0.0),
        )
    return np.where(point, hat, box)


def box_window(nodes: np.ndarray, width: float, period: float) -> int:
    """Columns a window of :func:`box_weights_window` needs on each side of an interval's centre [-]: the most
    nodes any interval of ``width`` [m] holds on the closed line of ``period`` [m], plus two (the hats that
    reach into it from outside)."""
    s = np.asarray(nodes, dtype=float)
    ext = np.r_[s, s + period]
    return int(np.max(np.searchsorted(ext, s + width, side="right") - np.arange(s.size))) + 2


def box_weights_window(nodes: np.ndarray, lo: np.ndarray, hi: np.ndarray, period: float,
                       half: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`box_weights` on a closed line, only on the ``2 half`` columns around each interval's centre.

    The weights are those of :func:`box_weights` bit for bit at the window's columns, and every column
    outside the window has weight zero there when ``half`` >= :func:`box_window` (the intervals no wider
    than its ``width``): a load patch touches a few columns of the raceway, so a record's patches need
    (n, 2 half) numbers instead of (n, n_columns).

    Parameters
    ----------
    nodes : ndarray (nk,)
        Sorted node positions [m].
    lo, hi : ndarray (n,)
        Intervals [m].
    period : float
        Length of the closed line [m].
    half : int
        Columns on each side of each interval's centre [-].

    Returns
    -------
    columns : ndarray (n, 2 half) of int
        Column indices of each interval's window.
    weights : ndarray (n, 2 half)
        Their weights [-].
    """
    s = np.asarray(nodes, dtype=float)
    lo = np.atleast_1d(np.asarray(lo, dtype=float))
    hi = np.atleast_1d(np.asarray(hi, dtype=float))
    nk = s.size
    left = np.r_[s[-1] - period, s[:-1]]
    right = np.r_[s[1:], s[0] + period]
    c = 0.5 * (lo + hi)
    # the first node at or after the centre, the centre taken onto [s_0, s_0 + P)
    first = np.searchsorted(s, s[0] + np.mod(c - s[0], period))
    cols = np.mod(first[:, None] + np.arange(-half, half)[None, :], nk)
    sk = s[cols]
    shift = np.mod(sk - c[:, None] + period / 2, period) - period / 2 - (sk - c[:, None])
    weights = _box_weights(sk + shift, left[cols] + shift, right[cols] + shift, lo[:, None], hi[:, None])
    return cols, weights


# ---------------------------------------------------------------------------
# Assembly with sfepy
# ---------------------------------------------------------------------------


def assemble_matrices(mesh: HousingMesh, ring: IsotropicMaterial, housing: IsotropicMaterial):
    """Stiffness and mass matrices of the mesh, assembled by sfepy, without boundary conditions.

    Returns
    -------
    K, M : scipy.sparse.csr_matrix (3n, 3n)
        [N/m] and [kg]; DOF 3 i + c is component c (x, y, z) of node i.
    """
    output.set_output(quiet=True)
    sf_mesh = Mesh.from_data(
        "housing",
        mesh.coors,
        np.zeros(mesh.n_nodes, dtype=np.int32),
        [mesh.conn.astype(np.int32)],
        [mesh.group.astype(np.int32)],
        ["3_8"],
    )
    domain = FEDomain("domain", sf_mesh)
    omega = domain.create_region("Omega", "all")
    regions = {
        GROUP_RING: domain.create_region("Ring", f"cells of group {GROUP_RING}"),
        GROUP_HOUSING: domain.create_region("Housing", f"cells of group {GROUP_HOUSING}"),
    }
    fld = Field.from_args("fu", np.float64, "vector", omega, approx_order=1)
    if not np.allclose(fld.get_coor(), mesh.coors):
        raise RuntimeError("sfepy reordered the nodes; DOF numbering would not match the mesh")
    u = FieldVariable("u", "unknown", fld)
    v = FieldVariable("v", "test", fld, primary_var_name="u")
    integral = Integral("i", order=2)
    tk, tm = [], []
    for gid, mat in ((GROUP_RING, ring), (GROUP_HOUSING, housing)):
        m = Material(
            f"m{gid}", D=stiffness_from_youngpoisson(3, mat.young_Pa, mat.poisson), rho=mat.density_kg_per_m3
        )
        tk.append(
            Term.new(
                f"dw_lin_elastic(m{gid}.D, v, u)", integral, regions[gid], **{f"m{gid}": m, "v": v, "u": u}
            )
        )
        tm.append(
            Term.new(f"dw_dot(m{gid}.rho, v, u)", integral, regions[gid], **{f"m{gid}": m, "v": v, "u": u})
        )
    eq_k = Equation("stiffness", tk[0] + tk[1])
    eq_m = Equation("mass", tm[0] + tm[1])
    pb = Problem("housing", equations=Equations([eq_k, eq_m]))
    pb.time_update()
    pb.update_materials()
    k = eq_k.evaluate(mode="weak", dw_mode="matrix", asm_obj=pb.mtx_a)
    mm = k.copy()
    mm.data[:] = 0.0
    mm = eq_m.evaluate(mode="weak", dw_mode="matrix", asm_obj=mm)
    return k.tocsr(), mm.tocsr()


# ---------------------------------------------------------------------------
# The model: boundary conditions, sensor, loads
# ---------------------------------------------------------------------------


@dataclass
class HousingModel:
    """The reduced system K u = f on the free DOFs, with the sensor and the load operators.

    Attributes
    ----------
    mesh : HousingMesh
    K, M : csc_matrix (nf, nf)
        Stiffness (with the sensor spring) [N/m] and mass [kg] on the free DOFs.
    free : ndarray (nf,)
        Global DOF index of each free DOF.
    sensor : ndarray (nf,)
        c with F_s = c . u [N/m] (full-width sensor force, compression positive).
    load_y, load_z : csr_matrix (nc, nf)
        Nodal forces of a unit y (z) load on raceway column c spread over
        the roller's half-length (half the load: the half model carries half).
    sensor_stiffness_N_per_m : float
    patch_width_m : float
    solver : str or None
        Sparse direct solver of K and of the direct method's effective matrix
        (:func:`piezobearing.numerics.sparse_solve.factorize`): None (PARDISO where
        installed), ``pardiso`` or ``superlu`` (the previous method).
    """

    mesh: HousingMesh
    K: sp.csc_matrix = field(repr=False)
    M: sp.csc_matrix = field(repr=False)
    free: np.ndarray = field(repr=False)
    sensor: np.ndarray = field(repr=False)
    load_y: sp.csr_matrix = field(repr=False)
    load_z: sp.csr_matrix = field(repr=False)
    sensor_stiffness_N_per_m: float
    patch_width_m: float
    mass_kg: float
    solver: str | None = None
    _lu: object = field(default=None, repr=False)

    @property
    def n_dofs(self) -> int:
        return len(self.free)

    def factor(self):
        """Factors of K (cached): PARDISO's Cholesky or SuperLU in the model's nested-dissection order."""
        if self._lu is None:
            self._lu = factorize_spd(self.K, self.solver)
        return self._lu

    def patch_weights(self, psi_rad: np.ndarray) -> np.ndarray:
        """Weights (n, nc) of the raceway columns for load patches centred at psi."""
        g = self.mesh.geometry
        r = g.raceway_radius_m
        s = np.atleast_1d(psi_rad).ravel() * r
        half = 0.5 * self.patch_width_m
        return box_weights(self.mesh.raceway_psi * r, s - half, s + half, period=2 * np.pi * r)

    def column_loads(self, load_N: np.ndarray, psi_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Column load amplitudes (y and z) of rollers with loads Q (n_t, Z) at angles psi (n_t, Z).

        The force of roller j is Q_j n(psi_j), n = (sin psi, -cos psi) in (y, z).

        Returns
        -------
        wy, wz : ndarray (n_t, nc) [N]
        """
        q = np.asarray(load_N, dtype=float)
        psi = np.asarray(psi_rad, dtype=float)
        nt, z = q.shape
        w = self.patch_weights(psi.ravel()).reshape(nt, z, -1)
        wy = np.einsum("tj,tjc->tc", q * np.sin(psi), w)
        wz = np.einsum("tj,tjc->tc", -q * np.cos(psi), w)
        return wy, wz

    def load_vectors(self, wy: np.ndarray, wz: np.ndarray) -> np.ndarray:
        """Nodal load vectors f (n_t, nf) [N] from column loads."""
        return np.asarray(self.load_y.T @ wy.T + self.load_z.T @ wz.T).T

    def influence_line(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Quasi-static sensor force per unit roller load at each raceway column.

        By reciprocity one solve, z = K^-1 c, gives the sensor force of a
        unit load at any column: g_y = P_y z, g_z = P_z z.

        Returns
        -------
        gy, gz : ndarray (nc,)
            Sensor force [N] per newton of y and z load on the column.
        radial : ndarray (nc,)
            Sensor force per newton of outward radial load at the column's angle [N/N].
        """
        zvec = self.factor().solve(self.sensor)
        gy = self.load_y @ zvec
        gz = self.load_z @ zvec
        psi = self.mesh.raceway_psi
        return gy, gz, gy * np.sin(psi) - gz * np.cos(psi)


    def sensor_port_compliance_m_per_N(self) -> float:
        """Flexibility of the housing at the sensor without the sensor, a0 = w . K0^-1 w [m/N] (half model).

        The sensor is the rank-one spring K = K0 + (k_s/2) w w^T, so with z = K^-1 c (c = -k_s w, the
        influence solve) a = w . K^-1 w = (c . z) / k_s^2, and a0 = a / (1 - (k_s/2) a).
        """
        k = self.sensor_stiffness_N_per_m
        a = float(self.sensor @ self.factor().solve(self.sensor)) / k**2
        return a / (1.0 - 0.5 * k * a)


def spring_share_factor(k_new_N_per_m: float, k_ref_N_per_m: float, port_compliance_m_per_N: float) -> float:
    """Sensor force with spring k_new over that with k_ref, for any load on the housing [-].

    With the housing's flexibility a0 at the sensor (half model, :meth:`HousingModel.sensor_port_compliance_m_per_N`)
    the sensor force is F = k g0 / (1 + k a0 / 2) for every load (g0: the displacement there without the sensor),
    so one factor scales the whole influence line: k_new (1 + k_ref a0/2) / (k_ref (1 + k_new a0/2)).
    """
    a0 = port_compliance_m_per_N
    return k_new_N_per_m * (1 + 0.5 * k_ref_N_per_m * a0) / (k_ref_N_per_m * (1 + 0.5 * k_new_N_per_m * a0))


def factorize_spd(a: sp.spmatrix, solver: str | None = None):
    """Factors of a symmetric positive definite matrix of the model (``solve(b)``).

    PARDISO orders with METIS; SuperLU (``solver="superlu"``) keeps the
    model's nested-dissection numbering (:func:`splu_symmetric`).
    """
    if sparse_solve.resolve(solver) == "superlu":
        return splu_symmetric(a)
    return sparse_solve.factorize(a, definite=True, solver="pardiso")


def splu_symmetric(a: sp.spmatrix, ordering: str = "NATURAL"):
    """SuperLU of a symmetric positive definite matrix, without pivoting.

    The model's DOFs are numbered in nested-dissection order already
    (:func:`piezobearing.housing.mesh.nested_dissection_order`), so the
    natural column order is the fill-reducing one.
    """
    return spla.splu(
        sp.csc_matrix(a), permc_spec=ordering, diag_pivot_thresh=0.0, options={"SymmetricMode": True}
    )


def build_model(
    mesh: HousingMesh,
    ring: IsotropicMaterial,
    housing: IsotropicMaterial,
    sensor_stiffness_N_per_m: float,
    patch_width_m: float,
) -> HousingModel:
    """Assemble the half model, apply the conditions, add the sensor and build the load operators.

    Conditions: U_x = 0 on the mirror plane x = 0; U = 0 on the foot's
    underside (bolted to a rigid base). The sensor: a spring k_s between the
    weighted mean radial displacement of its patch (the tip's area on the
    ring's outer surface at psi = 0) and the ground; in the half model it has
    half the stiffness, and F_s is reported for the full sensor.
    """
    g = mesh.geometry
    k, m = assemble_matrices(mesh, ring, housing)
    n = mesh.n_nodes
    fixed = np.zeros(3 * n, bool)
    on_plane = np.abs(mesh.coors[:, 0]) < 1e-12
    fixed[3 * np.where(on_plane)[0]] = True
    for c in range(3):
        fixed[3 * mesh.base_nodes + c] = True
    # free DOFs numbered in nested-dissection order of their nodes
    dofs = (3 * nested_dissection_order(mesh)[:, None] + np.arange(3)).ravel()
    free = dofs[~fixed[dofs]]
    gmap = -np.ones(3 * n, int)
    gmap[free] = np.arange(len(free))

    # sensor patch: square of the tip's area at psi = 0 on the ring's outer surface
    ro = g.ring_outer_radius_m
    at = g.tip_half_side_m
    ws = box_weights(mesh.ring_outer_psi * ro, np.array([-at]), np.array([at]), period=2 * np.pi * ro)[0]
    wx = box_weights(mesh.raceway_x, np.array([0.0]), np.array([at]))[0]
    wpatch = ws[:, None] * wx[None, :]
    nodes = mesh.ring_outer_nodes
    sel = wpatch > 0
    # radial displacement at psi ~ 0 is -u_z; weight the z DOFs
    c_full = np.zeros(3 * n)
    np.add.at(c_full, 3 * nodes[sel] + 2, wpatch[sel])
    # F_s = -k_s w . u_z = k_s w . (radial); c such that F_s = c . u
    c = -sensor_stiffness_N_per_m * c_full[free]
    # the half model carries half the sensor: K += (k_s/2) w w^T (w on the z DOFs)
    idx = np.where(c_full[free] != 0)[0]
    wv = c_full[free][idx]
    ks = sp.coo_matrix(
        (
            0.5 * sensor_stiffness_N_per_m * np.outer(wv, wv).ravel(),
            (np.repeat(idx, len(idx)), np.tile(idx, len(idx))),
        ),
        shape=(len(free), len(free)),
    )
    kf = (k[free][:, free] + ks).tocsc()
    mf = m[free][:, free].tocsc()

    # load operators: unit load on raceway column c, spread uniformly over x in [0, l/2], half of it
    wxl = box_weights(mesh.raceway_x, np.array([0.0]), np.array([g.roller_half_length_m]))[0]
    rows, cols_y, cols_z, vals = [], [], [], []
    for ci in range(len(mesh.raceway_psi)):
        for li, w in enumerate(wxl):
            if w == 0:
                continue
            node = mesh.raceway_nodes[ci, li]
            rows.append(ci)
            cols_y.append(gmap[3 * node + 1])
            cols_z.append(gmap[3 * node + 2])
            vals.append(0.5 * w)
    rows, cols_y, cols_z, vals = map(np.asarray, (rows, cols_y, cols_z, vals))
    ok_y, ok_z = cols_y >= 0, cols_z >= 0
    shape = (len(mesh.raceway_psi), len(free))
    py = sp.csr_matrix((vals[ok_y], (rows[ok_y], cols_y[ok_y])), shape=shape)
    pz = sp.csr_matrix((vals[ok_z], (rows[ok_z], cols_z[ok_z])), shape=shape)
    mass = float(m[0::3][:, 0::3].sum())
    return HousingModel(mesh, kf, mf, free, c, py, pz, sensor_stiffness_N_per_m, patch_width_m, 2 * mass)


# ---------------------------------------------------------------------------
# Modes
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Modes:
    """Mass-normalised modes of the half model.

    Attributes
    ----------
    omega_rad_s : ndarray (n,)
    shapes : ndarray (nf, n)
    """

    omega_rad_s: np.ndarray
    shapes: np.ndarray = field(repr=False)

    @property
    def frequencies_Hz(self) -> np.ndarray:
        return self.omega_rad_s / (2 * np.pi)


def compute_modes(model: HousingModel, n_modes: int, seed: int = 0) -> Modes:
    """The n lowest modes by shift-invert Lanczos about 0, reusing K's factors."""
    lu = model.factor()
    op = spla.LinearOperator(model.K.shape, matvec=lu.solve, dtype=float)
    v0 = np.random.default_rng(seed).standard_normal(model.n_dofs)
    lam, vec = spla.eigsh(model.K, k=n_modes, M=model.M, sigma=0.0, OPinv=op, which="LM", v0=v0)
    order = np.argsort(lam)
    lam, vec = lam[order], vec[:, order]
    # mass-normalise
    vec = vec / np.sqrt(np.einsum("ij,ij->j", vec, model.M @ vec))
    return Modes(np.sqrt(np.maximum(lam, 0.0)), vec)


def rayleigh_coefficients(damping_ratio: float, band_Hz: tuple[float, float]) -> tuple[float, float]:
    """alpha, beta of C = alpha M + beta K with the damping ratio zeta at both band edges."""
    wa, wb = 2 * np.pi * np.asarray(band_Hz, dtype=float)
    return 2 * damping_ratio * wa * wb / (wa + wb), 2 * damping_ratio / (wa + wb)


# ---------------------------------------------------------------------------
# Reduced method: modes + static correction, exact for piecewise-linear loads
# ---------------------------------------------------------------------------


def _ramp_recurrence(omega: np.ndarray, zeta: np.ndarray, h: float):
    """Matrices of the exact step of q'' + 2 zeta w q' + w^2 q = f, f linear over the step.

    Returns (A (n,2,2), B (n,2,2)) with x_{k+1} = A x_k + B (f_k, f_{k+1}), x = (q, q'), read-only. Kept for
    the modes and step last asked (:func:`_ramp_recurrence_of`): a 4 x 4 matrix exponential of norm w^2 h costs
    milliseconds per mode, and a comparison steps the same modes in every realisation.
    """
    omega = np.ascontiguousarray(omega, dtype=float)
    zeta = np.ascontiguousarray(zeta, dtype=float)
    return _ramp_recurrence_of(omega.tobytes(), zeta.tobytes(), float(h))


@functools.lru_cache(maxsize=8)
def _ramp_recurrence_of(omega_bytes: bytes, zeta_bytes: bytes, h: float):
    """:func:`_ramp_recurrence` of the modes given as their arrays' bytes."""
    omega, zeta = np.frombuffer(omega_bytes), np.frombuffer(zeta_bytes)
    a_mat = np.zeros((len(omega), 2, 2))
    b_mat = np.zeros((len(omega), 2, 2))
    for i, (w, z) in enumerate(zip(omega, zeta, strict=True)):
        aug = np.zeros((4, 4))
        aug[0, 1] = 1.0
        aug[1, 0] = -w * w
        aug[1, 1] = -2 * z * w
        aug[1, 2] = 1.0
        aug[2, 3] = 1.0
        e = expm(aug * h)
        a_mat[i] = e[:2, :2]
        # x_{k+1} = E11 x + E12 f_k + E13 fdot h... with state (f, df/dt): f' = fdot, fdot' = 0
        # E[:2, 2] multiplies f_k, E[:2, 3] multiplies fdot_k = (f_{k+1} - f_k)/h
        e_f, e_fd = e[:2, 2], e[:2, 3] / h
        b_mat[i, :, 0] = e_f - e_fd
        b_mat[i, :, 1] = e_fd
    a_mat.flags.writeable = False
    b_mat.flags.writeable = False
    return a_mat, b_mat


def modal_response(
    forces: np.ndarray, omega: np.ndarray, zeta: np.ndarray, h: float, velocity: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Modal coordinates q (n_t, n) under modal forces (n_t, n) linear between samples, exactly.

    Starts from the static response to the first sample (q = f_0 / w^2, q' = 0). With ``velocity``
    the modal velocities q' (n_t, n) too, as ``(q, q')``. The recurrence runs compiled
    (:func:`_modal_steps`).
    """
    a_mat, b_mat = _ramp_recurrence(omega, zeta, h)
    forces = np.ascontiguousarray(forces, dtype=float)
    n = forces.shape[1]
    x = np.stack([forces[0] / omega**2, np.zeros(n)], axis=1)  # (n, 2)
    q, qd = _modal_steps(a_mat, b_mat, forces, x)
    return (q, qd) if velocity else q


@njit(cache=True)
def _modal_steps(a_mat, b_mat, forces, x0):  # pragma: no cover - compiled
    """The recurrence x_{k+1} = A x_k + B (f_k, f_{k+1}) of every mode from x_0 (n, 2): q and q' (n_t, n).

    Scalar loops in the order of ``einsum("nij,nj->ni", A, x) + einsum("nij,nj->ni", B, (f_k, f_{k+1}))``
    (the same numbers to the last bit), compiled: a Python loop over the samples costs numpy's per-call
    overhead on arrays of a few modes at each of a record's tens of thousands of samples.
    """
    nt, n = forces.shape
    q = np.empty((nt, n))
    qd = np.zeros((nt, n))
    x = x0.copy()
    for i in range(n):
        q[0, i] = x[i, 0]
    for k in range(nt - 1):
        for i in range(n):
            p0 = a_mat[i, 0, 0] * x[i, 0] + a_mat[i, 0, 1] * x[i, 1]
            p1 = a_mat[i, 1, 0] * x[i, 0] + a_mat[i, 1, 1] * x[i, 1]
            r0 = b_mat[i, 0, 0] * forces[k, i] + b_mat[i, 0, 1] * forces[k + 1, i]
            r1 = b_mat[i, 1, 0] * forces[k, i] + b_mat[i, 1, 1] * forces[k + 1, i]
            x[i, 0] = p0 + r0
            x[i, 1] = p1 + r1
            q[k + 1, i] = x[i, 0]
            qd[k + 1, i] = x[i, 1]
    return q, qd


@dataclass(frozen=True)
class ReducedOperators:
    """Everything the reduced method needs, on the raceway columns.

    ``modal_y``/``modal_z`` (nc, n): modal force per unit column load;
    ``static_y``/``static_z`` (nc,): quasi-static sensor force per unit column load;
    ``sensor_modal`` (n,): c . phi_i; ``omega``, ``zeta`` (n,).
    """

    modal_y: np.ndarray
    modal_z: np.ndarray
    static_y: np.ndarray
    static_z: np.ndarray
    sensor_modal: np.ndarray
    omega: np.ndarray
    zeta: np.ndarray


def reduced_operators(model: HousingModel, modes: Modes, alpha: float, beta: float) -> ReducedOperators:
    gy, gz, _ = model.influence_line()
    phi = modes.shapes
    w = modes.omega_rad_s
    return ReducedOperators(
        modal_y=np.asarray(model.load_y @ phi),
        modal_z=np.asarray(model.load_z @ phi),
        static_y=gy,
        static_z=gz,
        sensor_modal=model.sensor @ phi,
        omega=w,
        zeta=(alpha / w + beta * w) / 2,
    )


def sensor_force_reduced(ops: ReducedOperators, wy: np.ndarray, wz: np.ndarray, h: float) -> dict:
    """Sensor force by modal superposition with static correction.

    Parameters
    ----------
    ops : ReducedOperators
    wy, wz : ndarray (n_t, nc)
        Column loads at the time samples [N] (linear in between).
    h : float
        Time step [s].

    Returns
    -------
    dict with ``force_N`` (total), ``quasi_static_N`` (g(t)) and ``dynamic_N`` (the difference).
    """
    g = wy @ ops.static_y + wz @ ops.static_z
    f = wy @ ops.modal_y + wz @ ops.modal_z
    q = modal_response(f, ops.omega, ops.zeta, h)
    dyn = (q - f / ops.omega**2) @ ops.sensor_modal
    return {"force_N": g + dyn, "quasi_static_N": g, "dynamic_N": dyn}


# ---------------------------------------------------------------------------
# Base motion and surface accelerations
# ---------------------------------------------------------------------------

#: Mounting places of a housing accelerometer: the surface and its outward normal (y, z) in the model's axes.
MOUNTING_POSITIONS = ("top", "side", "foot")


@dataclass(frozen=True)
class Probe:
    """An accelerometer's mounting place on the housing surface.

    Attributes
    ----------
    position : str
        One of :data:`MOUNTING_POSITIONS`.
    node : int
        Mesh node under the accelerometer [-].
    coordinates_m : tuple of float
        The node's (x, y, z) [m].
    normal : tuple of float
        Outward unit normal of the surface there, (x, y, z) [-]; the accelerometer's sensing axis.
    """

    position: str
    node: int
    coordinates_m: tuple[float, float, float]
    normal: tuple[float, float, float]


def mounting_probe(mesh: HousingMesh, position: str) -> Probe:
    """The node and normal of a mounting place on the half model's surface.

    ``top``: the top of the housing cap above the shaft centre (z = body top, y = 0, on the mirror plane
    x = 0: the housing's middle), normal +z. ``side``: the body's side at the bearing's centre line
    (y = body half width, z = 0, x = 0), normal +y. ``foot``: the foot's top face halfway between the body
    and the foot's end (z = -body bottom, y = (body half width + foot length / 2) / 2, x = 0), normal +z;
    the foot's underside is held rigidly, so a foot accelerometer reads little but the base's own motion.
    The node is the surface node nearest the target point.
    """
    g = mesh.geometry
    targets = {
        "top": ((0.0, 0.0, g.body_top_m), (0.0, 0.0, 1.0), 2),
        "side": ((0.0, g.body_half_width_m, 0.0), (0.0, 1.0, 0.0), 1),
        "foot": ((0.0, 0.5 * (g.body_half_width_m + 0.5 * g.foot_length_m), -g.body_bottom_m), (0.0, 0.0, 1.0), 2),
    }
    if position not in targets:
        raise ValueError(
            f"config accelerometer.position must be one of {', '.join(MOUNTING_POSITIONS)}, got {position!r}"
        )
    point, normal, axis = targets[position]
    c = mesh.coors
    # the surface: nodes at the target's coordinate along the normal, on the side the normal points to
    on_plane = np.abs(c[:, axis] - point[axis]) < 1e-9
    if position == "foot":
        on_plane &= np.abs(c[:, 1]) >= g.body_half_width_m - 1e-9
    idx = np.where(on_plane)[0]
    if idx.size == 0:
        raise ValueError(f"no mesh node on the {position} mounting surface; check the housing geometry")
    node = int(idx[np.argmin(np.linalg.norm(c[idx] - np.asarray(point), axis=1))])
    return Probe(position, node, tuple(float(v) for v in c[node]), normal)


@dataclass(frozen=True)
class BaseMotionOperators:
    """The base (foot) motion in the modal model, and the probes' rows.

    In base-relative coordinates u_rel = u - r_y b_y - r_z b_z (r: the rigid translations in y and z, 1 on
    the free DOFs of that component) the housing obeys M u_rel'' + C u_rel' + K u_rel = f(t) - M r a(t),
    with a = (a_y, a_z) the base's acceleration. The sensor's far end sits in the housing, which moves with
    the base, so the sensor force c . u_rel holds; an accelerometer reads the absolute acceleration
    n . (u_rel'' + r a).

    Attributes
    ----------
    rigid : ndarray (nf, 2)
        r_y, r_z on the free DOFs [-].
    participation : ndarray (2, n)
        Gamma_i = phi_i . M r for y and z [kg^0.5] (mass-normalised modes).
    rigid_mass_kg : ndarray (2,)
        r^T M r for y and z: the free DOFs' mass that the base drags [kg] (the held underside's nodes excluded).
    static_sensor : ndarray (2,)
        Quasi-static sensor force per unit base acceleration, -(K^-1 c) . M r [N per m/s^2].
    probes : tuple of Probe
    probe_rows : csr_matrix (n_probes, nf)
        n . u at each probe's node (its normal's components on the free DOFs).
    probe_modal : ndarray (n_probes, n)
        n . phi_i at each probe [-].
    probe_base : ndarray (n_probes, 2)
        (n_y, n_z) of each probe: its reading of the base's own acceleration [-].
    """

    rigid: np.ndarray = field(repr=False)
    participation: np.ndarray
    rigid_mass_kg: np.ndarray
    static_sensor: np.ndarray
    probes: tuple[Probe, ...]
    probe_rows: sp.csr_matrix = field(repr=False)
    probe_modal: np.ndarray
    probe_base: np.ndarray

    def effective_mass_fraction(self) -> np.ndarray:
        """Cumulative effective modal mass over r^T M r, (2, n) for y and z [-]: sum_{j<=i} Gamma_j^2 / r^T M r."""
        return np.cumsum(self.participation**2, axis=1) / self.rigid_mass_kg[:, None]


def base_motion_operators(model: HousingModel, modes: Modes, probes: tuple[Probe, ...] = ()) -> BaseMotionOperators:
    """The modal operators of base motion in y and z and of the probes (:class:`BaseMotionOperators`).

    The half model (mirror plane x = 0, U_x = 0 there) carries base motion in y and z only: an axial
    (x) motion of the base is antisymmetric about that plane.
    """
    comp = model.free % 3
    rigid = np.stack([(comp == 1).astype(float), (comp == 2).astype(float)], axis=1)
    mr = model.M @ rigid
    gmap = -np.ones(3 * model.mesh.n_nodes, int)
    gmap[model.free] = np.arange(model.n_dofs)
    rows, cols, vals = [], [], []
    for i, p in enumerate(probes):
        for c in (1, 2):
            dof = gmap[3 * p.node + c]
            if dof >= 0 and p.normal[c] != 0.0:
                rows.append(i)
                cols.append(dof)
                vals.append(p.normal[c])
    pr = sp.csr_matrix((vals, (rows, cols)), shape=(len(probes), model.n_dofs))
    zvec = model.factor().solve(model.sensor)
    return BaseMotionOperators(
        rigid=rigid,
        participation=np.asarray(modes.shapes.T @ mr).T,
        rigid_mass_kg=np.einsum("ij,ij->j", rigid, mr),
        static_sensor=-(zvec @ mr),
        probes=tuple(probes),
        probe_rows=pr,
        probe_modal=np.asarray(pr @ modes.shapes),
        probe_base=np.array([[p.normal[1], p.normal[2]] for p in probes]).reshape(len(probes), 2),
    )


def response_reduced(
    ops: ReducedOperators, base: BaseMotionOperators, wy: np.ndarray, wz: np.ndarray,
    base_acceleration: np.ndarray, h: float,
) -> dict:
    """Sensor force and probe accelerations under roller loads and base motion, by modal superposition.

    The sensor force as :func:`sensor_force_reduced` (modes plus the static correction of the truncated
    ones), its loads now with the base's inertia -M r a. The probes' accelerations are the retained modes'
    n . phi_i q_i'' (q_i'' = f_i - 2 zeta_i w_i q_i' - w_i^2 q_i, exact at the samples for loads linear
    between them) plus the base's n . a: a truncated mode of frequency w_i adds only (w / w_i)^2 of its
    quasi-static share at frequency w, so the mode count is converged against the band's top
    (:meth:`BaseMotionOperators.effective_mass_fraction`, and the direct solve).

    Parameters
    ----------
    ops : ReducedOperators
    base : BaseMotionOperators
    wy, wz : ndarray (n_t, nc)
        Column loads at the samples [N].
    base_acceleration : ndarray (n_t, 2)
        The base's acceleration (y, z) at the samples [m/s^2].
    h : float
        Time step [s].

    Returns
    -------
    dict with ``force_N`` (n_t,), ``quasi_static_N``, ``dynamic_N`` and ``acceleration_m_per_s2``
    (n_probes, n_t), the probes' absolute accelerations along their normals.
    """
    return response_projected(ops, base, wy @ ops.static_y + wz @ ops.static_z, wy @ ops.modal_y + wz @ ops.modal_z,
                              base_acceleration, h)


@dataclass(frozen=True)
class RacewayColumns:
    """The raceway's node columns, where the roller loads enter the housing model.

    Attributes
    ----------
    psi_rad : ndarray (nc,)
        Angle of each column, increasing [rad].
    radius_m : float
        Raceway radius [m].
    patch_width_m : float
        Circumferential width of a roller's load patch [m].
    """

    psi_rad: np.ndarray
    radius_m: float
    patch_width_m: float

    @classmethod
    def of(cls, model: HousingModel) -> RacewayColumns:
        """The columns of a housing model (its mesh's raceway and its patch width)."""
        return cls(model.mesh.raceway_psi, model.mesh.geometry.raceway_radius_m, model.patch_width_m)

    def window(self) -> int:
        """Columns on each side of a patch's centre that hold all its weights (:func:`box_window`) [-]."""
        return box_window(self.psi_rad * self.radius_m, self.patch_width_m, 2 * np.pi * self.radius_m)

    def patch_window(self, psi_rad: np.ndarray, half: int) -> tuple[np.ndarray, np.ndarray]:
        """The columns (n, 2 half) and weights of load patches centred at psi: :meth:`HousingModel.patch_weights`
        at the columns it does not leave zero (:func:`box_weights_window`)."""
        r = self.radius_m
        s = np.atleast_1d(psi_rad).ravel() * r
        half_width = 0.5 * self.patch_width_m
        return box_weights_window(self.psi_rad * r, s - half_width, s + half_width, 2 * np.pi * r, half)


def project_roller_loads(columns: RacewayColumns, ops: ReducedOperators, load_N: np.ndarray,
                         angle_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The roller loads' quasi-static sensor force g (n_t,) [N] and modal forces (n_t, n) [N].

    ``wy @ ops.static_y + wz @ ops.static_z`` and ``wy @ ops.modal_y + wz @ ops.modal_z`` with the column loads
    wy, wz of :meth:`HousingModel.column_loads`, each roller's force spread over the few columns its patch
    touches (the weights of :meth:`RacewayColumns.patch_window`) and summed there, compiled
    (:func:`_project_patches`): no (n_t, n_columns) load matrix is formed.
    """
    q = np.ascontiguousarray(load_N, dtype=float)
    psi = np.ascontiguousarray(angle_rad, dtype=float)
    nc = columns.psi_rad.size
    half = columns.window()
    if 2 * half > nc:
        raise ValueError(
            f"config housing.patch_width_m = {columns.patch_width_m:g} m spans half the raceway's {nc} columns; "
            "a roller's load patch must be narrower"
        )
    r = columns.radius_m
    nodes = np.ascontiguousarray(columns.psi_rad * r, dtype=float)
    period = 2 * np.pi * r
    left = np.r_[nodes[-1] - period, nodes[:-1]]
    right = np.r_[nodes[1:], nodes[0] + period]
    return _project_patches(q, psi, nodes, left, right, r, 0.5 * columns.patch_width_m, period, half,
                            np.ascontiguousarray(ops.static_y, dtype=float),
                            np.ascontiguousarray(ops.static_z, dtype=float),
                            np.ascontiguousarray(ops.modal_y, dtype=float),
                            np.ascontiguousarray(ops.modal_z, dtype=float))


@njit(cache=True)
def _hat_integral(sig, lft, node, rgt):  # pragma: no cover - compiled
    """:func:`_hat_antiderivative` of one hat at one point."""
    hl = node - lft
    hr = rgt - node
    a = (min(max(sig, lft), node) - lft) ** 2 / (2 * hl) if hl > 0 else 0.0
    b = hr / 2 - (rgt - min(max(sig, node), rgt)) ** 2 / (2 * hr) if hr > 0 else 0.0
    return a + b if sig > node else a


@njit(cache=True)
def _box_weight(node, lft, rgt, a, b):  # pragma: no cover - compiled
    """:func:`_box_weights` of one hat (lft, node, rgt) for one interval [a, b]."""
    width = b - a
    if width > 1e-15:
        return (_hat_integral(b, lft, node, rgt) - _hat_integral(a, lft, node, rgt)) / width
    hl, hr = node - lft, rgt - node
    if a <= node:
        return min(max((a - lft) / hl, 0.0), 1.0) if hl > 0 else 1.0 * (a == node)
    return min(max((rgt - a) / hr, 0.0), 1.0) if hr > 0 else 0.0


@njit(cache=True)
def _project_patches(q, psi, nodes, left, right, radius, half_width, period, half, static_y, static_z, modal_y,
                     modal_z):  # pragma: no cover - compiled
    """Each roller's patch weights on the ``2 half`` columns around its centre (:func:`box_weights_window`,
    element by element) times its force (sin psi, -cos psi) Q, summed into the sensor force and the modal
    forces sample by sample."""
    nt, z = q.shape
    nk = nodes.size
    nm = modal_y.shape[1]
    g = np.zeros(nt)
    f = np.zeros((nt, nm))
    for t in range(nt):
        for j in range(z):
            fy = q[t, j] * np.sin(psi[t, j])
            fz = -q[t, j] * np.cos(psi[t, j])
            centre = psi[t, j] * radius
            lo = centre - half_width
            hi = centre + half_width
            c = 0.5 * (lo + hi)
            first = np.searchsorted(nodes, nodes[0] + (c - nodes[0]) % period)
            for m in range(-half, half):
                col = (first + m) % nk
                sk = nodes[col]
                shift = (sk - c + period / 2) % period - period / 2 - (sk - c)
                w = _box_weight(sk + shift, left[col] + shift, right[col] + shift, lo, hi)
                if w != 0.0:
                    ay = fy * w
                    az = fz * w
                    g[t] += ay * static_y[col] + az * static_z[col]
                    for i in range(nm):
                        f[t, i] += ay * modal_y[col, i] + az * modal_z[col, i]
    return g, f


def response_projected(ops: ReducedOperators, base: BaseMotionOperators, static_N: np.ndarray, modal_N: np.ndarray,
                       base_acceleration: np.ndarray, h: float) -> dict:
    """:func:`response_reduced` from the roller loads' quasi-static sensor force ``static_N`` (n_t,) [N] and
    modal forces ``modal_N`` (n_t, n) [N] (:func:`project_roller_loads`)."""
    a = np.asarray(base_acceleration, dtype=float)
    g = static_N + a @ base.static_sensor
    f = modal_N - a @ base.participation
    q, qd = modal_response(f, ops.omega, ops.zeta, h, velocity=True)
    dyn = (q - f / ops.omega**2) @ ops.sensor_modal
    qdd = f - 2 * ops.zeta * ops.omega * qd - ops.omega**2 * q
    acc = base.probe_modal @ qdd.T + base.probe_base @ a.T
    return {"force_N": g + dyn, "quasi_static_N": g, "dynamic_N": dyn, "acceleration_m_per_s2": acc}


# ---------------------------------------------------------------------------
# Direct method: sfepy's generalized-alpha stepper on the full system
# ---------------------------------------------------------------------------


def sensor_force_direct(
    model: HousingModel,
    wy: np.ndarray,
    wz: np.ndarray,
    h: float,
    alpha: float,
    beta: float,
    rho_inf: float = 0.9,
    progress=None,
    base: BaseMotionOperators | None = None,
    base_acceleration: np.ndarray | None = None,
    substeps: int = 1,
) -> dict:
    """Sensor force (and, with ``base``, the probes' accelerations) by direct time integration with sfepy's
    ``ts.generalized_alpha``.

    ``base`` and ``base_acceleration`` (n_t, 2) [m/s^2]: the foot's acceleration in y and z, linear between
    the samples, as the load -M r a(t) in base-relative coordinates; the probes' absolute accelerations
    (``probe_acceleration_m_per_s2``, (n_probes, n_t)) are the relative ones of the solver's state plus the
    base's along each probe's normal. ``substeps``: solver steps per sample (the generalized-alpha rule's
    period error grows as (omega h)^2: at a DAQ rate's band top a check needs several steps a sample; the
    loads stay linear between the samples).

    The solver class is driven on the assembled matrices: its nonlinear
    solver (sfepy's Newton, linear mode, one iteration a step) evaluates
    the residual K u + C v + M a - f(t) with f linear between the samples, at
    the solver's intermediate time t_{n+1-alpha_f}; the effective matrix is
    factorised once. The run starts from static equilibrium (a_0 = 0). One
    residual a step: the full Newton step is taken without the backtracking
    line search's second residual (the same bits, 20 % less CPU:
    benchmarks/bench_ci_jobs.py).

    Returns
    -------
    dict with ``force_N`` and ``seconds``.
    """
    output.set_output(quiet=True)
    nt = wy.shape[0]
    nf = model.n_dofs
    kmat, mmat = model.K.tocsr(), model.M.tocsr()
    cmat = (alpha * mmat + beta * kmat).tocsr()
    blocks = sp.block_diag([kmat, cmat, mmat], format="csr")
    nsub = int(substeps)
    times = (h / nsub) * np.arange((nt - 1) * nsub + 1)

    inertia = None if base is None else -(model.M @ base.rigid)  # (nf, 2): load per unit base acceleration

    def load(t):
        k = int(np.clip(np.floor(t / h + 1e-9), 0, nt - 2))
        lam = np.clip(t / h - k, 0.0, 1.0)
        wyt = (1 - lam) * wy[k] + lam * wy[k + 1]
        wzt = (1 - lam) * wz[k] + lam * wz[k + 1]
        f = model.load_y.T @ wyt + model.load_z.T @ wzt
        if inertia is not None:
            f = f + inertia @ ((1 - lam) * base_acceleration[k] + lam * base_acceleration[k + 1])
        return f

    class _State:
        ts = None

    def fun(vec):
        u, v, a = vec[:nf], vec[nf : 2 * nf], vec[2 * nf :]
        return np.concatenate([kmat @ u - load(_State.ts.time), cmat @ v, mmat @ a])

    def fun_grad(vec):
        return blocks

    class _LS(ScipyDirect):
        """sfepy's direct solver, factorising the (symmetric positive definite) effective matrix once."""

        def presolve(self, mtx, use_mtx_digest=True):
            if self.solve is None:
                self.solve = factorize_spd(mtx, model.solver).solve

    def full_step(vec_x0, vec_r0, vec_dx0, it, err_last, conf, fun, apply_lin_solver, timers, log=None, context=None):
        """sfepy's line search (``line_search_fun``) for a linear system solved exactly: at the first iterate the
        residual (the step's right-hand side), after the solve the full Newton step. Its residual is not evaluated:
        sfepy's backtracking search computes it only to accept the full step (it falls by the solve's precision),
        and with ``i_max`` 1 nothing else reads it; one residual a step instead of two."""
        vec_x = vec_x0 - vec_dx0
        if it > 0:
            return vec_x, None, np.nan, True
        vec_r = fun(vec_x)
        err = float(np.linalg.norm(vec_r))
        if not np.isfinite(err):
            raise ValueError("infs or nans in the residual")
        return vec_x, vec_r, err, True

    ls = _LS({"use_presolve": True, "use_mtx_digest": False})
    nls = Newton(
        {"i_max": 1, "eps_a": 0.0, "eps_r": 0.0, "is_linear": True, "line_search_fun": full_step},
        fun=fun, fun_grad=fun_grad, lin_solver=ls,
    )

    class _GA(GeneralizedAlphaTS):
        def get_a0(self, nls, u0, e0, v0, unpack):
            # caches the constant M, C, K as sfepy's own get_a0() does; the static start has a0 = 0
            self.get_matrices(nls, np.concatenate([u0, e0, v0, np.zeros_like(v0)]), unpack)
            return np.zeros_like(u0)

    conf = Struct(
        name="ga",
        kind="ts.generalized_alpha",
        t0=0.0,
        t1=times[-1],
        n_step=len(times),
        rho_inf=rho_inf,
        is_linear=True,
        var_names={"u": "u", "du": "du", "ddu": "ddu"},
        verbose=False,
        quasistatic=False,
    )
    solver = _GA(conf, nls=nls)
    solver.set_dof_info(
        Struct(
            indx={"u": slice(0, nf), "du": slice(nf, 2 * nf), "ddu": slice(2 * nf, 3 * nf)},
            n_dof={"u": nf, "du": nf, "ddu": nf},
            n_dof_total=3 * nf,
        )
    )
    _State.ts = solver.ts
    u0 = model.factor().solve(load(0.0))
    vec0 = np.concatenate([u0, np.zeros(nf), np.zeros(nf)])
    out = np.zeros(nt)
    probes = None if base is None else np.zeros((base.probe_rows.shape[0], nt))

    def poststep(ts, vec):
        if ts.step % nsub:
            return vec
        k = ts.step // nsub
        out[k] = model.sensor @ vec[:nf]
        if probes is not None:
            probes[:, k] = base.probe_rows @ vec[2 * nf:]
        if progress is not None and k % 200 == 0:
            progress(k, nt)
        return vec

    t0 = time.perf_counter()
    solver(vec0=vec0, init_fun=lambda ts, v: v, prestep_fun=lambda ts, v: v, poststep_fun=poststep)
    result = {"force_N": out, "seconds": time.perf_counter() - t0}
    if probes is not None:
        result["probe_acceleration_m_per_s2"] = probes + base.probe_base @ base_acceleration.T
    return result
