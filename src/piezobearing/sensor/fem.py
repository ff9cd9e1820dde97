r"""The sensor stack in finite elements: sfepy matrices, scipy solves.

Weak form (time-harmonic, :math:`e^{j\omega t}`), displacement :math:`u` on
the whole stack, electric potential :math:`\phi` on the PZT only
(:math:`T = c^E \varepsilon + e^T\nabla\phi`, :math:`D = e\,\varepsilon -
\varepsilon^S \nabla\phi`):

.. math::
    \int_\Omega \varepsilon(v) : c : \varepsilon(u)
    - \omega^2 \int_\Omega \rho\, v\cdot u
    + \int_{\Omega_p} e_{kij}\varepsilon_{ij}(v)\nabla_k\phi
    = \int_{\Gamma_F} v\cdot t ,

    \int_{\Omega_p} e_{kij}\varepsilon_{ij}(u)\nabla_k q
    - \int_{\Omega_p} \varepsilon^S_{kl}\nabla_k q \nabla_l\phi
    = -\sum_{\rm electrodes} Q\, q|_{\rm electrode} ,

assembled with sfepy's ``dw_lin_elastic``, ``dw_dot``, ``dw_piezo_coupling``
and ``dw_diffusion`` into :math:`K, M, G, K_{\phi\phi}`. The top PZT face
(the clamped side, the housing) is grounded, :math:`\phi = 0`; the bottom
face is the hot electrode, one unknown potential :math:`V` shared by all its
nodes. Its row is the electrode's full charge balance (piezoelectric and
dielectric parts alike, because it is the weak form's own residual):

.. math::
    g^T u - k^T\phi_I - k_{EE} V = -Q, \qquad
    -Q = \frac{Y(\omega)}{j\omega} V = \Big(C_{\rm cable} + \frac{1}{j\omega R}\Big) V ,

with the measuring circuit's admittance :math:`Y = 1/R + j\omega C_{\rm cable}`
(charge leaves the electrode through the circuit). Eliminating the interior
potentials (no inertia, so exactly) gives the short-circuit stiffness
:math:`K_s = K + G_I K_{II}^{-1} G_I^T`, the coupling vector
:math:`b = g - G_I K_{II}^{-1}k` and the blocked capacitance
:math:`c_0 = k_{EE} - k^T K_{II}^{-1} k`:

.. math::
    \Big(K_s - \omega^2 M + \frac{b\,b^T}{c_0 + Y/(j\omega)}\Big) u = f ,\qquad
    V = \frac{b^T u}{c_0 + Y/(j\omega)} .

The circuit is a rank-one update of the real short-circuit problem: open
circuit is :math:`Y = 0`, short circuit :math:`V = 0`. With
:math:`\alpha = b^T (K_s-\omega^2M)^{-1} f` and
:math:`\beta = b^T (K_s-\omega^2M)^{-1} b`, Sherman-Morrison gives
:math:`V = \alpha / (c_0 + \beta + Y/(j\omega))`; :math:`\alpha, \beta` come
from a real modal reduction (short-circuit modes plus the two static
vectors :math:`K_s^{-1}f, K_s^{-1}b`), which is exact at zero frequency.

Only a quarter of the stack is meshed (:mod:`piezobearing.sensor.mesh`). The
planes x = 0 and y = 0 carry symmetric (S: normal displacement zero,
potential free) or antisymmetric (A: in-plane displacements and potential
zero) conditions; SS holds every axisymmetric mode (all that a centred axial
force excites), SA/AS the bending/rocking pairs, AA the torsion modes. In
every family but SS the hot electrode's potential is forced to zero by the
antisymmetry, so its short- and open-circuit frequencies coincide. All
energies, charges and capacitances of the quarter are a quarter of the full
stack's; the circuit admittance is scaled accordingly.

The potential unknowns are scaled by :math:`s = \sqrt{\max K / \max K_{\phi\phi}}`
(about 1e9) before any direct solve, since the two blocks differ by ~1e19.

Size. Over 600 lines as one module: assembly, boundary conditions, reduction, modes and the
measuring circuit act on the same assembled matrices and DOF maps (``Assembled``, ``ReducedSystem``);
the mode labelling and the modal survey are candidates for a module of their own.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg import eigh
from scipy.optimize import brentq, minimize_scalar
from scipy.spatial import cKDTree

from piezobearing.numerics import sfepy_setup  # noqa: F401  (before sfepy: without its JAX terms where JAX is absent)

# isort: split
from sfepy.base.base import output
from sfepy.discrete import Equation, Equations, FieldVariable, Integral, Material, Problem
from sfepy.discrete.fem import FEDomain, Field, Mesh
from sfepy.terms import Term

from piezobearing.numerics import sparse_solve
from piezobearing.sensor.materials import IsotropicMaterial, StressChargeForm
from piezobearing.sensor.mesh import GROUP_ADHESIVE, GROUP_BOTTOM_DISK, GROUP_PZT, GROUP_TOP_DISK, StackMesh

log = logging.getLogger(__name__)

#: Fraction of the full stack represented by the quarter mesh.
SECTOR_FRACTION = 0.25

#: Seed of ARPACK's start vector (and of any restart vector it asks for). Without it scipy draws
#: them from OS entropy and the eigenpairs differ in their last digits from run to run.
ARPACK_SEED = 20240521


# --------------------------------------------------------------------------- assembly


@dataclass(frozen=True)
class StackMaterials:
    """Material data the FEM needs.

    ``pzt`` in stress-charge form (sfepy order), ``pzt_density_kg_per_m3``,
    the alumina of the two disks, and the bond layers' ``adhesive`` (needed
    only if the mesh has adhesive cells).
    """

    pzt: StressChargeForm
    pzt_density_kg_per_m3: float
    alumina: IsotropicMaterial
    adhesive: IsotropicMaterial | None = None


@dataclass
class Assembled:
    """Unconstrained matrices of the quarter stack, sfepy's DOF order.

    ``K`` (nu, nu) stiffness [N/m], ``M`` (nu, nu) mass [kg], ``G`` (nu, np)
    piezoelectric coupling [C/m = N/V], ``Kpp`` (np, np) dielectric [F];
    ``u_coors`` (nu/3, 3) displacement node coordinates (DOFs are
    node-major: x, y, z of node 0, then node 1, ...), ``p_coors`` (np, 3)
    potential node coordinates [m]; ``load`` (nu,) consistent nodal forces of
    a unit total force on the load face of the full stack, i.e. 0.25 N on
    the quarter, pointing into the stack [N].
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    G: sp.csr_matrix
    Kpp: sp.csr_matrix
    u_coors: np.ndarray
    p_coors: np.ndarray
    load: np.ndarray
    mesh: StackMesh = field(repr=False)

    @property
    def n_u(self) -> int:
        return self.K.shape[0]


