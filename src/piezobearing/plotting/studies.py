"""Summary figures of the parameter studies."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd


def calibration_circuit(df: pd.DataFrame):
    """Impulse sensitivity, onset of linearity and reference sensitivity against R, one line per cable."""
    fig, axes = plt.subplots(1, 3, figsize=(10.0, 3.4))
    r_col, c_col = "synthesis__resistance_ohm", "sensor__cable_length_m"
    groups = df.groupby(c_col) if c_col in df else [(None, df)]
    for cable, g in groups:
        g = g.sort_values(r_col)
        label = f"cable {cable:g} m" if cable is not None else None
        r = g[r_col] / 1e6
        axes[0].plot(r, 1e3 * g["impulse_sensitivity_V_per_N"], "o-", label=label)
        axes[1].plot(r, g["linear_from_Hz"], "o-", label=label)
        axes[2].plot(r, g["reference_sensitivity_V_per_N"], "o-", label=label)
    for ax, ylabel in zip(
        axes, ["impulse sensitivity [mV/N]", "linear from [Hz]", "reference sensitivity [V/N]"], strict=True
    ):
        ax.set_xscale("log")
        ax.set_xlabel("R [MOhm]")
        ax.set_ylabel(ylabel)
    axes[0].legend()
    fig.suptitle("Calibration against DAQ resistance and cable length (synthetic presses, fitted model)")
    fig.tight_layout()
    return fig


def fault_detection(df: pd.DataFrame):
    """Fault indicator (median over noise seeds, log) and detection rates against shaft speed, a line per defect width.

    Faulty solid, healthy dashed (the healthy bearing has no defect: its lines
    differ only through the mesh's grading at the defect's place); the CFAR
    threshold dotted.
    """
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 3.8), gridspec_kw={"width_ratios": [1.6, 1.0]})
    s_col, w_col = "bearing__shaft_speed_rpm", "bearing__defects__0__width_m"
    groups = df.groupby(w_col) if w_col in df else [(None, df)]
    for i, (width, g) in enumerate(groups):
        g = g.sort_values(s_col)
        col = f"C{i}"
        label = f"defect {1e3 * width:g} mm" if width is not None else "faulty"
        axes[0].plot(g[s_col], g["indicator_faulty"], "o-", color=col, label=label)
        axes[0].plot(g[s_col], g["indicator_healthy"], "s--", color=col, mfc="none", alpha=0.8)
        axes[1].plot(g[s_col], 100 * g["detection_rate_faulty"], "o-", color=col, label=label)
        axes[1].plot(g[s_col], 100 * g["detection_rate_healthy"], "s--", color=col, mfc="none", alpha=0.8)
    thr = df.groupby(s_col)["threshold"].max().sort_index()
    axes[0].plot(thr.index, thr.to_numpy(), "k:", lw=1.5, label="threshold")
    axes[0].plot([], [], "ks--", mfc="none", label="healthy (dashed)")
    axes[0].set_yscale("log")
    axes[0].set_ylabel("fault indicator (median over seeds) [-]")
    axes[1].set_ylabel("detection rate [%]")
    axes[1].set_ylim(-5, 105)
    for ax in axes:
        ax.set_xlabel("shaft speed [rpm]")
    axes[0].legend(fontsize=7)
    r = df.iloc[0]
    fig.suptitle(
        f"Outer-race fault detection against shaft speed and defect width: SNR {r['snr_dB']:g} dB, "
        f"{int(r['n_seeds'])} noise seeds, band rule {r['band_rule']}",
        fontsize=9,
    )
    fig.tight_layout()
    return fig


def detection_map(df: pd.DataFrame, x_col: str, y_col: str, x_label: str, y_label: str, title: str,
                  log_x: bool = False, log_y: bool = False):
    """Where the sensor sees the fault: the faulty case classified as its true type (left) and the healthy
    case called faulty (right), in % of noise seeds, over two varied keys; each cell annotated."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 3.9))
    xs, ys = sorted(df[x_col].unique()), sorted(df[y_col].unique())
    for ax, col, name, cmap in ((axes[0], "correct_rate_faulty", "fault classified right [%]", "RdYlGn"),
                                (axes[1], "false_alarm_rate_healthy", "healthy called faulty [%]", "RdYlGn_r")):
        grid = np.full((len(ys), len(xs)), np.nan)
        for _, r in df.iterrows():
            grid[ys.index(r[y_col]), xs.index(r[x_col])] = 100 * r[col]
        im = ax.imshow(grid, origin="lower", cmap=cmap, vmin=0, vmax=100, aspect="auto")
        for i in range(len(ys)):
            for j in range(len(xs)):
                if np.isfinite(grid[i, j]):
                    ax.text(j, i, f"{grid[i, j]:.0f}", ha="center", va="center", fontsize=8)
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs], fontsize=7)
        ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys], fontsize=7)
        ax.set_xlabel(x_label)
        ax.set_ylabel(y_label)
        ax.set_title(name, fontsize=9)
        fig.colorbar(im, ax=ax, shrink=0.8)
    r = df.iloc[0]
    fig.suptitle(f"{title}: {int(r['n_seeds'])} noise seeds, noise {r['noise_model']}", fontsize=9)
    fig.tight_layout()
    return fig


def daq_noise(df: pd.DataFrame):
    """Sampling rate against the DAQ's input noise density."""
    return detection_map(df, "signals__sample_rate_Hz", "signals__noise__noise_density_V_per_sqrtHz",
                         "DAQ sampling rate [Hz]", "input noise density [V/sqrt(Hz)]",
                         "Outer-race fault against DAQ rate and absolute noise")


def defect_position(df: pd.DataFrame):
    """Defect angle from the sensor against cage slip."""
    return detection_map(df, "bearing__defects__0__angle_deg", "bearing__cage_slip",
                         "defect angle from the sensor [deg]", "cage slip [-]",
                         "Outer-race fault against its place and the cage slip")


def fault_type_speed(df: pd.DataFrame):
    """Fault type against shaft speed (the type as a row index: outer, inner, rolling element)."""
    order = {"outer_race": 0, "inner_race": 1, "rolling_element": 2}
    d = df.assign(type_index=df["bearing__defects__0__type"].map(order))
    fig = detection_map(d, "bearing__shaft_speed_rpm", "type_index", "shaft speed [rpm]",
                        "fault type (0 outer race, 1 inner race, 2 rolling element)",
                        "Each fault type against shaft speed")
    return fig


SUMMARY_FIGURES = {"calibration_circuit": calibration_circuit, "fault_detection": fault_detection,
                   "daq_noise": daq_noise, "defect_position": defect_position,
                   "fault_type_speed": fault_type_speed}
