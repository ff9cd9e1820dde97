"""Figures of the bearing and housing model: Fig. 3 (the mesh, front view and zoom on defect and sensor)."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from ..housing.mesh import GROUP_RING, HousingMesh

#: Face colours by cell group: ring (steel), housing (cast iron).
COLOURS = {GROUP_RING: "#8fa8d8", 2: "#d9c29a"}
#: Local node indices of the six faces of a hexahedron.
HEX_FACES = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])


def plane_faces(m: HousingMesh, axis: int, value: float = 0.0, tol: float = 1e-9):
    """Faces of the hexahedra lying in the plane coordinate[axis] = value: (quads (n, 4, 3), groups (n,))."""
    p = m.coors[m.conn]  # (ne, 8, 3)
    faces = p[:, HEX_FACES]  # (ne, 6, 4, 3)
    on = np.all(np.abs(faces[..., axis] - value) < tol, axis=2)  # (ne, 6)
    e, f = np.nonzero(on)
    return faces[e, f], m.group[e]


def _draw_section(ax, m: HousingMesh, axis: int, dims: tuple[int, int], lw: float, scale: float = 1e3):
    quads, groups = plane_faces(m, axis)
    xy = quads[..., list(dims)] * scale
    colours = [COLOURS.get(g, "0.7") for g in groups]
    ax.add_collection(PolyCollection(xy, facecolors=colours, edgecolors="k", linewidths=lw))
    ax.set_aspect("equal")
    ax.autoscale_view()


def _sensor_sketch(
    ax, m: HousingMesh, pzt_diameter_m: float, pzt_height_m: float, tip_height_m: float, horizontal: int = 1
):
    """The sensor stack below the ring at psi = 0: alumina tip, PZT disk, the held far face."""
    g = m.geometry
    ro = g.ring_outer_radius_m
    tip = g.tip_diameter_m
    z0 = -ro
    if horizontal == 1:
        x_tip, x_pzt = -tip / 2, -pzt_diameter_m / 2
    else:
        x_tip, x_pzt = 0.0, 0.0
        tip, pzt_diameter_m = tip / 2, pzt_diameter_m / 2  # half model across the width
    ax.add_patch(
        Rectangle(
            (1e3 * x_tip, 1e3 * (z0 - tip_height_m)),
            1e3 * tip,
            1e3 * tip_height_m,
            facecolor="white",
            edgecolor="C3",
            hatch="..",
            lw=1.2,
            label="alumina disk",
        )
    )
    z1 = z0 - tip_height_m - pzt_height_m
    ax.add_patch(
        Rectangle(
            (1e3 * x_pzt, 1e3 * z1),
            1e3 * pzt_diameter_m,
            1e3 * pzt_height_m,
            facecolor="#f4d35e",
            edgecolor="C3",
            lw=1.2,
            label="PZT (spring k_s)",
        )
    )
    ax.plot(
        1e3 * np.array([x_pzt, x_pzt + pzt_diameter_m]),
        [1e3 * z1] * 2,
        color="k",
        lw=3,
        label="held: U_z = 0",
    )


def fig03(
    healthy: HousingMesh,
    faulty: HousingMesh,
    pzt_diameter_m: float = 4.7e-3,
    pzt_height_m: float = 3.4e-3,
    tip_height_m: float = 1.0e-3,
) -> Figure:
    """Fig. 3: (a) front view of the half model on its mirror plane x = 0; (b) zoom on the defect and
    the sensor (faulty mesh, x = 0); (c) the section y = 0 through the sensor hole (faulty mesh)."""
    fig = Figure(figsize=(11, 7.2), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=[1.45, 1])
    ax_a = fig.add_subplot(gs[:, 0])
    ax_b = fig.add_subplot(gs[0, 1])
    ax_c = fig.add_subplot(gs[1, 1])
    g = faulty.geometry
    _draw_section(ax_a, healthy, 0, (1, 2), 0.15)
    ax_a.set_title(
        f"(a) front view, mirror plane x = 0 ({healthy.n_cells} hexahedra, {healthy.n_nodes} nodes)"
    )
    ax_a.set_xlabel("y [mm]")
    ax_a.set_ylabel("z [mm]")
    ro = 1e3 * g.ring_outer_radius_m
    ax_a.add_patch(Rectangle((-7, -ro - 8), 14, 13.2, fill=False, edgecolor="C3", lw=1.2))
    _draw_section(ax_b, faulty, 0, (1, 2), 0.3)
    _sensor_sketch(ax_b, faulty, pzt_diameter_m, pzt_height_m, tip_height_m, horizontal=1)
    ax_b.set_xlim(-7, 7)
    ax_b.set_ylim(-ro - 8, -ro + 5.2)
    ax_b.set_title(
        f"(b) defect ({1e3 * g.defect_width_m:.1f} x {1e3 * g.defect_depth_m:.1f} mm) and sensor, x = 0"
    )
    ax_b.set_xlabel("y [mm]")
    ax_b.set_ylabel("z [mm]")
    ax_b.legend(loc="lower center", ncol=3, fontsize=7, handlelength=1.2, columnspacing=0.8)
    _draw_section(ax_c, faulty, 1, (0, 2), 0.3)
    _sensor_sketch(ax_c, faulty, pzt_diameter_m, pzt_height_m, tip_height_m, horizontal=0)
    ax_c.set_xlim(0, 1e3 * g.half_axial_width_m)
    ax_c.set_ylim(-1e3 * g.centre_height_m, -ro + 6)
    ax_c.set_title("(c) section y = 0 through the sensor hole (x = 0: mirror plane)")
    ax_c.set_xlabel("x [mm]")
    ax_c.set_ylabel("z [mm]")
    ax_a.legend(
        handles=[
            Rectangle((0, 0), 1, 1, facecolor=COLOURS[1], edgecolor="k", label="outer ring (steel)"),
            Rectangle((0, 0), 1, 1, facecolor=COLOURS[2], edgecolor="k", label="housing (cast iron)"),
        ],
        loc="upper right",
        fontsize=8,
    )
    return fig