def _sfepy_quiet():
    output.set_output(quiet=True)


def _lagrange_1d(order: int, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes on [-1, 1] and the 1D Lagrange shape functions (len(nodes), len(a)) of the given order."""
    nodes = np.linspace(-1.0, 1.0, order + 1)
    n = np.ones((order + 1, len(a)))
    for i, xi in enumerate(nodes):
        for j, xj in enumerate(nodes):
            if i != j:
                n[i] *= (a - xj) / (xi - xj)
    return nodes, n


def face_load(mesh: StackMesh, u_coors: np.ndarray, order: int, face: str) -> np.ndarray:
    """Consistent nodal z-forces [N] of a unit uniform traction on the bottom or top face.

    Integrates the tensor-product Lagrange shape functions of every face
    quadrilateral over its bilinear map (Gauss rule exact for the
    integrand); face nodes are found by their coordinates among ``u_coors``.
    Returns a vector over all displacement DOFs (node-major, z components set).
    """
    z = mesh.coors[:, 2]
    zf = z.min() if face == "bottom" else z.max()
    local = [0, 1, 2, 3] if face == "bottom" else [4, 5, 6, 7]
    quads = mesh.cells[:, local]
    quads = quads[np.all(np.abs(z[quads] - zf) < 1e-9 * np.ptp(z), axis=1)]
    nodes, _ = _lagrange_1d(order, np.zeros(1))
    g, w = np.polynomial.legendre.leggauss(order + 2)
    _, ng = _lagrange_1d(order, g)  # (order+1, ng)
    tree = cKDTree(u_coors)
    out = np.zeros(u_coors.shape[0] * 3)
    ga, gb = np.meshgrid(g, g, indexing="ij")
    wab = np.outer(w, w)
    for q in quads:
        xy = mesh.coors[q, :2]
        # Jacobian of the bilinear map at the Gauss points.
        da = 0.25 * np.array([-(1 - gb), (1 - gb), (1 + gb), -(1 + gb)])
        db = 0.25 * np.array([-(1 - ga), -(1 + ga), (1 + ga), (1 - ga)])
        xa, ya = np.tensordot(xy[:, 0], da, 1), np.tensordot(xy[:, 1], da, 1)
        xb, yb = np.tensordot(xy[:, 0], db, 1), np.tensordot(xy[:, 1], db, 1)
        jac = np.abs(xa * yb - xb * ya) * wab
        for i, a in enumerate(nodes):
            for j, b in enumerate(nodes):
                m4 = 0.25 * np.array(
                    [(1 - a) * (1 - b), (1 + a) * (1 - b), (1 + a) * (1 + b), (1 - a) * (1 + b)]
                )
                p = np.array([*(m4 @ xy), zf])
                dist, k = tree.query(p)
                if dist > 1e-9 * np.ptp(mesh.coors):
                    raise RuntimeError(f"face node {p} not found among the displacement nodes")
                out[3 * k + 2] += np.sum(np.outer(ng[i], ng[j]) * jac)
    return out


def assemble(mesh: StackMesh, mat: StackMaterials, order: int = 2, load_face: str = "bottom") -> Assembled:
    """Assemble K, M, G, Kpp and the load vector with sfepy.

    Parameters
    ----------
    mesh : StackMesh
        Quarter hexahedral mesh (groups 1, 2, 3: bottom disk, PZT, top disk).
    mat : StackMaterials
    order : int
        Lagrange approximation order of both fields (2: 27-node hexahedra).
    load_face : {"bottom", "top"}
        Face carrying the unit force (uniform traction), directed into the
        body: +z on the bottom face, -z on the top face.
    """
    _sfepy_quiet()
    smesh = Mesh.from_data(
        "stack", mesh.coors, None, [mesh.cells.astype(np.int32)], [mesh.groups.astype(np.int32)], ["3_8"]
    )
    domain = FEDomain("stack", smesh)
    omega = domain.create_region("Omega", "all")
    present = set(np.unique(mesh.groups))
    regions = {
        g: domain.create_region(f"G{g}", f"cells of group {g}")
        for g in (GROUP_BOTTOM_DISK, GROUP_PZT, GROUP_TOP_DISK, GROUP_ADHESIVE)
        if g in present
    }
    if load_face not in ("bottom", "top"):
        raise ValueError(f"load_face must be 'bottom' or 'top', got {load_face!r}")
    direction = 1.0 if load_face == "bottom" else -1.0

    fu = Field.from_args("fu", np.float64, "vector", omega, approx_order=order)
    fp = Field.from_args("fp", np.float64, "scalar", regions[GROUP_PZT], approx_order=order)
    u = FieldVariable("u", "unknown", fu)
    v = FieldVariable("v", "test", fu, primary_var_name="u")
    p = FieldVariable("p", "unknown", fp)
    q = FieldVariable("q", "test", fp, primary_var_name="p")
    integral = Integral("i", order=2 * order)

    alu = mat.alumina
    m_alu = Material("alu", D=alu.stiffness_voigt(), rho=alu.density_kg_per_m3)
    m_pzt = Material(
        "pzt",
        D=mat.pzt.c_E_Pa,
        rho=mat.pzt_density_kg_per_m3,
        e=mat.pzt.e_C_per_m2,
        kappa=mat.pzt.eps_S_F_per_m,
    )
    passive = {GROUP_BOTTOM_DISK: m_alu, GROUP_TOP_DISK: m_alu}
    if GROUP_ADHESIVE in regions:
        if mat.adhesive is None:
            raise ValueError("the mesh has adhesive layers but StackMaterials.adhesive is not given")
        adh = mat.adhesive
        passive[GROUP_ADHESIVE] = Material("adh", D=adh.stiffness_voigt(), rho=adh.density_kg_per_m3)
    t_stiff, t_mass = [], []
    for g, reg in regions.items():
        mm = m_pzt if g == GROUP_PZT else passive[g]
        t_stiff.append(
            Term.new(f"dw_lin_elastic({mm.name}.D, v, u)", integral, reg, **{mm.name: mm}, v=v, u=u)
        )
        t_mass.append(Term.new(f"dw_dot({mm.name}.rho, v, u)", integral, reg, **{mm.name: mm}, v=v, u=u))
    reg_p = regions[GROUP_PZT]
    t_g = Term.new("dw_piezo_coupling(pzt.e, v, p)", integral, reg_p, pzt=m_pzt, v=v, p=p)
    t_gt = Term.new("dw_piezo_coupling(pzt.e, u, q)", integral, reg_p, pzt=m_pzt, u=u, q=q)
    t_d = Term.new("dw_diffusion(pzt.kappa, q, p)", integral, reg_p, pzt=m_pzt, q=q, p=p)
    eq_k = Equation("K", sum(t_stiff[1:], t_stiff[0]))
    eq_m = Equation("M", sum(t_mass[1:], t_mass[0]))
    eq_g = Equation("G", t_g + t_gt)
    eq_d = Equation("D", t_d)
    pb = Problem("stack", equations=Equations([eq_k, eq_m, eq_g, eq_d]), domain=domain)
    pb.time_update()
    pb.update_materials()
    template = pb.mtx_a

    def mat_of(eq):
        a = template.copy()
        a.data[:] = 0.0
        return eq.evaluate(mode="weak", dw_mode="matrix", asm_obj=a).tocsr()

    full_k, full_m, full_g, full_d = (mat_of(e) for e in (eq_k, eq_m, eq_g, eq_d))
    adi = pb.equations.variables.adi
    su, spp = adi.indx["u"], adi.indx["p"]
    K = full_k[su, su]
    M = full_m[su, su]
    G = full_g[su, spp]
    Gt = full_g[spp, su]
    if abs(G - Gt.T).max() > 1e-9 * abs(G).max():
        raise RuntimeError("dw_piezo_coupling blocks are not transposes of each other")
    Kpp = full_d[spp, spp]

    # Consistent load of a uniform traction, integrated here: sfepy's dw_surface_ltr distributed
    # the load of non-parallelogram hexahedron faces to the wrong nodes (tests/test_sensor_fem.py).
    u_coors = fu.get_coor().copy()
    load = face_load(mesh, u_coors, order, load_face) * direction
    load *= SECTOR_FRACTION / abs(load[2::3].sum())
    return Assembled(
        K=K,
        M=M,
        G=G,
        Kpp=Kpp,
        u_coors=fu.get_coor().copy(),
        p_coors=fp.get_coor().copy(),
        load=load,
        mesh=mesh,
    )


# --------------------------------------------------------------------------- constraints


@dataclass(frozen=True)
class BoundaryConditions:
    """Mechanical and electrical conditions of one analysis.

    Parameters
    ----------
    symmetry : str
        Two letters for the planes x = 0 and y = 0: "S" (mirror symmetric) or
        "A" (antisymmetric).
    clamped : tuple of (face, components)
        Faces ("top": z = z_max, "bottom": z = z_min) and the displacement
        components (0, 1, 2) held at zero there.
    hot_z_m, ground_z_m : float
        z of the hot (floating) and the grounded electrode faces of the PZT [m].
    """

    symmetry: str = "SS"
    clamped: tuple = (("top", (0, 1, 2)),)
    hot_z_m: float = 0.0
    ground_z_m: float = 0.0


def _select(coors, value, axis, tol):
    return np.flatnonzero(np.abs(coors[:, axis] - value) < tol)


def _face_dofs(asm: Assembled, face: str, comps, tol) -> np.ndarray:
    z = asm.u_coors[:, 2]
    zz = z.max() if face == "top" else z.min()
    nodes = _select(asm.u_coors, zz, 2, tol)
    return np.concatenate([3 * nodes + c for c in comps]) if len(nodes) else np.array([], int)


@dataclass
class ReducedSystem:
    """The constrained, potential-scaled problem of one symmetry family.

    Holds the free displacement blocks (``K``, ``M``, load ``f``), the
    interior potential blocks, the coupling vector ``b`` and blocked
    capacitance ``c0`` of the hot electrode (quarter model, [C/m] and [F]),
    and a factorization of the short-circuit saddle matrix.
    """

    asm: Assembled = field(repr=False)
    bc: BoundaryConditions
    free_u: np.ndarray
    K: sp.csr_matrix = field(repr=False)
    M: sp.csr_matrix = field(repr=False)
    G_I: sp.csr_matrix = field(repr=False)
    Kpp_II: sp.csr_matrix = field(repr=False)
    g: np.ndarray = field(repr=False)
    k_I: np.ndarray = field(repr=False)
    k_EE: float
    f: np.ndarray = field(repr=False)
    scale: float
    electrode_active: bool
    solver: str | None = None
    #: The largest set of modes solved so far, by circuit (:func:`modes` answers smaller requests from it).
    _modes: dict = field(default_factory=dict, repr=False, compare=False)

    @cached_property
    def _saddle_lu(self):
        """Factors of the symmetric indefinite saddle matrix: PARDISO's LDL^T, or SuperLU (``solver``)."""
        s = self.scale
        a = sp.bmat([[self.K, s * self.G_I], [s * self.G_I.T, -(s * s) * self.Kpp_II]], format="csc")
        log.info("factorizing saddle matrix n=%d nnz=%d", a.shape[0], a.nnz)
        return sparse_solve.factorize(a, definite=False, solver=self.solver, ordering="MMD_AT_PLUS_A")

    @cached_property
    def _kpp_lu(self):
        return spla.splu(self.Kpp_II.tocsc(), permc_spec="MMD_AT_PLUS_A")

    def solve_short(self, y: np.ndarray) -> np.ndarray:
        """K_s^{-1} y for one or more columns y (free displacement DOFs)."""
        y = np.asarray(y, dtype=float)
        one = y.ndim == 1
        y2 = y[:, None] if one else y
        rhs = np.vstack([y2, np.zeros((self.G_I.shape[1], y2.shape[1]))])
        x = self._saddle_lu.solve(rhs)[: self.K.shape[0]]
        return x[:, 0] if one else x

    def potential_of(self, u: np.ndarray) -> np.ndarray:
        """Interior potentials [V] of the short-circuited electrode for displacements u."""
        if self.G_I.shape[1] == 0:
            return np.zeros(0)
        return self._kpp_lu.solve(self.G_I.T @ u)

    def ks_matvec(self, x: np.ndarray) -> np.ndarray:
        """K_s x = K x + G_I K_II^{-1} G_I^T x."""
        return self.K @ x + self.G_I @ self.potential_of(x)

    @cached_property
    def _w(self) -> np.ndarray:
        return self._kpp_lu.solve(self.k_I) if len(self.k_I) else np.zeros(0)

    @cached_property
    def b(self) -> np.ndarray:
        """Coupling vector of the hot electrode b = g - G_I K_II^{-1} k [C/m] (quarter)."""
        if not self.electrode_active:
            return np.zeros(self.K.shape[0])
        return self.g - self.G_I @ self._w

    @cached_property
    def c0(self) -> float:
        """Blocked (clamped-strain) capacitance of the hot electrode [F] (quarter)."""
        if not self.electrode_active:
            return np.inf
        return float(self.k_EE - self.k_I @ self._w)

    @cached_property
    def ks_inv_b(self) -> np.ndarray:
        return self.solve_short(self.b)

    @cached_property
    def ks_inv_f(self) -> np.ndarray:
        return self.solve_short(self.f)

    @property
    def static_capacitance_F(self) -> float:
        """Capacitance with the mechanical conditions, zero force: c0 + b^T K_s^{-1} b [F] (quarter)."""
        return self.c0 + float(self.b @ self.ks_inv_b)

    def static_open_voltage_V(self) -> float:
        """Open-circuit voltage under the unit force [V] (full stack, 1 N)."""
        return float(self.b @ self.ks_inv_f) / self.static_capacitance_F

    def solve_open(self, y: np.ndarray) -> np.ndarray:
        """(K_s + b b^T / c0)^{-1} y: the open-circuit (floating electrode) stiffness inverse."""
        x = self.solve_short(y)
        if not self.electrode_active:
            return x
        return x - np.outer(self.ks_inv_b, self.b @ x).reshape(x.shape) / self.static_capacitance_F

    def full_u(self, x: np.ndarray) -> np.ndarray:
        """Free-DOF displacements to all DOFs of the quarter (constrained ones zero), shape (n_nodes, 3)."""
        out = np.zeros(self.asm.n_u)
        out[self.free_u] = x
        return out.reshape(-1, 3)


def reduce(asm: Assembled, bc: BoundaryConditions, solver: str | None = None) -> ReducedSystem:
    """Apply the conditions of ``bc`` and split the potential into interior and electrodes.

    ``solver`` factorises the saddle matrix (:func:`piezobearing.numerics.sparse_solve.factorize`):
    None (PARDISO where installed), ``pardiso`` or ``superlu`` (the previous method).
    """
    if len(bc.symmetry) != 2 or set(bc.symmetry) - {"S", "A"}:
        raise ValueError(f"symmetry must be two letters S/A, got {bc.symmetry!r}")
    span = np.ptp(asm.u_coors, axis=0).max()
    tol = 1e-8 * span
    fixed = []
    p_fixed = []
    for axis, kind in enumerate(bc.symmetry):
        nodes = _select(asm.u_coors, 0.0, axis, tol)
        if kind == "S":
            fixed.append(3 * nodes + axis)
        else:
            others = [c for c in range(3) if c != axis]
            fixed += [3 * nodes + c for c in others]
            p_fixed.append(_select(asm.p_coors, 0.0, axis, tol))
    for face, comps in bc.clamped:
        fixed.append(_face_dofs(asm, face, comps, tol))
    fixed = np.unique(np.concatenate(fixed))
    free_u = np.setdiff1d(np.arange(asm.n_u), fixed)

    ground = _select(asm.p_coors, bc.ground_z_m, 2, tol)
    hot = _select(asm.p_coors, bc.hot_z_m, 2, tol)
    if len(ground) == 0 or len(hot) == 0:
        raise ValueError("no potential nodes on the electrode faces; check hot_z_m / ground_z_m")
    p_zero = np.unique(np.concatenate([ground] + p_fixed))
    electrode_active = not np.intersect1d(hot, p_zero).size
    hot_free = hot if electrode_active else np.array([], int)
    interior = np.setdiff1d(np.arange(asm.p_coors.shape[0]), np.concatenate([p_zero, hot]))

    K = asm.K[free_u][:, free_u].tocsr()
    M = asm.M[free_u][:, free_u].tocsr()
    G = asm.G[free_u]
    G_I = G[:, interior].tocsr()
    Kpp_II = asm.Kpp[interior][:, interior].tocsr()
    ones = np.ones(len(hot_free))
    g = np.asarray(G[:, hot_free] @ ones).ravel()
    k_I = np.asarray(asm.Kpp[interior][:, hot_free] @ ones).ravel()
    k_EE = float(ones @ (asm.Kpp[hot_free][:, hot_free] @ ones))
    kmax = abs(K.diagonal()).max()
    pmax = abs(Kpp_II.diagonal()).max() if Kpp_II.shape[0] else 1.0
    scale = float(np.sqrt(kmax / pmax))
    return ReducedSystem(
        asm=asm,
        bc=bc,
        free_u=free_u,
        K=K,
        M=M,
        G_I=G_I,
        Kpp_II=Kpp_II,
        g=g,
        k_I=k_I,
        k_EE=k_EE,
        f=asm.load[free_u],
        scale=scale,
        electrode_active=electrode_active,
        solver=solver,
    )


# --------------------------------------------------------------------------- modes


@dataclass(frozen=True)
class Modes:
    """Mass-normalised modes of one family: frequencies [Hz], shapes (n_free, k)."""

    frequency_Hz: np.ndarray
    shapes: np.ndarray


def modes(rs: ReducedSystem, n: int, circuit: str = "short") -> Modes:
    """The n lowest modes with the electrode short- or open-circuited (floating, zero net charge).

    Shift-invert Lanczos (ARPACK) about zero, the inverse applied through the
    short-circuit saddle factorization (open circuit: plus a rank-one update).
    The start vector is a fixed pseudo-random vector (seed ``ARPACK_SEED``), so
    the same system gives bit-identical modes in every run; each shape's sign is
    fixed by making its largest component positive.

    The largest set solved on ``rs`` is kept (per circuit): a request for no
    more modes returns its lowest n instead of a new solve (they agree with a
    solve for n alone to ARPACK's tolerance, 1e-10; the sensor_modal rule asks
    the SS system for 8, 5, 12, 3 and 2 modes, and solves 3 times instead of 7).
    """
    n_free = rs.K.shape[0]
    solve = rs.solve_short if circuit == "short" else rs.solve_open
    if circuit not in ("short", "open"):
        raise ValueError(f"circuit must be 'short' or 'open', got {circuit!r}")
    k = min(n, n_free - 2)
    done = rs._modes.get(circuit)
    if done is not None and done.shapes.shape[1] >= k:
        return Modes(done.frequency_Hz[:k].copy(), done.shapes[:, :k].copy())
    op = spla.LinearOperator((n_free, n_free), matvec=solve, dtype=float)
    a = spla.LinearOperator((n_free, n_free), matvec=rs.ks_matvec, dtype=float)
    v0 = np.random.default_rng(ARPACK_SEED).uniform(-1.0, 1.0, n_free)
    lam, vec = spla.eigsh(
        a,
        k=k,
        M=rs.M,
        sigma=0.0,
        OPinv=op,
        which="LM",
        tol=1e-10,
        v0=v0,
        rng=np.random.default_rng(ARPACK_SEED + 1),
    )
    order = np.argsort(lam)
    lam, vec = lam[order], vec[:, order]
    vec = vec / np.sqrt(np.einsum("ik,ik->k", vec, rs.M @ vec))
    vec = vec * np.sign(vec[np.abs(vec).argmax(axis=0), np.arange(vec.shape[1])])
    out = Modes(np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), vec)
    rs._modes[circuit] = out
    return Modes(out.frequency_Hz.copy(), out.shapes.copy())


