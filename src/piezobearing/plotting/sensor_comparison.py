"""Figures of the sensor comparison: both sensors' envelope spectra, and where each sensor wins in the study."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
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


def summary_figure(df: pd.DataFrame):
    """The study sensor_comparison: each sensor's margin over the healthy bearing against the disturbance.

    One panel per fault case (type and width); x: the base motion's RMS; y: the median margin of the true
    family over the healthy rig's largest [dB] (above 0: detected); markers by sensor, line per shaft speed
    and mounting place. Where the PZT's curve lies above the accelerometer's, the embedded sensor wins.
    """
    d = df.copy()
    d["fault"] = d["fault_type"] + " " + (1e3 * d["defect_width_m"]).map("{:.1f} mm".format)
    faults = sorted(d["fault"].unique())
    fig, axes = plt.subplots(1, len(faults), figsize=(4.0 * len(faults), 3.6), sharey=True, squeeze=False)
    styles = {"pzt": ("o", "-"), "accelerometer": ("s", "--")}
    for ax, fault in zip(axes[0], faults, strict=True):
        g = d[d["fault"] == fault]
        for (sensor, rpm, pos), h in g.groupby(["sensor", "shaft_speed_rpm", "accelerometer_position"]):
            h = h.sort_values("disturbance_rms_m_per_s2")
            marker, line = styles.get(sensor, ("x", ":"))
            label = f"{SENSOR_NAMES.get(sensor, sensor)}, {rpm:g} rpm" + (f", {pos}" if sensor == "accelerometer" else "")
            x = np.maximum(h["disturbance_rms_m_per_s2"], 1e-3)
            ax.plot(x, h["margin_over_healthy_dB"], marker=marker, ls=line, label=label)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel("base motion [m/s$^2$ rms] (at rest: 1e-3)")
        ax.set_title(fault, fontsize=9)
    axes[0, 0].set_ylabel("margin over healthy [dB]")
    axes[0, -1].legend(fontsize=6)
    fig.suptitle("Embedded sensor against housing accelerometer: above 0 dB the fault is seen", fontsize=9)
    fig.tight_layout()
    return fig
