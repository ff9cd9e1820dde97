"""Figures of the model-versus-measurement diagnosis.

Each function takes the arrays of ``diagnosis.npz`` (``a``, a dict of
arrays) and the content of ``diagnosis.json`` (``d``) and returns a Figure.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

BASE, FINAL, FLOOR, MEAS = "#D55E00", "#0072B2", "#000000", "#999999"


def _label(d: dict, key: str) -> str:
    eff = d[key]["effects"]
    return "baseline" if not eff else "baseline + " + " + ".join(eff)


def sample_time(a: dict, index) -> np.ndarray:
    """Time [s] of full-record sample ``index`` (the series in ``a`` may be thinned for display)."""
    return float(a["t0_s"]) + np.asarray(index) * float(a["dt_s"])


def _shade_impulses(ax, a: dict) -> None:
    for k, (s, e) in enumerate(zip(a["impulse_start"], a["impulse_stop"], strict=True)):
        if k % 2 == 0:
            ax.axvspan(sample_time(a, s), sample_time(a, e - 1), color="0.92", zorder=0, lw=0)
    for p in a["impulse_peak"]:
        ax.axvline(sample_time(a, p), color="0.75", lw=0.6, zorder=0)


def overlay(a: dict, d: dict) -> Figure:
    """Measured voltage, baseline and final model; a zoom on the impulse where the baseline misses most
    (``zoom_*``: full rate; the whole record may be thinned for display)."""
    fig = Figure(figsize=(7.0, 5.4))
    ax, az = fig.subplots(2, 1, gridspec_kw={"height_ratios": [1.3, 1]})
    t = a["time_s"]
    for axis, z in ((ax, ""), (az, "zoom_")):  # the models wide and pale, the measurement thin on top of them
        axis.plot(a[f"{z}time_s"], a[f"{z}baseline_model_V"], color=BASE, lw=2.4, alpha=0.45,
                  label=_label(d, "baseline"))
        if d["final"]["effects"]:
            axis.plot(a[f"{z}time_s"], a[f"{z}final_model_V"], color=FINAL, lw=1.4, ls="--",
                      label=_label(d, "final"))
        axis.plot(a[f"{z}time_s"], a[f"{z}voltage_V"], color="k", lw=0.6, label="measured", zorder=3)
        axis.set_ylabel("voltage (V)")
    _shade_impulses(ax, a)
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="upper right", ncol=3, fontsize=8)
    ax.set_title(
        f"NRMSE baseline {100 * d['baseline']['nrmse']:.2f}%, final {100 * d['final']['nrmse']:.2f}%, "
        f"noise floor {100 * d['final']['noise_floor_nrmse']:.2f}%"
    )
    zt = a["zoom_time_s"]
    az.set_xlim(zt[0], zt[-1])
    k = np.flatnonzero(a["impulse_start"] == int(a["zoom_start"]))
    if k.size:
        az.set_title(f"impulse {k[0] + 1} (largest baseline error)")
    fax = az.twinx()
    fax.plot(zt, a["zoom_force_N"], color="0.6", lw=0.7)
    fax.set_ylabel("force (N)", color="0.5")
    fax.grid(False)
    az.set_xlabel("time (s)")
    fig.tight_layout()
    return fig


def residuals(a: dict, d: dict) -> Figure:
    """Residual against time (baseline, final) with impulses and flagged windows; per-impulse NRMSE."""
    fig = Figure(figsize=(7.0, 6.4))
    axs = fig.subplots(3, 1, gridspec_kw={"height_ratios": [1, 1, 0.9]})
    t = a["time_s"]
    for ax, key, col in ((axs[0], "baseline", BASE), (axs[1], "final", FINAL)):
        _shade_impulses(ax, a)
        ax.plot(t, a[f"{key}_residual_V"] * 1e3, color=col, lw=0.5)
        rms = d[key]["noise_floor_rms_V"] * 1e3
        ax.axhline(2 * rms, color=FLOOR, lw=0.8, ls=":")
        ax.axhline(-2 * rms, color=FLOOR, lw=0.8, ls=":", label="±2 x floor rms")
        for w in d[key]["tests"]["time_windows"]["flagged"]:
            ax.axvspan(w["time_s"][0], w["time_s"][1], color="red", alpha=0.25, lw=0)
        ax.set_xlim(t[0], t[-1])
        ax.set_ylabel("residual (mV)")
        ax.set_title(
            f"{_label(d, key)}: NRMSE {100 * d[key]['nrmse']:.2f}% "
            f"(floor {100 * d[key]['noise_floor_nrmse']:.2f}%)"
        )
    axs[0].legend(loc="upper right", fontsize=8)
    axs[1].set_xlabel("time (s)")
    pi = d.get("per_impulse", {})
    ax = axs[2]
    if pi.get("baseline"):
        k = np.array([p["impulse"] for p in pi["baseline"]])
        ax.bar(k - 0.2, [100 * p["nrmse"] for p in pi["baseline"]], 0.4, color=BASE, label="baseline")
        ax.bar(k + 0.2, [100 * p["nrmse"] for p in pi["final"]], 0.4, color=FINAL, label="final")
        ax.set_xticks(k)
        ax.legend(fontsize=8)
    ax.set_xlabel("impulse")
    ax.set_ylabel("NRMSE in window (%)")
    fig.tight_layout()
    return fig


def spectrum(a: dict, d: dict) -> Figure:
    """Residual PSD of baseline and final against their noise floors and the detection threshold."""
    fig = Figure(figsize=(7.0, 4.4))
    ax = fig.subplots()
    keys = (
        (("baseline", BASE), ("final", FINAL))
        if d["final"]["effects"] != d["baseline"]["effects"]
        else (("baseline", BASE),)
    )
    for key, col in keys:
        f = a[f"{key}_psd_freq_Hz"][1:]
        ax.loglog(f, a[f"{key}_psd_V2_per_Hz"][1:], color=col, lw=0.9, label=f"residual, {_label(d, key)}")
    f = a["final_psd_freq_Hz"][1:]
    ax.loglog(f, a["final_floor_psd_V2_per_Hz"][1:], color=FLOOR, lw=1.2, label="noise floor (final model)")
    ax.loglog(
        a["baseline_psd_freq_Hz"][1:],
        a["baseline_floor_psd_V2_per_Hz"][1:],
        color=FLOOR,
        lw=0.8,
        ls=":",
        label="noise floor (baseline)",
    )
    ax.loglog(
        f,
        a["final_threshold_psd_V2_per_Hz"][1:],
        color="red",
        lw=0.8,
        ls="--",
        label="detection threshold (final)",
    )
    for pk in d["final"]["tests"]["spectrum"]["peaks"][:4]:
        ax.annotate(
            f"{pk['frequency_Hz']:.1f} Hz",
            (pk["frequency_Hz"], a["final_psd_V2_per_Hz"][1:].max()),
            xytext=(0, -12),
            textcoords="offset points",
            ha="center",
            fontsize=8,
            color="red",
        )
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD (V$^2$/Hz)")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return fig


def correlations(a: dict, d: dict) -> Figure:
    """Whitened-residual autocorrelation and cross-correlation with the force (baseline left, final right).

    Grey: the 99% band of white noise (per lag); dotted: the family-wise threshold of the verdict.
    """
    fig = Figure(figsize=(7.6, 5.2))
    axs = fig.subplots(2, 2)
    b99 = float(a["band99"])
    for j, (key, col) in enumerate((("baseline", BASE), ("final", FINAL))):
        for i, (kind, xlabel) in enumerate(
            (("acf", "lag (ms)"), ("xcf", "lag of the residual after the force (ms)"))
        ):
            ax = axs[i, j]
            thr = float(a[f"{key}_{kind}_threshold"])
            y = a[f"{key}_{kind}"]
            ax.axhspan(-b99, b99, color="0.85", lw=0, label="99% band of white noise")
            ax.axhline(thr, color=FLOOR, ls=":", lw=0.8)
            ax.axhline(-thr, color=FLOOR, ls=":", lw=0.8, label="family-wise threshold")
            ax.plot(a[f"{key}_{kind}_lags_s"] * 1e3, y, color=col, lw=1.0)
            lim = max(np.max(np.abs(y)), 3 * thr)
            ax.set_ylim(-1.1 * lim, 1.1 * lim)
            ax.set_xlabel(xlabel, fontsize=8)
            if j == 0:
                ax.set_ylabel("autocorrelation" if kind == "acf" else "cross-correlation with force")
        axs[0, j].set_title(_label(d, key), fontsize=9)
    axs[0, 1].legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return fig


def ranking(d: dict) -> Figure:
    """Delta BIC of each catalogue effect added to the configured model (symmetric log scale)."""
    fig = Figure(figsize=(7.0, 3.6))
    ax = fig.subplots()
    r = d["ranking"][::-1]
    y = np.arange(len(r))
    winner = d["winner"]["effect"] if d.get("winner") else None
    cols = [
        FINAL
        if x["effect"] == winner
        else ("0.55" if x["delta_bic"] > d["settings"]["min_delta_bic"] else "0.8")
        for x in r
    ]
    ax.barh(y, [x["delta_bic"] for x in r], color=cols)
    ax.set_yticks(y, [x["effect"] for x in r])
    ax.set_xscale("symlog", linthresh=10)
    ax.axvline(
        d["settings"]["min_delta_bic"], color="red", ls="--", lw=0.8, label="very strong evidence (10)"
    )
    ax.set_xlabel("delta BIC = BIC without - BIC with the effect (> 0 favours it; larger: stronger)")
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    return fig


#: How many of the ranking's best candidates not kept the ladder shows beside the steps.
CANDIDATES = 3


def ladder(d: dict) -> Figure:
    """NRMSE after each step, with each model's noise floor; beside them, hatched, the NRMSE the best
    :data:`CANDIDATES` of the first ranking that were not kept would have left."""
    fig = Figure(figsize=(8.0, 3.8))
    ax = fig.subplots()
    labels = ["baseline"]
    err = [d["baseline"]["nrmse"]]
    flo = [d["baseline"]["noise_floor_nrmse"]]
    for i, s in enumerate(d["steps"]):
        if i == 0 and not s["effects"]:
            continue
        labels.append("configured\n" + "\n".join(s["effects"]) if i == 0 else "+\n" + s["added"])
        err.append(s["nrmse"])
        flo.append(s["noise_floor_nrmse"])
    for s in d.get("dropped_steps", []):
        labels.append("(+\n" + s["added"] + ")\ndropped")
        err.append(s["nrmse"])
        flo.append(s["noise_floor_nrmse"])
    n_kept = len(labels) - len(d.get("dropped_steps", []))
    n_shown = len(labels)
    # the best candidates of the ranking that were not kept: what adding them would have done
    used = {*d.get("selected", []), *(s["added"] for s in d.get("dropped_steps", []))}
    for r in [r for r in d.get("ranking", []) if r["effect"] not in used][:CANDIDATES]:
        labels.append("(+\n" + r["effect"] + ")\nnot kept")
        err.append(r["nrmse"])
        flo.append(r["noise_floor_nrmse"])
    x = np.arange(len(labels))
    colours = [FINAL] * n_kept + ["0.8"] * (n_shown - n_kept) + ["white"] * (len(labels) - n_shown)
    bars = ax.bar(x, np.array(err) * 100, color=colours, edgecolor=["none"] * n_shown + ["0.5"] * (len(labels) - n_shown),
                  width=0.6)
    for b in bars[n_shown:]:
        b.set_hatch("//")
    ax.hlines(np.array(flo) * 100, x - 0.4, x + 0.4, color=FLOOR, lw=1.5, label="noise floor of the model")
    for xi, e in zip(x, err, strict=True):
        ax.annotate(
            f"{100 * e:.2f}%",
            (xi, 100 * e),
            xytext=(0, 2),
            textcoords="offset points",
            ha="center",
            fontsize=8,
        )
    ax.set_xticks(x, labels, fontsize=7)  # one effect name a line: long names do not run into each other
    ax.set_ylabel("NRMSE (%)")
    ax.set_ylim(0, 1.12 * 100 * max(err))
    ax.legend(fontsize=8, loc="upper right")
    extra = "; hatched: the best candidates of the ranking, not kept" if len(labels) > n_shown else ""
    ax.set_title(f"verdict: {d['verdict']}{extra}", fontsize=9)
    fig.tight_layout()
    return fig


def all_figures(a: dict, d: dict) -> dict[str, Figure]:
    """Every figure of the report by name (see :data:`piezobearing.diagnosis.calibration.report.FIGURES`)."""
    return {
        "overlay": overlay(a, d),
        "residuals": residuals(a, d),
        "spectrum": spectrum(a, d),
        "correlations": correlations(a, d),
        "ranking": ranking(d),
        "ladder": ladder(d),
    }