def modes_below(rs: ReducedSystem, f_max_Hz: float, circuit: str = "short", n_start: int = 8) -> Modes:
    """All modes below ``f_max_Hz`` (asks for more until one lies above)."""
    n = n_start
    while True:
        m = modes(rs, n, circuit)
        if m.frequency_Hz[-1] > f_max_Hz or n >= rs.K.shape[0] - 3:
            keep = m.frequency_Hz < f_max_Hz
            return Modes(m.frequency_Hz[keep], m.shapes[:, keep])
        n *= 2


# --------------------------------------------------------------------------- mode labels


def _test_fields(coors: np.ndarray, kind: str) -> np.ndarray:
    """Columns of displacement fields (n_nodes*3, k) spanning a symmetry type, low-order polynomials."""
    x, y, z = coors.T
    zs = (z - z.mean()) / np.ptp(z)
    rs2 = (x**2 + y**2) / (x**2 + y**2).max()
    polys = [np.ones_like(x), zs, zs**2, rs2, zs * rs2, zs**3, rs2**2]
    cols = []
    for pfun in polys:
        u = np.zeros((len(x), 3))
        if kind == "axial":
            u[:, 2] = pfun
        elif kind == "radial":
            u[:, 0], u[:, 1] = x * pfun, y * pfun
        elif kind == "torsion":
            u[:, 0], u[:, 1] = -y * pfun, x * pfun
        elif kind == "lateral":  # translation/rotation family of the SA planes: along y, rocking about x
            u[:, 1] = pfun
            u[:, 2] = y * pfun
        cols.append(u.ravel())
    return np.column_stack(cols)


