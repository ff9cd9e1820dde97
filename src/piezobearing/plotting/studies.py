"""Summary figures of the parameter studies."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pandas as pd


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


SUMMARY_FIGURES = {"calibration_circuit": calibration_circuit}
