"""Summary figures of the parameter studies."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from . import sensor_comparison


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


#: The paper's stack (Sec. III-A, Fig. 2c) as the sensor_design table names it.
PAPER_DESIGN = {"material": "apc850_paper", "pzt_diameter_m": 4.7e-3, "pzt_thickness_m": 3.4e-3,
                "top_disk_diameter_m": 3.0e-3, "adhesive_thickness_m": 0.0, "cable_length_m": 2.0}


def pareto_front(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both x and y (larger is better), by increasing x."""
    order = np.argsort(-np.asarray(x), kind="stable")
    front, best = [], -np.inf
    for i in order:
        if y[i] > best:
            front.append(i)
            best = y[i]
    return np.array(front[::-1], dtype=int)


def _is_paper(df: pd.DataFrame) -> np.ndarray:
    ok = np.ones(len(df), bool)
    for k, v in PAPER_DESIGN.items():
        ok &= (df[k] == v).to_numpy() if isinstance(v, str) else np.isclose(df[k].to_numpy(float), v)
    return ok


def _design_label(r) -> str:
    """Ceramic and PZT size, and what else differs from the paper's stack (bond layer, cable, DAQ resistance)."""
    out = f"{r['material']} {1e3 * r['pzt_diameter_m']:g}x{1e3 * r['pzt_thickness_m']:g}"
    if r["adhesive_thickness_m"] > 0:
        out += f", {1e6 * r['adhesive_thickness_m']:g} um bond"
    if not np.isclose(r["cable_length_m"], PAPER_DESIGN["cable_length_m"]):
        out += f", {r['cable_length_m']:g} m cable"
    if not np.isclose(r["resistance_ohm"], 50e6):
        out += f", R {r['resistance_ohm'] / 1e6:g} MOhm"
    return out


def sensor_design(df: pd.DataFrame):
    """Mid-band sensitivity against the +3 dB band edge, colour the detection margin with an ideal ADC (comparable
    over every design); the designs whose record clips the configured ADC range crossed out, the paper's stack
    marked, the trade-off front drawn. Right: where the DAQ resistance puts the low-frequency corner."""
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.6), gridspec_kw={"width_ratios": [1.7, 1.0]})
    ax = axes[0]
    bw, sens = df["band_high_Hz"].to_numpy(float) / 1e3, df["sensitivity_V_per_N"].to_numpy(float)
    margin = df["detection_margin_ideal_adc_dB"].to_numpy(float)
    clipped = df["clipped"].astype(bool).to_numpy()
    sc = ax.scatter(bw, sens, c=margin, cmap="viridis", s=36, edgecolors="k", linewidths=0.4, zorder=3)
    fig.colorbar(sc, ax=ax, label="detection margin, ideal ADC [dB]")
    range_V = float(df["range_V"].iloc[0])
    ax.scatter(bw[clipped], sens[clipped], marker="x", s=40, c="r", linewidths=0.8, zorder=4,
               label=f"record clips the +-{range_V:g} V ADC range")
    front = pareto_front(bw, sens)
    ax.plot(bw[front], sens[front], "k--", lw=1, zorder=2, label="trade-off front")
    paper = _is_paper(df) & np.isclose(df["resistance_ohm"].to_numpy(float), 50e6)
    ax.scatter(bw[paper], sens[paper], s=160, facecolors="none", edgecolors="r", linewidths=1.5, zorder=4,
               label="the paper's stack")
    # labels on the front and the paper's stack only (every design is a row of summary.csv), alternately above
    # and below their point, so that neighbours along the front do not overlap
    labelled = sorted(set(front.tolist()) | set(np.flatnonzero(paper).tolist()), key=lambda i: bw[i])
    for k, i in enumerate(labelled):
        ax.annotate(_design_label(df.iloc[i]), (bw[i], sens[i]), fontsize=6, xytext=(4, 5 if k % 2 == 0 else -10),
                    textcoords="offset points")
    ax.set_xlabel("+3 dB band edge [kHz]; labelled: the trade-off front and the paper's stack")
    ax.set_ylabel("mid-band sensitivity [V/N]")
    ax.set_yscale("log")
    ax.legend(fontsize=7, loc="upper right")
    ax = axes[1]
    rr = df["resistance_ohm"].to_numpy(float)
    ax.loglog(rr / 1e6, df["corner_Hz"], "o", label="RC corner f_c")
    ax.loglog(rr / 1e6, df["linear_from_Hz"], "s", mfc="none", label="within 5% of mid-band from")
    f0 = float(df["bpfo_Hz"].iloc[0])
    ax.axhline(f0, color="0.5", lw=0.8, ls=":")
    ax.text(rr.min() / 1e6, f0 * 1.08, "BPFO", fontsize=7, color="0.4")
    ax.set_xlabel("DAQ input resistance [MOhm]")
    ax.set_ylabel("frequency [Hz]")
    ax.legend(fontsize=7)
    fig.suptitle(f"{len(df)} sensor designs ({int(clipped.sum())} clip the ADC range); colour: detection margin = "
                 "20 log10(largest noise density still detected / "
                 f"{df['noise_density_V_per_sqrtHz'].iloc[0]:.3g} V/sqrt(Hz)) with an ADC that neither clips nor "
                 "quantises", fontsize=7.5)
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


SUMMARY_FIGURES = {
    "calibration_circuit": calibration_circuit,
    "fault_detection": fault_detection,
    "daq_noise": daq_noise,
    "defect_position": defect_position,
    "fault_type_speed": fault_type_speed,
    "sensor_design": sensor_design,
    "sensor_comparison": sensor_comparison.summary_figure,
}