def _captured(rs: ReducedSystem, shape: np.ndarray, kind: str) -> float:
    """Fraction of the mode's M-norm in the span of the test fields of ``kind``."""
    t = _test_fields(rs.asm.u_coors, kind)[rs.free_u]
    mt = rs.M @ t
    gram = t.T @ mt
    rhs = mt.T @ shape
    coef = np.linalg.lstsq(gram, rhs, rcond=1e-12)[0]
    return float(rhs @ coef / (shape @ (rs.M @ shape)))


def kinetic_fractions(rs: ReducedSystem, shape: np.ndarray) -> dict:
    """Share of the mode's (lumped) kinetic energy in radial, circumferential and axial motion."""
    lumped = np.asarray(rs.asm.M.sum(axis=1)).ravel().reshape(-1, 3)[:, 0]
    u = rs.full_u(shape)
    x, y = rs.asm.u_coors[:, 0], rs.asm.u_coors[:, 1]
    r = np.hypot(x, y)
    c, s = np.where(r > 0, x / np.where(r > 0, r, 1), 1.0), np.where(r > 0, y / np.where(r > 0, r, 1), 0.0)
    ur = c * u[:, 0] + s * u[:, 1]
    ut = -s * u[:, 0] + c * u[:, 1]
    e = np.array([(lumped * ur**2).sum(), (lumped * ut**2).sum(), (lumped * u[:, 2] ** 2).sum()])
    e = e / e.sum()
    return {"radial": float(e[0]), "circumferential": float(e[1]), "axial": float(e[2])}


