"""Figures of the calibration chain: Fig. 5, 6 and 8a of the paper."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.ticker import NullFormatter


def fig05_impulses(record: pd.DataFrame, sensitivity: dict):
    """Force and voltage against time, each impulse's peaks marked (paper Fig. 5)."""
    fig, (ax_f, ax_v) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 4.8))
    t = record["time_s"]
    ax_f.plot(t, record["force_N"], color="C0", lw=0.8, label="reference force")
    ax_v.plot(t, 1e3 * record["voltage_V"], color="C1", lw=0.8, label="PZT voltage")
    for k, imp in enumerate(sensitivity["impulses"]):
        for ax in (ax_f, ax_v):
            ax.axvspan(*imp["window_s"], color="0.5", alpha=0.06 if k % 2 else 0.12, lw=0)
        ax_f.plot(imp["time_force_peak_s"], imp["force_peak_N"], "v", color="C0", ms=5)
        ax_v.plot(imp["time_voltage_peak_s"], 1e3 * imp["voltage_peak_V"], "v", color="C1", ms=5)
        ax_v.annotate(
            f"{1e3 * imp['sensitivity_V_per_N']:.0f}",
            (imp["time_voltage_peak_s"], 1e3 * imp["voltage_peak_V"]),
            textcoords="offset points",
            xytext=(0, 6),
            ha="center",
            fontsize=7,
        )
    s = sensitivity
    lo, hi = s["sensitivity_ci95_V_per_N"]
    ax_f.set_ylabel("force [N]")
    ax_v.set_ylabel("voltage [mV]")
    ax_v.set_xlabel("time [s]")
    ax_f.set_title(
        f"{s['n_impulses']} impulses; sensitivity {1e3 * s['sensitivity_V_per_N']:.1f} mV/N "
        f"(95% CI {1e3 * lo:.1f}-{1e3 * hi:.1f}); numbers: per-impulse mV/N"
    )
    return fig


def fig06_fit(fit: pd.DataFrame, resistance: dict):
    """Measured and simulated voltage with the residual below (paper Fig. 6)."""
    fig, (ax, ax_r) = plt.subplots(
        2, 1, sharex=True, figsize=(7.0, 4.8), gridspec_kw={"height_ratios": [3, 1]}
    )
    t = fit["time_s"]
    ax.plot(t, 1e3 * fit["voltage_V"], color="0.4", lw=0.8, label="measured")
    ax.plot(t, 1e3 * fit["simulated_voltage_V"], color="C1", lw=1.0, label="Eq. 6, fitted R")
    ax_r.plot(t, 1e3 * (fit["voltage_V"] - fit["simulated_voltage_V"]), color="C2", lw=0.6)
    lo, hi = resistance["resistance_ci95_ohm"]
    ax.set_title(
        f"R = {resistance['resistance_ohm'] / 1e6:.2f} MOhm (95% CI {lo / 1e6:.2f}-{hi / 1e6:.2f}), "
        f"tau = {1e3 * resistance['tau_s']:.2f} ms, NRMSE = {resistance['nrmse']:.3f}"
    )
    ax.set_ylabel("voltage [mV]")
    ax.legend(loc="upper right")
    ax_r.set_ylabel("residual [mV]")
    ax_r.set_xlabel("time [s]")
    return fig


def fig08a_lowfreq(curve: pd.DataFrame, lowfreq: dict):
    """Sensitivity and its deviation at low frequency (paper Fig. 8a)."""
    fig, (ax, ax_d) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 4.8))
    f = curve["frequency_Hz"]
    ax.plot(f, curve["sensitivity_V_per_N"], "o-", color="C0", label="S(f) of the fitted model")
    ax.axhline(lowfreq["open_circuit_sensitivity_V_per_N"], color="0.5", ls=":", label="open circuit d33/C")
    f0, s0 = lowfreq["linear_from_Hz"], lowfreq["reference_sensitivity_V_per_N"]
    ax.plot([f0], [s0], "s", color="C1", ms=8, label=f"reference: {s0:.3f} V/N at {f0:g} Hz")
    ax.set_ylabel("sensitivity [V/N]")
    ax.legend(loc="lower right")
    ax_d.plot(f, 100 * curve["deviation_next"], "o-", color="C0", label="change to next frequency")
    ax_d.plot(f, 100 * curve["deviation_asymptote"], "s--", color="C2", ms=4, label="below d33/C")
    ax_d.axhline(100 * lowfreq["deviation_threshold"], color="C3", ls="--", label="threshold")
    ax_d.axvline(f0, color="C1", lw=0.8)
    ax_d.set_yscale("log")
    ax_d.set_ylabel("deviation [%]")
    ax_d.set_xlabel("frequency [Hz]")
    ax_d.legend(loc="upper right")
    if f.max() / f.min() >= 10:  # a decade or more: log-spaced, ticks at 1-2-5 and the sweep's ends
        ax_d.set_xscale("log")
        ticks = [v for v in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000) if f.min() <= v <= f.max()]
        ticks = sorted({float(f.min()), *ticks, float(f.max())})
        ax_d.set_xticks(ticks, [f"{v:g}" for v in ticks])
        ax_d.xaxis.set_minor_formatter(NullFormatter())
    else:
        ax_d.set_xticks(np.asarray(f))
    return fig
