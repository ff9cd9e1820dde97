"""The figure of a fault detection on a record: the squared envelope spectrum with every fault band marked,
and the fast kurtogram with the band used."""

from __future__ import annotations

from datetime import datetime

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Rectangle

from . import save, use_style

#: One colour per family.
FAMILY_COLOURS = {"outer_race": "tab:blue", "inner_race": "tab:red", "rolling_element": "tab:green"}


def detection_figure(detection: dict, title: str = ""):
    """Squared envelope spectrum (power over the local median, dB) with the families' line windows shaded,
    and the kurtogram (spectral kurtosis over level and frequency) with the band used.

    Parameters
    ----------
    detection : dict
        A :class:`piezobearing.signals.detectors.Detection` of the envelope detector, as ``to_dict()``.
    title : str
        The figure's title (the record).
    """
    use_style()
    details = detection["details"]
    kurtogram = details.get("kurtogram")
    fig, axes = plt.subplots(2 if kurtogram else 1, 1, figsize=(9, 7 if kurtogram else 4), squeeze=False)
    ax = axes[0, 0]
    f = np.asarray(details["spectrum"]["frequency_Hz"])
    level = 10 * np.log10(np.maximum(np.asarray(details["spectrum"]["ratio"]), 1e-3))
    ax.plot(f, level, color="0.2", lw=0.6)
    top = max(level.max(), 15.0)
    for family, lines in details["lines"].items():
        colour = FAMILY_COLOURS.get(family, "0.5")
        for i, line in enumerate(lines):
            ax.axvspan(line["low_Hz"], line["high_Hz"], color=colour, alpha=0.25, lw=0,
                       label=family.replace("_", " ") if i == 0 else None)
    shaft = details["shaft"]["shaft_Hz"]
    for k in range(1, int(f[-1] / shaft) + 1):
        ax.axvline(k * shaft, color="0.6", lw=0.5, ls=":", label="shaft harmonics" if k == 1 else None)
    threshold = max((ln["threshold_dB"] for fam in detection["families"].values() for ln in fam["lines"]),
                    default=None)
    if threshold is not None:
        ax.axhline(threshold, color="k", lw=0.6, ls="--", label="line threshold")
    ax.set_xlim(0, f[-1])
    ax.set_ylim(-5, top + 3)
    # order-tracked: the spectrum is in orders (cycles per shaft revolution), the band still in Hz
    unit = "order" if details.get("order_tracking") else "Hz"
    ax.set_xlabel("order [cycles per revolution]" if unit == "order" else "frequency [Hz]")
    ax.set_ylabel("squared envelope over local median [dB]")
    band = detection["band_Hz"]
    call = detection["fault_type"].replace("_", " ")
    ax.set_title(f"{title}  call: {call}  band {band[0]:.0f}-{band[1]:.0f} Hz  shaft {shaft:.3f} {unit}".strip())
    ax.legend(loc="upper right", fontsize=7, ncol=2)
    if kurtogram:
        kax = axes[1, 0]
        levels = np.asarray(kurtogram["level"])
        sk = np.asarray(kurtogram["kurtosis"])
        order = sorted(set(levels.round(6)))
        norm = plt.Normalize(min(0.0, sk.min()), max(sk.max(), 1e-6))
        cmap = plt.get_cmap("viridis")
        for lo, hi, lv, value in zip(kurtogram["low_Hz"], kurtogram["high_Hz"], levels, sk, strict=True):
            row = order.index(round(lv, 6))
            kax.add_patch(Rectangle((lo, row - 0.5), hi - lo, 1.0, color=cmap(norm(value)), lw=0))
        kax.add_patch(Rectangle((band[0], -0.5), band[1] - band[0], len(order), fill=False, ec="r", lw=1.2))
        kax.set_xlim(0, max(kurtogram["high_Hz"]))
        kax.set_ylim(len(order) - 0.5, -0.5)
        kax.set_yticks(range(len(order)), [f"{v:.1f}" for v in order])
        kax.set_xlabel("frequency [Hz]")
        kax.set_ylabel("level (log2 Nyquist/bandwidth)")
        kax.set_title("fast kurtogram (spectral kurtosis); red: the band used")
        fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=kax, label="spectral kurtosis [-]")
    fig.tight_layout()
    return fig


def save_detection(fig, path) -> None:
    """Save a :func:`detection_figure` as PNG. Its layout (``tight_layout``, the legend inside the axes) already
    fits the canvas, so the style's tight crop (``savefig.bbox: tight``), which draws the whole figure once more
    to find the crop, is left out: the save takes about 0.3 s instead of 0.5 s, a tenth of ``piezobearing
    detect`` on one record (``python benchmarks/bench_detect_record.py``)."""
    with plt.rc_context({"savefig.bbox": "standard"}):
        save(fig, path)


def trend_figure(table, x_label: str):
    """Each family's margin over the records in their order (a trend, as a monitoring engineer reads it), the
    call of each record marked above.

    Parameters
    ----------
    table : DataFrame
        The batch table (``piezobearing.stages.recording.BATCH_COLUMNS``): ``x`` (the record's time or order),
        ``{family}_margin_dB`` and ``call`` per record; rows without a call (unreadable) are left out.
    x_label : str
        What ``x`` is (its unit).
    """
    use_style()
    ok = table[table["status"] == "ok"]
    fig, ax = plt.subplots(figsize=(9, 5))
    x = ok["x"].to_numpy()
    for family, colour in FAMILY_COLOURS.items():
        ax.plot(x, ok[f"{family}_margin_dB"].to_numpy(dtype=float), "o-", color=colour, ms=3, lw=0.8,
                label=family.replace("_", " "))
    ax.axhline(0.0, color="k", lw=0.6, ls="--", label="threshold")
    markers = {"unknown": ("X", "0.3"), **{f: ("v", c) for f, c in FAMILY_COLOURS.items()}}
    top = np.nanmax(ok[[f"{f}_margin_dB" for f in FAMILY_COLOURS]].to_numpy(dtype=float), initial=0.0)
    for call, (marker, colour) in markers.items():
        sel = ok["call"] == call
        if sel.any():
            ax.plot(x[sel.to_numpy()], np.full(int(sel.sum()), top + 2.0), marker, color=colour, ms=6, ls="none",
                    label=f"called {call.replace('_', ' ')}")
    ax.set_xlabel(x_label)
    ax.set_ylabel("margin over the threshold [dB]")
    ax.set_title(f"{len(ok)} records; margins of every family, calls marked above")
    ax.set_ylim(top=top + 4.0)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), fontsize=7, ncol=4, frameon=False)
    if len(x) and isinstance(x[0], datetime):
        fig.autofmt_xdate()
    return fig