def label_mode(rs: ReducedSystem, shape: np.ndarray) -> tuple[str, dict]:
    """Label a mode from its shape: axial, radial, torsion, bending/rocking, or n>=2.

    The symmetry family fixes the circumferential character (SS: n = 0 or 2,
    AA: torsion or n = 2, SA/AS: n = 1, bending/rocking); within SS and AA
    the mode's share in axisymmetric (resp. torsional) polynomial fields
    separates n = 0 from n = 2, and for n = 0 the larger of the axial and
    radial kinetic energies names it.
    """
    fam = rs.bc.symmetry
    kin = kinetic_fractions(rs, shape)
    info = {"kinetic": kin}
    if fam == "SS":
        ax, ra = _captured(rs, shape, "axial"), _captured(rs, shape, "radial")
        info["axisymmetric_fraction"] = ax + ra
        if ax + ra < 0.05:
            return "radial (n=2)", info
        return ("axial" if kin["axial"] >= kin["radial"] else "radial"), info
    if fam == "AA":
        tor = _captured(rs, shape, "torsion")
        info["torsion_fraction"] = tor
        return ("torsion" if tor >= 0.05 else "circumferential (n=2)"), info
    return "bending/rocking", info


# --------------------------------------------------------------------------- harmonic response


@dataclass(frozen=True)
class MeasuringCircuit:
    """What hangs across the electrodes: resistance R [Ohm] parallel to a capacitance [F] (the cable)."""

    resistance_ohm: float
    capacitance_F: float

    def admittance_over_jw(self, f_Hz: np.ndarray) -> np.ndarray:
        """Y / (j omega) = C + 1 / (j omega R) [F] for the full stack."""
        w = 2 * np.pi * np.asarray(f_Hz, dtype=float)
        return self.capacitance_F + 1.0 / (1j * w * self.resistance_ohm)


