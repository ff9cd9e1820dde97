"""Figures of the sensor comparison: both sensors' envelope spectra, and where each sensor wins in the study."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pandas as pd

#: Panel titles by sensor and condition.
SENSOR_NAMES = {"pzt": "embedded PZT", "accelerometer": "housing accelerometer"}
CONDITION_NAMES = {"without_disturbance": "frame at rest", "with_disturbance": "frame vibrating"}


def envelope_spectra(spectra: pd.DataFrame, summary: dict):
    """Both sensors' squared envelope spectra (the faulty bearing, first seed), with the frame at rest and vibrating.

    Rows: the conditions; columns: the sensors. Each spectrum as the envelope detector tested it (its band's
    power over the local median, log scale); the true family's search windows shaded (the detector's lines).
    Each title gives the band, the true family's median margin over seeds, its margin over the healthy
    bearing's largest and the share of seeds where that is positive (``summary``: sensor_comparison.json).
    """
    fault = summary["with_disturbance"]["fault_type"]
    conditions = [c for c in CONDITION_NAMES if c in summary]
    fig, axes = plt.subplots(len(conditions), 2, figsize=(10.0, 3.0 * len(conditions)), sharex=True, squeeze=False)
    top = 0.0
    for i, cond in enumerate(conditions):
        for j, sensor in enumerate(SENSOR_NAMES):
            ax = axes[i, j]
            d = spectra[(spectra["condition"] == cond) & (spectra["sensor"] == sensor)]
            ax.semilogy(d["frequency_Hz"], d["ratio"], lw=0.7, color="k")
            r = summary[cond]["sensors"][sensor]
            for line in r["detection"]["details"]["lines"].get(fault, []):
                ax.axvspan(line["low_Hz"], line["high_Hz"], color="tab:red", alpha=0.3, lw=0)
            top = max(top, float(d["frequency_Hz"].max()))
            band = r["detection"]["band_Hz"]
            ax.set_title(
                f"{SENSOR_NAMES[sensor]}, {CONDITION_NAMES[cond]} "
                f"({summary[cond]['disturbance_rms_m_per_s2']:.2g} m/s$^2$ rms)\n"
                f"band {band[0] / 1e3:.1f}-{band[1] / 1e3:.1f} kHz; margin {r['margin_dB']:.1f} dB, "
                f"{r['margin_over_healthy_dB']:+.1f} dB over healthy; seen in {r['detection_rate_over_healthy']:.0%}",
                fontsize=8,
            )
            if j == 0:
                ax.set_ylabel("SES / local median [-]")
            if i == len(conditions) - 1:
                ax.set_xlabel("frequency [Hz]")
    for ax in axes.ravel():
        ax.set_xlim(0, top)
    fig.suptitle(f"{fault.replace('_', ' ')} defect, {summary['shaft_speed_rpm']:g} rpm; shaded: the detector's "
                 "search windows of the fault's lines", fontsize=9)
    fig.tight_layout()
    return fig


#: Colours of the win map: which sensor sees the fault (its median margin over the healthy rig above 0 dB).
OUTCOME_COLOURS = {"both": "#c7e9c0", "embedded PZT only": "#6baed6", "accelerometer only": "#fd8d3c",
                   "neither": "#d9d9d9"}


def _outcome(pzt_dB: float, accelerometer_dB: float) -> str:
    seen = (pzt_dB > 0.0, accelerometer_dB > 0.0)
    return {(True, True): "both", (True, False): "embedded PZT only", (False, True): "accelerometer only",
            (False, False): "neither"}[seen]


def summary_figure(df: pd.DataFrame):
    """The study sensor_comparison as a win map: where each sensor sees the fault.

    One row per case without its disturbance (shaft speed, fault type and width, mounting place), one column
    per disturbance level (the base motion's RMS beneath it). Each cell is coloured by which sensor's median
    margin over the healthy rig's largest is above 0 dB (both, the embedded PZT only, the accelerometer
    only, neither) and gives both margins [dB]: P for the embedded PZT, A for the accelerometer.
    """
    d = df.copy()
    d["fault"] = d["fault_type"].str.replace("_", " ") + " " + (1e3 * d["defect_width_m"]).map("{:.1f} mm".format)
    d["row"] = (d["fault"] + ", " + d["shaft_speed_rpm"].map("{:g} rpm".format) + ", accelerometer "
                + d["accelerometer_position"])
    wide = d.pivot_table(index=["row", "disturbance_level"], columns="sensor", values="margin_over_healthy_dB")
    rms = d.groupby("disturbance_level")["disturbance_rms_m_per_s2"].median()
    order = d.sort_values(["fault_type", "defect_width_m", "accelerometer_position", "shaft_speed_rpm"])["row"]
    rows = list(dict.fromkeys(order))
    levels = sorted(d["disturbance_level"].unique())
    height = 1.3 + 0.42 * len(rows)
    fig, ax = plt.subplots(figsize=(2.0 + 1.45 * len(levels), height))
    ax.grid(False)
    for i, row in enumerate(rows):
        for j, level in enumerate(levels):
            if (row, level) not in wide.index:
                continue
            p, a = wide.loc[(row, level), "pzt"], wide.loc[(row, level), "accelerometer"]
            ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, color=OUTCOME_COLOURS[_outcome(p, a)]))
            ax.text(j, i, f"P {p:+.1f}\nA {a:+.1f}", ha="center", va="center", fontsize=6.5)
    ax.set_xlim(-0.5, len(levels) - 0.5)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xticks(range(len(levels)))
    ax.set_xticklabels([f"level {v:g}\n{rms[v]:.2g} m/s$^2$" for v in levels], fontsize=7)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=7)
    ax.set_xlabel("base motion (level; RMS over y and z)", fontsize=8)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in OUTCOME_COLOURS.values()]
    fig.legend(handles, list(OUTCOME_COLOURS), fontsize=7, ncol=4, loc="lower center", frameon=False)
    ax.set_title("Who sees the fault: margin over the healthy rig [dB], P embedded PZT, A accelerometer", fontsize=8)
    fig.tight_layout(rect=(0, 0.35 / height, 1, 1))
    return fig
