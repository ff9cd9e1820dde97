"""Figures of the running bearing's diagnosis (``results/diagnostics_bearing/figures/``).

Each function takes the arrays of ``diagnosis.npz`` (``a``) and the content
of ``diagnosis.json`` (``d``) and returns a Figure. Ranking and ladder are
the engine's (:mod:`piezobearing.plotting.diagnostics`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .diagnostics import ladder, ranking

BASE, FINAL, FLOOR, MEAS = "#D55E00", "#0072B2", "#000000", "#999999"


def _label(d: dict, key: str) -> str:
    eff = d[key]["effects"]
    return "baseline" if not eff else "baseline + " + " + ".join(eff)


def overlay(a: dict, d: dict) -> Figure:
    """Measured voltage, baseline and final model over 12 roller passages, the passages marked."""
    fig = Figure(figsize=(7.0, 5.0))
    ax, ar = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1.5, 1]})
    t = a["zoom_time_s"]
    s, e = int(a["zoom_start"]), int(a["zoom_stop"])
    # the models wide and pale, the measurement thin on top; the baseline's residual wide under the final's
    ax.plot(t, a["zoom_baseline_model_V"], color=BASE, lw=2.4, alpha=0.45, label=_label(d, "baseline"))
    ar.plot(t, a["zoom_baseline_residual_V"], color=BASE, lw=1.8, alpha=0.5, label="baseline residual")
    if d["final"]["effects"]:
        ax.plot(t, a["zoom_final_model_V"], color=FINAL, lw=1.4, ls="--", label=_label(d, "final"))
        ar.plot(t, a["zoom_final_residual_V"], color=FINAL, lw=0.7, label="final residual")
    ax.plot(t, a["zoom_voltage_V"], color="k", lw=0.6, label="measured", zorder=3)
    for c in a["passage_peak"]:
        if s <= c < e:
            for axis in (ax, ar):
                axis.axvline(t[c - s], color="0.8", lw=0.6, zorder=0)
    ax.set_ylabel("voltage (V)")
    ar.set_ylabel("residual (V)")
    ar.set_xlabel("time (s); grey lines: a roller over the sensor (baseline's kinematics)")
    ax.legend(loc="upper right", fontsize=8, ncol=3)
    ar.legend(loc="upper right", fontsize=8)
    ax.set_title(
        f"NRMSE baseline {100 * d['baseline']['nrmse']:.2f}%, final {100 * d['final']['nrmse']:.2f}%, "
        f"noise floor {100 * d['final']['noise_floor_nrmse']:.2f}%"
    )
    fig.tight_layout()
    return fig


def per_passage(a: dict, d: dict) -> Figure:
    """Residual energy per roller passage over the floor, baseline and final, with the flagging level."""
    fig = Figure(figsize=(7.0, 3.4))
    ax = fig.subplots()
    for key, col in (("baseline", BASE), ("final", FINAL)):
        t, r = a.get(f"per_passage_{key}_time_s"), a.get(f"per_passage_{key}_excess_ratio")
        if t is not None and t.size:
            ax.plot(t, r, "o-", ms=2.5, lw=0.7, color=col, label=_label(d, key))
    thr = a.get("per_passage_final_threshold")
    if thr is not None and thr.size:
        ax.axhline(float(np.median(thr)), color="red", ls="--", lw=0.8, label="flagging level")
    ax.axhline(1.0, color=FLOOR, lw=0.6, label="noise floor")
    ax.set_yscale("log")
    ax.set_xlabel("time of the roller passage (s)")
    ax.set_ylabel("residual energy / floor")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def synchronous_average(a: dict, d: dict) -> Figure:
    """Measured, model and residual averaged over the roller-passage period."""
    fig = Figure(figsize=(7.0, 4.8))
    ax, ar = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1.4, 1]})
    ang = a["synchronous_average_final_angle_deg"]
    o = np.argsort(ang)
    ax.plot(ang[o], a["synchronous_average_baseline_model_V"][o], color=BASE, lw=2.4, alpha=0.45,
            label=_label(d, "baseline"))
    ax.plot(ang[o], a["synchronous_average_final_model_V"][o], color=FINAL, lw=1.4, ls="--", label=_label(d, "final"))
    ax.plot(ang[o], a["synchronous_average_final_measured_V"][o], color="k", lw=0.7, label="measured", zorder=3)
    for key, col, lw, alpha in (("baseline", BASE, 1.8, 0.5), ("final", FINAL, 0.8, 1.0)):
        ar.plot(ang[o], 1e3 * a[f"synchronous_average_{key}_residual_V"][o], color=col, lw=lw, alpha=alpha,
                label=f"{key} residual")
    band = 1e3 * a["synchronous_average_final_band_V"][o]
    ar.fill_between(ang[o], -band, band, color="0.85", lw=0, label="noise band")
    ax.set_ylabel("voltage (V)")
    ar.set_ylabel("residual (mV)")
    ar.set_xlabel("cage angle from a roller over the sensor (deg)")
    ax.legend(fontsize=8)
    ar.legend(fontsize=8)
    fig.tight_layout()
    return fig


def envelope(a: dict, d: dict) -> Figure:
    """Envelope spectra of the measured voltage and the final residual, every fault band marked."""
    fig = Figure(figsize=(7.0, 4.6))
    ax, ar = fig.subplots(2, 1, sharex=True)
    f = a["envelope_final_freq_Hz"]
    ax.plot(f, 1e3 * a["envelope_final_measured_V"], color=MEAS, lw=0.8, label="measured")
    if d["final"]["effects"]:  # the baseline's residual wide and pale under the final's
        ar.plot(f, 1e3 * a["envelope_baseline_residual_V"], color=BASE, lw=1.8, alpha=0.5, label="baseline residual")
        ar.plot(f, 1e3 * a["envelope_final_residual_V"], color=FINAL, lw=0.7, label="final residual")
    else:
        ar.plot(f, 1e3 * a["envelope_baseline_residual_V"], color=BASE, lw=0.7,
                label="residual (final model = baseline)")
    colours = {"shaft": "0.4", "FTF": "#009E73", "BPFO": "#CC79A7", "BPFI": "#E69F00", "BSF": "#56B4E9", "2xBSF": "#56B4E9"}
    labelled = []  # (frequency, level) of the labels placed: a label close to the last one goes one level down
    span = float(f[-1] - f[0]) if f.size > 1 else 1.0
    for ln in sorted(d["envelope"]["final"]["lines"], key=lambda x: x["frequency_Hz"]):
        base = ln["name"].split("x", 1)[-1] if ln["name"][0].isdigit() else ln["name"]
        for axis in (ax, ar):
            axis.axvline(ln["frequency_Hz"], color=colours.get(base, "0.6"), lw=0.6, ls=":", zorder=0)
        if not ln["name"][0].isdigit():
            near = labelled and ln["frequency_Hz"] - labelled[-1][0] < 0.04 * span
            level = (labelled[-1][1] + 1) % 3 if near else 0
            labelled.append((ln["frequency_Hz"], level))
            ax.text(ln["frequency_Hz"], 1.0 - 0.17 * level, ln["name"], transform=ax.get_xaxis_transform(),
                    fontsize=6.5, va="top", ha="left", color=colours.get(base, "0.3"),
                    bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8})
    lo, hi = d["envelope"]["final"]["band_Hz"]
    ax.set_title(f"envelope of {lo:.0f}-{hi:.0f} Hz; dotted: fault bands (shaft, FTF, BPFO, BPFI, BSF, 2xBSF, harmonics)", fontsize=8)
    ax.set_ylabel("amplitude (mV)")
    ar.set_ylabel("amplitude (mV)")
    ar.set_xlabel("frequency (Hz)")
    ax.legend(fontsize=8, loc="center right")
    ar.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig


def spectrum(a: dict, d: dict) -> Figure:
    """Residual PSD of baseline and final against the measured noise floor and the test's threshold."""
    fig = Figure(figsize=(7.0, 3.6))
    ax = fig.subplots()
    for key, col in (("baseline", BASE), ("final", FINAL)):
        ax.semilogy(a[f"{key}_psd_freq_Hz"], a[f"{key}_psd_V2_per_Hz"], color=col, lw=0.7, label=f"{key} residual")
    ax.semilogy(a["final_psd_freq_Hz"], a["final_floor_psd_V2_per_Hz"], color=FLOOR, lw=0.8, label="noise floor")
    ax.semilogy(a["final_psd_freq_Hz"], a["final_threshold_psd_V2_per_Hz"], color="red", ls="--", lw=0.8, label="test threshold")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD (V$^2$/Hz)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def all_figures(a: dict, d: dict) -> dict[str, Figure]:
    return {
        "overlay": overlay(a, d),
        "per_passage": per_passage(a, d),
        "synchronous_average": synchronous_average(a, d),
        "envelope": envelope(a, d),
        "spectrum": spectrum(a, d),
        "ranking": ranking(d),
        "ladder": ladder(d),
    }