@dataclass(frozen=True)
class ReducedModel:
    """Real Ritz model of the SS family, enough for every harmonic quantity.

    ``omega2`` (k,) Ritz eigenvalues [rad^2/s^2]; ``b_k``, ``f_k`` (k,) the
    coupling vector and the load projected on the M-normalised Ritz vectors;
    ``c0_F`` blocked capacitance; all of the quarter model (multiply charges
    and capacitances by 1/SECTOR_FRACTION for the full stack).
    """

    omega2: np.ndarray
    b_k: np.ndarray
    f_k: np.ndarray
    c0_F: float
    damping_ratio: float = 0.0

    def alpha_beta(self, f_Hz) -> tuple[np.ndarray, np.ndarray]:
        """alpha = b^T H f and beta = b^T H b, H = (K_s - w^2 M + j 2 zeta w_k w)^-1 (quarter)."""
        w = 2 * np.pi * np.atleast_1d(np.asarray(f_Hz, dtype=float))[:, None]
        wk = np.sqrt(self.omega2)[None, :]
        den = self.omega2[None, :] - w**2 + 2j * self.damping_ratio * wk * w
        alpha = (self.b_k * self.f_k / den).sum(axis=1)
        beta = (self.b_k**2 / den).sum(axis=1)
        return alpha, beta

    def voltage_per_force(self, f_Hz, circuit: MeasuringCircuit | None) -> np.ndarray:
        """Complex V/F [V/N] of the full stack; ``None`` = open circuit (no circuit at all)."""
        alpha, beta = self.alpha_beta(f_Hz)
        load = 0.0 if circuit is None else SECTOR_FRACTION * circuit.admittance_over_jw(np.atleast_1d(f_Hz))
        return alpha / (self.c0_F + beta + load)

    @property
    def charge_per_force_C_per_N(self) -> float:
        """Short-circuit charge per newton at zero frequency, b^T K_s^-1 f (the stack's effective d33) [C/N]."""
        return float((self.b_k * self.f_k / self.omega2).sum()) / SECTOR_FRACTION

    @property
    def static_capacitance_F(self) -> float:
        """Electrode capacitance with the mechanical conditions, zero force: c0 + b^T K_s^-1 b [F] (full)."""
        return float(self.c0_F + (self.b_k**2 / self.omega2).sum()) / SECTOR_FRACTION


