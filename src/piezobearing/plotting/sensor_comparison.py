"""Figures of the sensor comparison: both sensors' envelope spectra, and where each sensor wins in the study."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

#: Panel titles by sensor and condition.
SENSOR_NAMES = {"pzt": "embedded PZT", "accelerometer": "housing accelerometer"}
CONDITION_NAMES = {"without_disturbance": "frame at rest", "with_disturbance": "frame vibrating"}
#: The carrier of each fault family in the kinematics record.
CARRIERS = {"outer_race": ("bpfo_Hz", 1.0), "inner_race": ("bpfi_Hz", 1.0), "rolling_element": ("bsf_Hz", 2.0)}


def _fault_bands(ax, carrier_Hz: float, slip_max: float, n_harmonics: int, top_Hz: float) -> None:
    """Shade k x carrier over cage slip [0, slip_max] (the detector's search windows), k = 1..n."""
    for k in range(1, n_harmonics + 1):
        hi = k * carrier_Hz
        if hi > top_Hz:
            break
        ax.axvspan(hi * (1 - slip_max), hi, color="tab:red", alpha=0.25, lw=0)


def envelope_spectra(spectra: pd.DataFrame, summary: dict):
    """Both sensors' envelope spectra (the faulty bearing, first seed), with the frame at rest and vibrating.

    Rows: the conditions; columns: the sensors. Amplitude over the spectrum's median (log scale) up to
    8 carriers; the true family's search windows (k x carrier over cage slip 0 to slip_max) shaded. Each
    title gives the detection rate over seeds and the median margins (the true family's, and over the healthy
    bearing's largest) from ``summary`` (sensor_comparison.json).
    """
    fault = summary["with_disturbance"]["fault_type"]
    key, mult = CARRIERS.get(fault, ("bpfo_Hz", 1.0))
    carrier = mult * summary["kinematics"][key]
    det = summary["config"]["signals"]["detector"]
    top = 8.5 * carrier
    conditions = [c for c in CONDITION_NAMES if c in summary]
    fig, axes = plt.subplots(len(conditions), 2, figsize=(10.0, 3.0 * len(conditions)), sharex=True, squeeze=False)
    for i, cond in enumerate(conditions):
        for j, sensor in enumerate(SENSOR_NAMES):
            ax = axes[i, j]
            d = spectra[(spectra["condition"] == cond) & (spectra["sensor"] == sensor)]
            d = d[d["frequency_Hz"] <= top]
            ax.semilogy(d["frequency_Hz"], d["amplitude_over_median"], lw=0.7, color="k")
            _fault_bands(ax, carrier, det["slip_max"], det["n_harmonics"], top)
            r = summary[cond]["sensors"][sensor]
            band = r["detection"]["band_Hz"]
            ax.set_title(
                f"{SENSOR_NAMES[sensor]}, {CONDITION_NAMES[cond]} "
                f"({summary[cond]['disturbance_rms_m_per_s2']:.2g} m/s$^2$ rms)\n"
                f"band {band[0] / 1e3:.1f}-{band[1] / 1e3:.1f} kHz; margin {r['margin_dB']:.1f} dB, "
                f"{r['margin_over_healthy_dB']:+.1f} dB over healthy; detected {r['detection_rate_over_healthy']:.0%}",
                fontsize=8,
            )
            ax.set_xlim(0, top)
            if j == 0:
                ax.set_ylabel("envelope / median [-]")
            if i == len(conditions) - 1:
                ax.set_xlabel("frequency [Hz]")
    fig.suptitle(f"{fault.replace('_', ' ')} defect, {summary['shaft_speed_rpm']:g} rpm: "
                 f"shaded: k x {key.split('_')[0].upper()} over cage slip 0-{det['slip_max']:.0%}", fontsize=9)
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
