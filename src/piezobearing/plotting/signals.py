"""Figures of the fault-detection chain: Fig. 9, Fig. 10 and the SNR study."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

#: Reference frequencies drawn in Fig. 10 besides BPFO: (key, label, colour, line style).
REFERENCE_LINES = (("bpfi_Hz", "BPFI", "C2", (0, (4, 2))), ("ftf_Hz", "FTF", "C3", (0, (1, 1.5))),
                   ("bsf_Hz", "BSF", "C4", (0, (6, 2, 1, 2))))


def _unit(values) -> tuple[float, str]:
    """Scale and unit for a voltage axis: V above 2 V, else mV."""
    return (1.0, "V") if float(np.nanmax(np.abs(values))) > 2.0 else (1e3, "mV")


def fig09_voltage(healthy: pd.DataFrame, faulty: pd.DataFrame, events: pd.DataFrame, kinematics: dict,
                  n_periods: float | None = 12):
    """Sensor voltage against time, healthy above faulty, the defect impulses marked (paper Fig. 9).

    Shows the first ``n_periods`` BPFO periods of the record (None: all of it),
    so the single roller passages stay visible.
    """
    fig, axes = plt.subplots(2, 1, sharex=True, sharey=True, figsize=(7.0, 4.8))
    f0 = kinematics["bpfo_Hz"]
    t0, t_end = float(healthy["time_s"].iloc[0]), float(healthy["time_s"].iloc[-1])
    t1 = t_end if n_periods is None else min(t_end, t0 + n_periods / f0)
    k, unit = _unit(np.concatenate([healthy["voltage_V"], faulty["voltage_V"]]))
    for ax, df, col in ((axes[0], healthy, "C0"), (axes[1], faulty, "C1")):
        m = (df["time_s"] >= t0) & (df["time_s"] <= t1)
        ax.plot(df["time_s"][m], k * df["voltage_V"][m], color=col, lw=0.9, marker=".", ms=2.0)
        ax.set_ylabel(f"voltage [{unit}]")
    e = events[(events["time_s"] >= t0) & (events["time_s"] <= t1)]
    axes[1].plot(e["time_s"], k * e["voltage_V"], "v", color="k", ms=5, mfc="none")
    axes[0].set_title("healthy bearing: one load bump per roller passing the sensor", loc="left")
    axes[1].set_title("faulty bearing; triangles: defect impulses (largest |faulty - healthy| per 1/BPFO)",
                      loc="left")
    axes[1].set_xlabel("time [s]")
    axes[1].set_xlim(t0, t1)
    fig.suptitle(f"sensor voltage; rollers pass the sensor at BPFO = {f0:.2f} Hz (period {1e3 / f0:.2f} ms)",
                 fontsize=9)
    return fig


def _markers(ax, kinematics: dict, fmax: float, n_bpfo: int) -> None:
    f0 = kinematics["bpfo_Hz"]
    for k in range(1, n_bpfo + 1):
        if k * f0 <= fmax:
            ax.axvline(k * f0, color="C1", lw=0.8, alpha=0.6, ls="--", label="k BPFO" if k == 1 else None)
    for key, lab, col, ls in REFERENCE_LINES:
        f = kinematics[key]
        if f <= fmax:
            ax.axvline(f, color=col, lw=0.9, ls=ls, alpha=0.8, label=f"{lab} {f:.1f} Hz")


def fig10_envelope(healthy: pd.DataFrame, faulty: pd.DataFrame, indicator: dict, kinematics: dict,
                   fmax_Hz: float = 500.0, n_bpfo: int = 7):
    """Envelope spectra of the noisy voltage, healthy above faulty, with k BPFO marked (paper Fig. 10).

    The harmonics in the indicator are circled; the noiseless record's
    envelope spectrum (same band) is drawn thin and black over the noisy one for reference.
    """
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7.0, 5.2))
    k, unit = _unit(np.concatenate([healthy["amplitude_V"], faulty["amplitude_V"]]))
    for ax, df, case, col in ((axes[0], healthy, "healthy", "C0"), (axes[1], faulty, "faulty", "C1")):
        r = indicator[case]
        m = df["frequency_Hz"] <= fmax_Hz
        ax.plot(df["frequency_Hz"][m], k * df["noiseless_amplitude_V"][m], color="k", lw=0.6,
                label="noiseless", zorder=3)  # over the noisy spectrum, which hid it
        ax.plot(df["frequency_Hz"][m], k * df["amplitude_V"][m], color=col, lw=0.9,
                label=f"SNR {r['snr_dB']:g} dB")
        for h in r["harmonics"]:
            ax.plot(h["frequency_Hz"], k * h["amplitude_V"], "o", mfc="none", color="k", ms=7)
            half = 0.5 * kinematics["bpfo_Hz"]
            ax.plot([h["frequency_Hz"] - half, h["frequency_Hz"] + half], [k * h["floor_V"]] * 2, color="k",
                    lw=0.8, alpha=0.7, label="local floor (rms)" if h["k"] == 1 else None)
        _markers(ax, kinematics, fmax_Hz, n_bpfo)
        verdict = "fault detected" if r["detected"] else "no fault detected"
        ax.set_title(
            f"{case}: band {r['band_Hz'][0]:.0f}-{r['band_Hz'][1]:.0f} Hz; indicator {r['indicator']:.1f} "
            f"vs threshold {r['threshold']:.1f} -> {verdict}", loc="left")
        ax.set_ylabel(f"envelope amplitude [{unit}]")
        ax.set_ylim(0, 1.15 * float(k * df["amplitude_V"][m].max()))
    axes[0].legend(loc="upper right", fontsize=7, ncol=2)
    axes[1].set_xlabel("frequency [Hz]")
    axes[1].set_xlim(0, fmax_Hz)
    return fig


def snr_study(summary: pd.DataFrame, study: dict):
    """Detection rate against SNR, healthy and faulty, over the noise seeds.

    Solid: the configured band rule; dashed: the other rule on the same noise
    records. Below: the indicator (median and range) of the configured rule.
    """
    fig, (ax, ax_i) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 5.4))
    rule = study["band_rule"]
    other = study.get("other_band_rule", {}).get("band_rule")
    for case, col in (("healthy", "C0"), ("faulty", "C1")):
        c = summary[(summary["case"] == case) & (summary["band_rule"] == rule)].sort_values("snr_dB")
        ax.plot(c["snr_dB"], c["detection_rate"], "o-", color=col, ms=3, label=f"{case} ({rule})")
        if other:
            o = summary[(summary["case"] == case) & (summary["band_rule"] == other)].sort_values("snr_dB")
            ax.plot(o["snr_dB"], o["detection_rate"], "--", color=col, lw=0.9, alpha=0.8, label=f"{case} ({other})")
        ax_i.plot(c["snr_dB"], c["indicator_median"], "-", color=col, label=f"{case}: median")
        ax_i.fill_between(c["snr_dB"], c["indicator_min"], c["indicator_max"], color=col, alpha=0.2, lw=0,
                          label=f"{case}: min-max")
    thr = summary["threshold"].min()
    ax_i.axhline(thr, color="k", lw=0.9, ls="--", label=f"threshold {thr:.1f}")
    ax_i.set_yscale("log")
    lim = study["faulty"]["detection_limit_dB"]
    fa = study["healthy"]["first_snr_rate_above_dB"]
    for a in (ax, ax_i):
        a.axvline(study["snr_dB"], color="0.5", lw=0.8, ls=":")
        if lim is not None and np.isfinite(lim):
            a.axvline(lim, color="C1", lw=0.8, ls="-.")
    ax.set_ylabel("detection rate")
    ax.set_ylim(-0.03, 1.03)
    fa_txt = "" if fa is None or not np.isfinite(fa) else f"; healthy false alarms > {1 - study['required_detection_rate']:g} from {fa:g} dB"
    ax.set_title(f"{study['n_seeds']} noise seeds per SNR; faulty detected (rate >= "
                 f"{study['required_detection_rate']:g}) from {lim} dB up{fa_txt}", loc="left", fontsize=8)
    ax.legend(loc="center right", fontsize=7)
    ax_i.set_ylabel(f"indicator ({rule})")
    ax_i.set_xlabel("SNR [dB]")
    ax_i.legend(loc="upper left", fontsize=7, ncol=2)
    return fig
