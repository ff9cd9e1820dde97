"""Figures of the sensor finite-element model: Fig. 7 (first axial mode) and Fig. 8b (harmonic response)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib import cm, colors
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from . import plt

#: Vertex indices of the six faces of a VTK hexahedron, outward.
_HEX_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])

LABEL_COLORS = {"axial": "C0", "bending/rocking": "C1", "torsion": "C2", "radial": "C3"}


def boundary_faces(cells: np.ndarray) -> np.ndarray:
    """Quadrilateral faces (k, 4) that belong to one hexahedron only."""
    faces = cells[:, _HEX_FACES].reshape(-1, 4)
    keys = np.sort(faces, axis=1)
    _, inv, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return faces[counts[inv.ravel()] == 1]


def _cutaway_polygons(coors, cells, disp, scale):
    """Three mirrored copies of the quarter (one quadrant cut away), deformed by ``scale * disp``.

    Returns polygons (k, 4, 3) [mm] and the |u| of each face.
    """
    faces = boundary_faces(cells)
    tol = 1e-9 * np.ptp(coors)
    on_x = np.all(np.abs(coors[faces, 0]) < tol, axis=1)
    on_y = np.all(np.abs(coors[faces, 1]) < tol, axis=1)
    mag = np.linalg.norm(disp, axis=1)
    polys, vals = [], []
    # (sx, sy, show faces on plane x=0, show faces on plane y=0): the quadrant x>0, y>0 is cut away.
    for sx, sy, show_x, show_y in ((-1, 1, True, False), (1, -1, False, True), (-1, -1, False, False)):
        keep = ~((on_x & (not show_x)) | (on_y & (not show_y)))
        s = np.array([sx, sy, 1.0])
        x = (coors + scale * disp) * s
        polys.append(x[faces[keep]] * 1e3)
        vals.append(mag[faces[keep]].mean(axis=1))
    return np.concatenate(polys), np.concatenate(vals)


def mode_shape_figure(mode: dict, modal: dict, scale_fraction: float = 0.12) -> Figure:
    """Fig. 7: the first axial mode (3D cut-away, deformed, coloured by |u|) and the mode chart.

    Parameters
    ----------
    mode : dict
        Arrays of the mode file: ``coors_m`` (n, 3), ``cells`` (k, 8), ``displacement`` (n, 3)
        (max |u| = 1) and ``frequency_Hz``.
    modal : dict
        The modal results (results/sensor/modal.json).
    scale_fraction : float
        Largest drawn displacement as a fraction of the stack height.
    """
    coors, cells, disp = mode["coors_m"], mode["cells"], mode["displacement"]
    height = np.ptp(coors[:, 2])
    polys, vals = _cutaway_polygons(coors, cells, disp, scale_fraction * height)
    fig = plt.figure(figsize=(10.0, 4.6))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    norm = colors.Normalize(0.0, 1.0)
    cmap = plt.get_cmap("viridis")
    pc = Poly3DCollection(polys, facecolors=cmap(norm(vals)), edgecolors="k", linewidths=0.1)
    ax.add_collection3d(pc)
    lim = np.abs(polys[..., :2]).max()
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_zlim(polys[..., 2].min(), polys[..., 2].max())
    ax.set_box_aspect((1, 1, np.ptp(polys[..., 2]) / (2 * lim)))
    ax.view_init(elev=22, azim=40)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    ax.set_title(
        f"first axial mode, {mode['frequency_Hz'] / 1e3:.1f} kHz (short circuit)\n"
        f"top face clamped; max |u| drawn as {scale_fraction * height / 1e-3:.2f} mm",
    )
    fig.colorbar(cm.ScalarMappable(norm, cmap), ax=ax, shrink=0.6, pad=0.1, label="|u| / max |u|")

    ax2 = fig.add_subplot(1, 2, 2)
    for m in modal["modes"]:
        label = m["label"]
        col = LABEL_COLORS.get(label.split(" ")[0], "C4")
        fs, fo = m["frequency_short_Hz"] / 1e3, m["frequency_open_Hz"] / 1e3
        ax2.vlines(fs, 0, 1, color=col, lw=2)
        if abs(fo - fs) > 1e-6 * fs:
            ax2.vlines(fo, 0, 1, color=col, lw=2, ls="--")
        mult = " (x2)" if m["multiplicity"] > 1 else ""
        ax2.text(
            fs, 1.03, f"{label}{mult}\n{fs:.1f}", rotation=90, ha="center", va="bottom", fontsize=8, color=col
        )
    ax2.axvline(modal["paper_first_resonance_Hz"] / 1e3, color="k", lw=1, ls=":")
    ax2.text(
        modal["paper_first_resonance_Hz"] / 1e3, 0.5, " paper 121 kHz", fontsize=8, rotation=90, va="center"
    )
    ax2.set_xlim(0, modal["modal_max_frequency_Hz"] / 1e3)
    ax2.set_ylim(0, 2.0)
    ax2.set_yticks([])
    ax2.set_xlabel("frequency [kHz]")
    ax2.set_title(
        "modes below {:.0f} kHz: solid short circuit, dashed open".format(
            modal["modal_max_frequency_Hz"] / 1e3
        )
    )
    fig.tight_layout()
    return fig


def harmonic_figure(df: pd.DataFrame, band: dict) -> Figure:
    """Fig. 8b: |V/F| of the stack with the circuit up to the sweep end, the band edges and the RC model."""
    f = df["frequency_Hz"].to_numpy()
    h = df["voltage_per_force_V_per_N"].to_numpy()
    ref = band["reference_sensitivity_V_per_N"]
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7.0, 6.2), sharex=True, height_ratios=[3, 2])
    ax.loglog(f, h, label="FEM with R and cable")
    ax.loglog(f, df["rc_model_V_per_N"], ls="--", label="RC model (calibration, paper's d33 and Cp)")
    ax.loglog(f, df["open_circuit_V_per_N"], ls=":", lw=1, label="FEM open circuit (no cable, R infinite)")
    ax.axhline(ref, color="0.4", lw=0.8)
    ax.set_ylabel("|V / F| [V/N]")
    ax.set_ylim(max(h.min(), 1e-2), min(h.max() * 1.5, 100 * ref))
    ax.legend(loc="upper left")
    ax.set_title(
        f"harmonic response, 1 N on the bottom, top clamped, R = {band['resistance_ohm'] / 1e6:.1f} MOhm "
        f"+ {band['cable_capacitance_F'] * 1e12:.0f} pF\nloaded resonance {band['loaded_resonance_Hz'] / 1e3:.1f} kHz"
    )
    dev = 100 * (h / ref - 1)
    ax2.semilogx(f, dev)
    r_db = 100 * (10 ** (band["band_ratio_dB"] / 20) - 1)
    for level, edge, lab, ls in (
        (r_db, band["band_high_Hz"], f"+{band['band_ratio_dB']:g} dB", "-"),
        (
            band["band_ratio_percent"],
            band["band_high_27_percent_Hz"],
            f"+{band['band_ratio_percent']:g}%",
            "--",
        ),
    ):
        ax2.axhline(level, color="0.5", lw=0.8, ls=ls)
        for a in (ax, ax2):
            a.axvline(edge, color="C2", lw=1, ls=ls)
        ax2.text(edge, level, f" {lab}: {edge / 1e3:.1f} kHz", fontsize=8, va="bottom")
    for a in (ax, ax2):
        a.axvline(band["band_low_Hz"], color="C2", lw=1)
        a.axvline(band["paper"]["band_high_Hz"], color="k", lw=0.8, ls=":")
    ax2.text(band["band_low_Hz"], -40, f" band low {band['band_low_Hz']:g} Hz", fontsize=8)
    ax2.text(band["paper"]["band_high_Hz"], -40, " paper 45 kHz", fontsize=8, ha="right", rotation=90)
    ax2.set_ylim(-60, 100)
    ax2.set_ylabel(f"deviation from |V/F| at {band['reference_frequency_Hz']:g} Hz [%]")
    ax2.set_xlabel("frequency [Hz]")
    fig.tight_layout()
    return fig
