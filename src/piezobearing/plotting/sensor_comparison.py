"""Figures of the sensor comparison: both sensors' envelope spectra, and where each sensor wins in the study."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..comparison.statistics import roc

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


def _row_label(d: pd.DataFrame) -> pd.Series:
    """A case's label without its disturbance: fault and width, speed, mounting (and the roughness where the
    study varies it)."""
    fault = d["fault_type"].str.replace("_", " ") + " " + (1e3 * d["defect_width_m"]).map("{:.1f} mm".format)
    row = fault + ", " + d["shaft_speed_rpm"].map("{:g} rpm".format) + ", accelerometer " + d["accelerometer_position"]
    if "roughness_rms_m" in d and d["roughness_rms_m"].nunique() > 1:
        row = row + ", roughness " + (1e6 * d["roughness_rms_m"]).map("{:.2g} um".format)
    return row


def summary_figure(df: pd.DataFrame):
    """The study sensor_comparison as a win map: where each sensor detects the fault.

    One row per case without its disturbance (shaft speed, fault type and width, mounting place, roughness
    where varied), one column per disturbance level (the base motion's RMS beneath it). Each cell gives both
    sensors' detection probability at the calibrated threshold (``calibrated_detection_probability``: the
    healthy seeds' false-alarm rate ``calibrated_false_alarm_rate``), P for the embedded PZT, A for the
    accelerometer, and is coloured by which of them detects on at least half the faulty seeds.
    """
    d = df.copy()
    d["row"] = _row_label(d)
    wide = d.pivot_table(index=["row", "disturbance_level"], columns="sensor",
                         values="calibrated_detection_probability")
    rms = d.groupby("disturbance_level")["disturbance_rms_m_per_s2"].median()
    keys = [k for k in ("fault_type", "defect_width_m", "accelerometer_position", "shaft_speed_rpm",
                        "roughness_rms_m") if k in d]
    rows = list(dict.fromkeys(d.sort_values(keys)["row"]))
    levels = sorted(d["disturbance_level"].unique())
    far = float(d["calibrated_false_alarm_rate"].iloc[0])
    height = 1.9 + 0.45 * len(rows)
    fig, ax = plt.subplots(figsize=(3.4 + 1.2 * len(levels), height))
    ax.grid(False)
    for i, row in enumerate(rows):
        for j, level in enumerate(levels):
            if (row, level) not in wide.index:
                continue
            p, a = wide.loc[(row, level), "pzt"], wide.loc[(row, level), "accelerometer"]
            ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, color=OUTCOME_COLOURS[_outcome(p - 0.5, a - 0.5)]))
            ax.text(j, i, f"P {p:.2f}\nA {a:.2f}", ha="center", va="center", fontsize=7)
    ax.set_xlim(-0.5, len(levels) - 0.5)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_aspect("auto")
    ax.set_xticks(range(len(levels)))
    ax.set_xticklabels([f"level {v:g}\n{rms[v]:.2g} m/s$^2$" for v in levels], fontsize=7)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=7)
    ax.set_xlabel("base motion (level; RMS over y and z)", fontsize=8)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in OUTCOME_COLOURS.values()]
    fig.legend(handles, list(OUTCOME_COLOURS), fontsize=7, ncol=4, loc="lower center", frameon=False,
               title="detects on at least half the faulty seeds", title_fontsize=7)
    ax.set_title(f"Detection probability at a false-alarm rate of {far:g}\n(P embedded PZT, A accelerometer)",
                 fontsize=8)
    fig.tight_layout(rect=(0, 0.45 / height, 1, 1))
    return fig


def _condition(case: dict) -> str:
    """A case's label: speed, fault, width, base motion level and roughness."""
    s = case["summary"]
    return (f"{s['shaft_speed_rpm']:g} rpm, {s['fault_type'].replace('_', ' ')} {1e3 * s['defect_width_m']:.1f} mm, "
            f"level {s['disturbance_level']:g}, roughness {1e6 * s['roughness_rms_m']:.2g} um")


def healthy_distributions(cases: list[dict]):
    """The healthy rig's statistic per sensor: the survival function (share of healthy seeds above) of the true
    family's margin [dB] on every case's healthy seeds, one line per case (at rest and under base motion, with
    and without roughness as the study's cases hold them), the calibrated threshold marked on each."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.2), sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, case in enumerate(cases):
        colour = colours[k % len(colours)]
        rows = {r["sensor"]: r for r in case["summary"]["rows"]}
        for ax, per in zip(axes, case["summary"]["per_seed"], strict=True):
            h = np.sort(np.asarray(per["healthy_margin_dB"], dtype=float))
            share = 1.0 - np.arange(h.size) / h.size
            ls = "-" if case["summary"]["disturbance_level"] > 0 else "--"
            ax.step(h, share, where="post", color=colour, ls=ls, lw=1.2, label=_condition(case))
            ax.axvline(rows[per["sensor"]]["calibrated_threshold_dB"], color=colour, ls=":", lw=0.8)
    for ax, name in zip(axes, ("pzt", "accelerometer"), strict=True):
        ax.set_yscale("log")
        ax.set_title(f"{SENSOR_NAMES[name]}: healthy seeds", fontsize=9)
        ax.set_xlabel("true family's margin over the detector's threshold [dB]", fontsize=8)
    axes[0].set_ylabel("share of healthy seeds above", fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0, 0.06 + 0.035 * ((len(cases) + 1) // 2), 1, 1))
    return fig


def roc_curves(cases: list[dict]):
    """The ROC curve of each case, both sensors in one panel (detection probability against the false-alarm
    rate of the true family's margin, from the case's healthy and faulty seeds), the area in the legend."""
    n = len(cases)
    cols = min(n, 3)
    nrows = (n + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(3.4 * cols, 3.2 * nrows), squeeze=False)
    for ax, case in zip(axes.flat, cases, strict=False):
        rows = {r["sensor"]: r for r in case["summary"]["rows"]}
        for per in case["summary"]["per_seed"]:
            curve = roc(per["healthy_margin_dB"], per["faulty_margin_dB"])
            s = per["sensor"]
            ax.step(curve.false_alarm_rate, curve.detection_probability, where="post",
                    label=f"{SENSOR_NAMES[s]} (AUC {rows[s]['roc_auc']:.3f})")
        ax.plot([0, 1], [0, 1], color="0.7", lw=0.6)
        ax.set_xscale("symlog", linthresh=0.01)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.02)
        ax.set_title(_condition(case), fontsize=7)
        ax.set_xlabel("false-alarm rate", fontsize=7)
        ax.set_ylabel("detection probability", fontsize=7)
        ax.legend(fontsize=6, loc="lower right")
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    return fig
