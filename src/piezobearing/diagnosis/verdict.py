"""The verdict: is the residual explained by the noise, and if not, where is the structure left?

A diagnosis is ``explained`` when the final residual passes every test of
:mod:`piezobearing.diagnosis.residual_tests` and every finding of the
subject's representations is empty; else ``unexplained``, with one finding
per failed test naming where the structure is: frequencies (narrowband or
broadband, dB above the floor), lags of the autocorrelation and of the
correlation with the input, and time windows (with the segment they fall in).
"""

from __future__ import annotations

import numpy as np

from ..fitting.least_squares import nrmse
from .fit import ModelFit
from .record import Segments
from .residual_tests import ResidualTests


def peak_where(pk: dict) -> str:
    """Where a spectral peak of the residual lies: its frequency, or its band and peak [Hz]."""
    f = pk["frequency_Hz"]
    if pk["kind"] == "narrowband":
        return f"{f:.2f} Hz"
    return f"{pk['band_Hz'][0]:.2f}-{pk['band_Hz'][1]:.2f} Hz (peak {f:.2f} Hz)"


def findings(tests: ResidualTests, input_name: str = "input", segments: Segments | None = None) -> list[dict]:
    """What structure remains and where, one dict per failed test (empty when all pass).

    ``input_name`` names the measured input (``force``) and ``segments`` the stretches time windows
    fall in (``impulse``, anchored at the ``force peak``).
    """
    out = []
    if not tests.spectrum_ok:
        for pk in tests.peaks[:5]:
            f = pk["frequency_Hz"]
            where = peak_where(pk)
            out.append(
                {
                    "test": "spectrum",
                    "kind": pk["kind"],
                    "frequency_Hz": f,
                    "band_Hz": pk["band_Hz"],
                    "excess_dB": pk["excess_dB"],
                    "where": f"residual {pk['kind']} {pk['excess_dB']:.1f} dB above the noise floor at {where}",
                }
            )
    if not tests.white:
        lag = tests.acf_lags[0] if tests.acf_lags else None
        msg = f"residual not white (Ljung-Box p = {tests.ljung_box_p:.2g})"
        if lag:
            msg += f"; strongest autocorrelation {lag['value']:+.3f} at lag {lag['peak_lag_s'] * 1e3:.1f} ms"
        out.append(
            {
                "test": "whiteness",
                "p": tests.ljung_box_p,
                "lag_s": lag["peak_lag_s"] if lag else None,
                "where": msg,
            }
        )
    if not tests.uncorrelated:
        i = int(np.argmax(np.abs(tests.xcf)))
        lag_s = float(tests.xcf_lags_s[i])
        out.append(
            {
                "test": "input_correlation",
                "p": tests.xcf_p,
                "lag_s": lag_s,
                "value": float(tests.xcf[i]),
                "where": f"residual correlated with the {input_name}: {tests.xcf[i]:+.3f} at lag "
                f"{lag_s * 1e3:+.1f} ms (residual after {input_name} for positive lags)",
            }
        )
    if not tests.windows_ok:
        for w in tests.windows:  # every time-local event, largest first (a sixth spike is a finding too)
            ts, te = w["time_s"]
            msg = f"residual energy {w['max_ratio']:.1f}x the floor at t = {ts:.2f}-{te:.2f} s"
            name, anchor = (segments.name, segments.anchor) if segments is not None else ("segment", "start")
            if name in w:
                a, b = w[f"from_{anchor}_s"]
                msg += f" ({name} {w[name]}, {a:+.2f} to {b:+.2f} s from its {anchor.replace('_', ' ')})"
            out.append(
                {
                    "test": "time_window",
                    "time_s": w["time_s"],
                    name: w.get(name),
                    "max_ratio": w["max_ratio"],
                    "where": msg,
                }
            )
    return out


def segment_stats(fit_: ModelFit, voltage_V: np.ndarray, start: int, stop: int) -> dict:
    """NRMSE, rms residual [V] and whitened mean square (1 for noise alone) of a fit within [start, stop)."""
    sl = slice(start, stop)
    r = fit_.residual_V[sl]
    return {
        "nrmse": nrmse(r, voltage_V[sl]),
        "residual_rms_V": float(np.sqrt(np.mean(r**2))),
        "excess_ratio": float(np.mean(fit_.whitened[sl] ** 2)),
    }


def verdict(found: list[dict]) -> str:
    """``explained`` when no test found structure, else ``unexplained``."""
    return "explained" if not found else "unexplained"