def reduced_model(rs: ReducedSystem, short_modes: Modes, damping_ratio: float = 0.0) -> ReducedModel:
    """Ritz reduction on [short-circuit modes, K_s^-1 f, K_s^-1 b], exact at zero frequency."""
    cols = [short_modes.shapes, rs.ks_inv_f[:, None]]
    if rs.electrode_active:
        cols.append(rs.ks_inv_b[:, None])
    t = np.hstack(cols)
    t = t / np.sqrt(np.einsum("ik,ik->k", t, rs.M @ t))
    kt = np.column_stack([rs.ks_matvec(t[:, k]) for k in range(t.shape[1])])
    kr = 0.5 * (t.T @ kt + (t.T @ kt).T)
    mr = t.T @ (rs.M @ t)
    mr = 0.5 * (mr + mr.T)
    lam, y = eigh(kr, mr)
    psi = t @ y
    return ReducedModel(
        omega2=lam, b_k=psi.T @ rs.b, f_k=psi.T @ rs.f, c0_F=rs.c0, damping_ratio=damping_ratio
    )


def direct_voltage_per_force(rs: ReducedSystem, f_Hz: float, circuit: MeasuringCircuit | None) -> complex:
    """V/F [V/N] from one direct (complex, undamped) solve of the full coupled system; for verification
    (:func:`direct_voltages_per_force` of one circuit)."""
    return direct_voltages_per_force(rs, f_Hz, [circuit])[0]


def direct_voltages_per_force(rs: ReducedSystem, f_Hz: float, circuits) -> list[complex]:
    """V/F [V/N] of the full coupled system (undamped) at ``f_Hz`` for each of ``circuits`` (None: open).

    The circuits change only the electrode's diagonal entry, d_c = -s^2 (k_EE + load_c): the system of the
    first circuit is factorised (SuperLU, complex) and solved for the force and for the electrode's unit
    vector e; each other circuit is the same matrix plus delta e e^T, whose electrode potential is exactly
    x_E / (1 + delta z_E) (Sherman-Morrison, z = M^-1 e): one factorisation per frequency instead of one
    per circuit, the same numbers to rounding (benchmarks/bench_sensor_fem.py compares them).
    """
    s = rs.scale
    w2 = (2 * np.pi * f_Hz) ** 2
    loads = [0.0 if c is None else SECTOR_FRACTION * complex(c.admittance_over_jw(f_Hz)) for c in circuits]
    n_i = rs.G_I.shape[1]
    a = sp.bmat(
        [
            [rs.K - w2 * rs.M, s * rs.G_I, s * sp.csr_matrix(rs.g[:, None])],
            [s * rs.G_I.T, -(s * s) * rs.Kpp_II, -(s * s) * sp.csr_matrix(rs.k_I[:, None])],
            [
                s * sp.csr_matrix(rs.g[None, :]),
                -(s * s) * sp.csr_matrix(rs.k_I[None, :]),
                sp.csr_matrix(np.array([[-(s * s) * (rs.k_EE + loads[0])]])),
            ],
        ],
        format="csc",
    ).astype(complex)
    rhs = np.concatenate([rs.f, np.zeros(n_i + 1)]).astype(complex)
    if len(circuits) == 1:
        return [complex(s * spla.spsolve(a, rhs)[-1])]
    lu = spla.splu(a)
    x_e = lu.solve(rhs)[-1]
    e = np.zeros(rhs.size, complex)
    e[-1] = 1.0
    z_e = lu.solve(e)[-1]
    out = []
    for load in loads:
        delta = -(s * s) * (load - loads[0])
        out.append(complex(s * x_e / (1.0 + delta * z_e)))
    return out


