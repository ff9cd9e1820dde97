"""Structured hexahedral mesh of the sensor stack (paper Fig. 2c).

The stack is three coaxial disks along z (bottom to top): the narrow alumina
disk that touches the bearing's outer ring, the PZT disk, and the wide alumina
disk that bears against the housing. Only the quarter x >= 0, y >= 0 is
meshed; the planes x = 0 and y = 0 are mirror planes of the geometry, and
:mod:`piezobearing.sensor.fem` recovers every mode of the full stack from the
four combinations of symmetric and antisymmetric conditions on them.

The cross-section is an O-grid: a square core, a transition ring out to the
first radius, then one annulus per further radius, all sharing the same
angular division, so that the three disks are conforming at their
interfaces. Each circle is a polygon whose vertices sit at the radius that
gives the polygon the area of the circle (``r sqrt(delta / sin delta)`` for a
segment angle delta), so the axial stiffness and the capacitance see the true
areas. Spacing is graded towards the re-entrant corners where stresses
concentrate: the rim of the narrow disk on the PZT and the PZT rim under the
wide disk, both in r and in z.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Cell groups (material ids) of the mesh.
GROUP_BOTTOM_DISK, GROUP_PZT, GROUP_TOP_DISK, GROUP_ADHESIVE = 1, 2, 3, 4


@dataclass(frozen=True)
class StackGeometry:
    """The sensor stack, bottom (load side) to top (clamped side).

    Parameters
    ----------
    bottom_disk_diameter_m, bottom_disk_height_m : float
        Alumina disk in contact with the outer ring [m].
    pzt_diameter_m, pzt_height_m : float
        PZT disk [m].
    top_disk_diameter_m, top_disk_height_m : float
        Alumina disk against the housing (clamped face) [m].
    adhesive_height_m : float
        Bond layer between the PZT and each alumina disk [m]; it covers the
        narrower of the two faces it joins. 0: no layer (the disks touch the PZT).
    """

    bottom_disk_diameter_m: float = 3.0e-3
    bottom_disk_height_m: float = 1.0e-3
    pzt_diameter_m: float = 4.7e-3
    pzt_height_m: float = 3.4e-3
    top_disk_diameter_m: float = 5.0e-3
    top_disk_height_m: float = 1.0e-3
    adhesive_height_m: float = 0.0

    @property
    def z_interfaces_m(self) -> np.ndarray:
        """z of the bottom face, the two PZT faces and the top face [m]."""
        a = self.adhesive_height_m
        if a == 0.0:
            return np.cumsum([0.0, self.bottom_disk_height_m, self.pzt_height_m, self.top_disk_height_m])
        z = np.cumsum([0.0, self.bottom_disk_height_m, a, self.pzt_height_m, a, self.top_disk_height_m])
        return z[[0, 2, 3, 5]]

    @property
    def layers(self) -> list[tuple[int, float, float, float]]:
        """(group, radius [m], z_low [m], z_high [m]) of each layer, bottom to top."""
        r_b, r_p, r_t = self.radii_m
        a = self.adhesive_height_m
        spec = [(GROUP_BOTTOM_DISK, r_b, self.bottom_disk_height_m)]
        if a > 0.0:
            spec.append((GROUP_ADHESIVE, min(r_b, r_p), a))
        spec.append((GROUP_PZT, r_p, self.pzt_height_m))
        if a > 0.0:
            spec.append((GROUP_ADHESIVE, min(r_t, r_p), a))
        spec.append((GROUP_TOP_DISK, r_t, self.top_disk_height_m))
        z = np.cumsum([0.0] + [h for _, _, h in spec])
        return [(g, r, float(z[k]), float(z[k + 1])) for k, (g, r, _) in enumerate(spec)]

    @property
    def radii_m(self) -> tuple[float, float, float]:
        return (self.bottom_disk_diameter_m / 2, self.pzt_diameter_m / 2, self.top_disk_diameter_m / 2)


@dataclass(frozen=True)
class MeshDensity:
    """Element divisions at refinement multiplier 1 (scaled by the level).

    ``n_core`` divisions per side of the square core; ``n_rings`` radial
    divisions of the rings (core to r_bottom, r_bottom to r_pzt, r_pzt to
    r_top) when the radii are in that order; ``n_layers`` axial divisions of
    the bottom disk, PZT and top disk (an adhesive layer gets one); ``grading``
    the ratio of the largest to the smallest element in a graded run.
    """

    n_core: int = 2
    n_rings: tuple[int, int, int] = (2, 2, 1)
    n_layers: tuple[int, int, int] = (2, 4, 2)
    grading: float = 3.0


@dataclass(frozen=True)
class StackMesh:
    """Hexahedral quarter mesh: vertices [m], 8-node cells, cell groups."""

    coors: np.ndarray
    cells: np.ndarray
    groups: np.ndarray
    geometry: StackGeometry
    level: float

    @property
    def n_cells(self) -> int:
        return len(self.cells)


def graded(n: int, ratio: float, ends: str) -> np.ndarray:
    """n+1 points in [0, 1], finer towards ``ends`` ("lo", "hi", "both", "none").

    Geometric spacing whose largest/smallest element ratio is ``ratio``.
    """
    if n < 1:
        raise ValueError(f"need at least one division, got {n}")
    if ends == "none" or n == 1 or ratio == 1.0:
        return np.linspace(0.0, 1.0, n + 1)
    i = np.arange(n)
    if ends == "both":
        steps = np.minimum(i, n - 1 - i)
    elif ends == "lo":
        steps = i
    elif ends == "hi":
        steps = n - 1 - i
    else:
        raise ValueError(f"ends must be lo, hi, both or none, got {ends!r}")
    q = ratio ** (1.0 / max(steps.max(), 1))
    h = q**steps
    return np.concatenate([[0.0], np.cumsum(h)]) / h.sum()


def _area_radius(r: float, delta: float) -> float:
    """Vertex radius of a regular polygon (segment angle delta) with the area of a circle of radius r."""
    return r * np.sqrt(delta / np.sin(delta))


def cross_section(radii: list[float], n_core: int, n_rings: list[int], grading: float, corner_radii):
    """2D O-grid of the quarter disk.

    Returns points (N, 2), quads (M, 4) counter-clockwise and each quad's
    centroid radius (the exact circle radius it lies inside, for selecting
    the cells of each disk).
    """
    n = n_core
    n_ang = 2 * n
    delta = (np.pi / 2) / n_ang
    r_first = radii[0]
    a = 0.5 * r_first
    theta = np.linspace(0.0, np.pi / 2, n_ang + 1)
    # Square boundary from (a, 0) to (a, a) to (0, a), n_ang segments.
    sq = np.concatenate(
        [
            np.column_stack([np.full(n + 1, a), np.linspace(0, a, n + 1)]),
            np.column_stack([np.linspace(a, 0, n + 1)[1:], np.full(n, a)]),
        ]
    )
    idx = {}
    pts = []

    def add(key, p):
        if key not in idx:
            idx[key] = len(pts)
            pts.append(p)
        return idx[key]

    # Core nodes (i, j): key ("c", i, j).
    g = np.linspace(0, a, n + 1)
    for i in range(n + 1):
        for j in range(n + 1):
            add(("c", i, j), (g[i], g[j]))
    # Map square boundary index k to its core key.
    core_key = [("c", n, k) for k in range(n + 1)] + [("c", n - k, n) for k in range(1, n + 1)]
    quads = []
    qrad = []
    for i in range(n):
        for j in range(n):
            quads.append(
                [idx[("c", i, j)], idx[("c", i + 1, j)], idx[("c", i + 1, j + 1)], idx[("c", i, j + 1)]]
            )
            qrad.append(0.0)
    # Rings: radial stations along each ray k.
    circle = np.column_stack([np.cos(theta), np.sin(theta)])
    stations = []  # list of (kind, param) per radial station after the square
    prev = None
    for m, (r, nr) in enumerate(zip(radii, n_rings, strict=True)):
        rv = _area_radius(r, delta)
        lo_corner = m > 0 and any(np.isclose(radii[m - 1], c) for c in corner_radii)
        hi_corner = any(np.isclose(r, c) for c in corner_radii)
        ends = (
            "both" if (lo_corner and hi_corner) else ("hi" if hi_corner else ("lo" if lo_corner else "none"))
        )
        t = graded(nr, grading, ends)
        for tt in t[1:]:
            if m == 0:
                stations.append(("core", rv, tt))
            else:
                stations.append(("ring", prev + tt * (rv - prev), tt))
        prev = rv
    ring_keys = [core_key]
    for s, (kind, val, tt) in enumerate(stations):
        keys = []
        for k in range(n_ang + 1):
            if kind == "core":
                p = sq[k] + tt * (val * circle[k] - sq[k])
            else:
                p = val * circle[k]
            key = ("r", s, k)
            add(key, tuple(p))
            keys.append(key)
        ring_keys.append(keys)
    # Exact radius reached at each station (for cell selection: the cell's outer station).
    outer_exact = []
    for m, nr in enumerate(n_rings):
        outer_exact += [radii[m]] * nr
    for s in range(len(stations)):
        inner, outer = ring_keys[s], ring_keys[s + 1]
        for k in range(n_ang):
            quads.append([idx[inner[k]], idx[outer[k]], idx[outer[k + 1]], idx[inner[k + 1]]])
            qrad.append(outer_exact[s])
    return np.array(pts, dtype=float), np.array(quads, dtype=int), np.array(qrad)


def divisions(base: int, multiplier: float) -> int:
    """Division count ``base`` scaled by the refinement ``multiplier`` (at least one)."""
    return max(1, int(np.floor(base * multiplier + 0.5)))


def stack_mesh(
    geometry: StackGeometry, density: MeshDensity = MeshDensity(), level: float = 1.0
) -> StackMesh:
    """Quarter hexahedral mesh of the stack at refinement multiplier ``level``.

    Every division count of ``density`` is multiplied by ``level`` and rounded.
    """
    if level <= 0:
        raise ValueError(f"mesh refinement multiplier must be > 0, got {level}")
    r_b, r_p, r_t = geometry.radii_m
    radii = sorted({r_b, r_p, r_t})
    if len(radii) != 3:
        raise ValueError("the three disk diameters must differ")
    n_rings = [divisions(k, level) for k in density.n_rings]
    # Re-entrant corners: the rim of the narrower disk at each of the two PZT interfaces.
    corners = sorted({min(r_b, r_p), min(r_t, r_p)})
    pts2, quads2, qrad = cross_section(
        radii, divisions(density.n_core, level), n_rings, density.grading, corners
    )
    n_layers = {GROUP_BOTTOM_DISK: density.n_layers[0], GROUP_PZT: density.n_layers[1]}
    n_layers[GROUP_TOP_DISK] = density.n_layers[2]
    # Refine towards the PZT faces (the corners sit there); a bond layer is one element thick.
    ends = {GROUP_BOTTOM_DISK: "hi", GROUP_PZT: "both", GROUP_TOP_DISK: "lo", GROUP_ADHESIVE: "none"}
    layers = geometry.layers
    zlist = [np.array([layers[0][2]])]
    layer_of_cell_row = []
    for k, (gid, _, z0, z1) in enumerate(layers):
        nl = 1 if gid == GROUP_ADHESIVE else divisions(n_layers[gid], level)
        t = graded(nl, density.grading, ends[gid])
        zlist.append(z0 + t[1:] * (z1 - z0))
        layer_of_cell_row += [k] * nl
    z = np.concatenate(zlist)
    n2 = len(pts2)
    coors = np.column_stack([np.tile(pts2, (len(z), 1)), np.repeat(z, n2)])
    cells, groups = [], []
    for row, k in enumerate(layer_of_cell_row):
        gid, radius = layers[k][0], layers[k][1]
        keep = qrad <= radius * (1 + 1e-9)
        q = quads2[keep]
        lo, hi = row * n2, (row + 1) * n2
        cells.append(np.hstack([q + lo, q + hi]))
        groups.append(np.full(len(q), gid))
    cells = np.vstack(cells)
    groups = np.concatenate(groups)
    used, inv = np.unique(cells, return_inverse=True)
    return StackMesh(coors[used], inv.reshape(cells.shape), groups, geometry, level)


def cylinder_mesh(radius_m: float, height_m: float, n_core: int, n_ring: int, n_layers: int) -> StackMesh:
    """Quarter mesh of a single cylinder (group 2), for the verification cases."""
    pts2, quads2, _ = cross_section([radius_m], n_core, [n_ring], 1.0, [])
    z = np.linspace(0.0, height_m, n_layers + 1)
    n2 = len(pts2)
    coors = np.column_stack([np.tile(pts2, (len(z), 1)), np.repeat(z, n2)])
    cells = np.vstack([np.hstack([quads2 + k * n2, quads2 + (k + 1) * n2]) for k in range(n_layers)])
    geo = StackGeometry(pzt_diameter_m=2 * radius_m, pzt_height_m=height_m)
    return StackMesh(coors, cells, np.full(len(cells), GROUP_PZT), geo, 1)


def hex_volumes(mesh: StackMesh) -> np.ndarray:
    """Volume of each hexahedron [m^3] (2x2x2 Gauss rule on the trilinear map)."""
    g = np.array([-1, 1]) / np.sqrt(3)
    ref = np.array(
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
        dtype=float,
    )
    x = mesh.coors[mesh.cells]  # (nc, 8, 3)
    vol = np.zeros(len(x))
    for a in g:
        for b in g:
            for c in g:
                dn = np.empty((8, 3))
                xi = np.array([a, b, c])
                for k in range(3):
                    o = [0, 1, 2]
                    o.remove(k)
                    dn[:, k] = ref[:, k] / 8 * (1 + ref[:, o[0]] * xi[o[0]]) * (1 + ref[:, o[1]] * xi[o[1]])
                jac = np.einsum("cni,nj->cij", x, dn)
                vol += np.linalg.det(jac)
    return vol