# --------------------------------------------------------------------------- analyses of the stack

#: The symmetry families of the quarter model; AS is the mirror image of SA
#: (the mesh is symmetric under x <-> y), so its modes are SA's partners.
FAMILIES = ("SS", "SA", "AA")


def stack_conditions(z_interfaces_m, family: str = "SS") -> BoundaryConditions:
    """The sensor's conditions: top face clamped, PZT bottom face hot, PZT top face grounded."""
    z = np.asarray(z_interfaces_m)
    return BoundaryConditions(family, (("top", (0, 1, 2)),), hot_z_m=float(z[1]), ground_z_m=float(z[2]))


@dataclass(frozen=True)
class ModeRecord:
    """One mode of the full stack: family, label, short/open frequencies [Hz], shape measures."""

    family: str
    multiplicity: int
    label: str
    frequency_short_Hz: float
    frequency_open_Hz: float
    kinetic: dict
    coupling_factor: float


@dataclass
class ModalSurvey:
    """Every mode below ``f_max_Hz`` and the SS family's system and modes (for the harmonic analysis)."""

    records: list
    ss_system: ReducedSystem = field(repr=False)
    ss_short: Modes = field(repr=False)

    @property
    def first_axial(self) -> ModeRecord:
        ax = [r for r in self.records if r.label == "axial"]
        if not ax:
            raise RuntimeError("no axial mode below the modal frequency limit; raise modal_max_frequency_Hz")
        return ax[0]


def modal_survey(asm: Assembled, z_interfaces_m, f_max_Hz: float) -> ModalSurvey:
    """Modes of every symmetry family below ``f_max_Hz``, short- and open-circuited, labelled by shape.

    SS modes are paired short/open by index: the open circuit is a rank-one
    stiffening, so its eigenvalues interlace the short-circuit ones.
    """
    records = []
    ss_sys = ss_short = None
    for fam in FAMILIES:
        rs = reduce(asm, stack_conditions(z_interfaces_m, fam))
        short = modes_below(rs, f_max_Hz, "short")
        if fam == "SS":
            ss_sys = rs
            n_all = len(short.frequency_Hz) + 4
            ss_short = modes(rs, n_all, "short")
            f_open = modes(rs, n_all, "open").frequency_Hz[: len(short.frequency_Hz)]
        else:
            f_open = short.frequency_Hz
        for k, f_s in enumerate(short.frequency_Hz):
            label, info = label_mode(rs, short.shapes[:, k])
            keff = float(np.sqrt(max(0.0, 1 - (f_s / f_open[k]) ** 2)))
            records.append(
                ModeRecord(
                    fam, 2 if fam == "SA" else 1, label, float(f_s), float(f_open[k]), info["kinetic"], keff
                )
            )
    records.sort(key=lambda r: r.frequency_short_Hz)
    return ModalSurvey(records, ss_sys, ss_short)


def first_axial_shape(survey: ModalSurvey) -> np.ndarray:
    """Short-circuit shape (free DOFs) of the first axial mode of the SS family, max |u| = 1."""
    rs, short = survey.ss_system, survey.ss_short
    f_ax = survey.first_axial.frequency_short_Hz
    k = int(np.argmin(np.abs(short.frequency_Hz - f_ax)))
    u = short.shapes[:, k]
    uz = rs.full_u(u)[:, 2]
    sign = np.sign(uz[np.argmax(np.abs(uz))])
    return sign * u / np.abs(rs.full_u(u)).max()


def loaded_resonance_Hz(
    model: ReducedModel, circuit: MeasuringCircuit, f_lo_Hz: float, f_hi_Hz: float
) -> float:
    """Frequency of the largest |V/F| in [f_lo, f_hi]: the first axial resonance with the circuit attached."""
    grid = np.linspace(f_lo_Hz, f_hi_Hz, 2001)
    h = np.abs(model.voltage_per_force(grid, circuit))
    k = int(np.argmax(h))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    res = minimize_scalar(
        lambda f: -abs(model.voltage_per_force(f, circuit)[0]),
        bounds=(lo, hi),
        method="bounded",
        options={"xatol": 1e-6 * hi},
    )
    return float(res.x)


def band_edge_Hz(
    model: ReducedModel,
    circuit: MeasuringCircuit,
    ratio: float,
    reference_V_per_N: float,
    f_lo_Hz: float,
    f_peak_Hz: float,
) -> float:
    """Frequency in (f_lo, f_peak) where |V/F| first reaches ``ratio`` times the reference (root-found)."""
    def g(f):
        return abs(model.voltage_per_force(f, circuit)[0]) / reference_V_per_N - ratio

    if g(f_lo_Hz) >= 0 or g(f_peak_Hz) <= 0:
        raise ValueError(
            f"the response does not cross {ratio:.4g} x reference between {f_lo_Hz} and {f_peak_Hz} Hz"
        )
    # Bracket on a log grid first: the response is monotonic there, but this guards the root.
    grid = np.geomspace(f_lo_Hz, f_peak_Hz, 400)
    vals = np.array([g(f) for f in grid])
    k = int(np.flatnonzero(vals >= 0)[0])
    return float(brentq(g, grid[k - 1], grid[k], xtol=1e-9 * grid[k], rtol=1e-12))
