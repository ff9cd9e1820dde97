"""The calibration diagnosis report (``DIR/report.md``), composed of the engine's sections.

:func:`render` takes the JSON-ready dict of the diagnosis (plus ``source``
and ``config``) and the relative paths of the figures, and returns the text.
What is the calibration's own: the baseline's name (the RC model of Eq. 6),
the measurement and its floor (impulses, quiet stretches between presses,
the force channel), the per-impulse table, and the method's wording.
"""

from __future__ import annotations

from ..report import sections as s
from .figures import FIGURES


def measurement(d: dict) -> list[str]:
    """The record and its noise floor, measured in the quiet stretches between impulses."""
    fl, base = d["noise_floor"], d["baseline"]
    return [
        "## The measurement and its noise floor",
        "",
        f"{d['n_samples']} samples at {d['sample_rate_Hz']:.6g} Hz ({d['duration_s']:.3g} s), "
        f"{d['n_impulses']} impulses, voltage rms {d['voltage_rms_V'] * 1e3:.1f} mV.",
        "",
        f"Noise floor measured in {fl['n_stretches']} quiet stretches between impulses ({fl['quiet_s']:.2f} s; "
        f"{fl['method']}): voltage channel {fl['voltage_noise_V'] * 1e3:.3g} mV rms, force channel "
        f"{fl['force_noise_N'] * 1e3:.3g} mN rms. A correct model leaves the voltage channel's noise plus the "
        "force channel's noise carried through the model, S(f) = s_v^2 + s_f^2 |G(f)|^2; for the baseline "
        f"that is {base['noise_floor_rms_V'] * 1e3:.2f} mV rms, NRMSE {s.pct(base['noise_floor_nrmse'])}.",
        "",
        *s.filled_gaps(d),
    ]


def where_it_fails(d: dict, figures: s.Figures) -> list[str]:
    """The baseline's tests and findings, its residual figures, and the error of each impulse."""
    out = s.where_it_fails(d, "force", "impulse")
    out += figures.lines(
        "residuals",
        "Residual against time (impulses shaded, windows above the floor in red) and the error of each impulse.",
    )
    out += figures.lines("spectrum", "Residual spectrum against the noise floor and the detection threshold.")
    out += figures.lines(
        "correlations",
        "Autocorrelation of the whitened residual and its cross-correlation with the force, "
        "with the 99% band of white noise (dotted: the family-wise threshold).",
    )
    imp = d.get("per_impulse", {})
    if imp.get("baseline"):
        out.append(
            "| impulse | t (s) | peak force (N) | NRMSE baseline | NRMSE final | residual / floor (final) |"
        )
        out.append("|---|---|---|---|---|---|")
        for b, f in zip(imp["baseline"], imp["final"], strict=True):
            out.append(
                f"| {b['impulse']} | {b['time_force_peak_s']:.2f} | {b['force_peak_N']:.2f} | {s.pct(b['nrmse'])} | "
                f"{s.pct(f['nrmse'])} | {f['excess_ratio']:.2f} |"
            )
        out.append("")
    return out


METHOD_FIT = (
    "- Fit: maximum likelihood with both channels noisy (errors in variables). The model is fitted on the "
    "force with its noise removed above twice its band, weighting each frequency by the floor of that "
    "input, so that a delay or a lead cannot fit the carried force noise; the residual, NRMSE and tests "
    "above use the recorded force as it is. NRMSE = rms(residual) / rms(measured voltage)."
)
METHOD_TESTS = (
    "- Tests on the residual whitened by the floor: Ljung-Box; largest cross-correlation with the force "
    "(Bonferroni over lags); averaged periodogram against the chi-square quantile (Bonferroni over "
    "frequencies); energy in windows (Bonferroni over windows)."
)
ADVICE = (
    "Look for a mechanism at these frequencies, times and lags (a resonance of the fixture, a "
    "non-linear contact, an interference source); add it as an effect module to test it."
)


def render(d: dict, figures: dict[str, str] | None = None) -> str:
    """The report as Markdown; ``figures`` maps :data:`FIGURES` names to paths relative to the report."""
    fig = s.Figures(figures or {})
    return s.join(
        [
            s.headline(
                d,
                f"Model versus measurement: `{d.get('source', 'measurement')}`",
                "The RC baseline (Eq. 6, R fitted)",
            ),
            s.verdict_paragraph(d, "force"),
            measurement(d),
            s.compare(
                d,
                fig,
                "Measured voltage with the baseline and the final model; below, the impulse where the "
                "baseline misses most.",
            ),
            where_it_fails(d, fig),
            s.ranking(d, fig),
            s.ladder(d, fig),
            s.final_model(d, "force", ADVICE),
            s.identifiability(d),
            s.method(d, METHOD_FIT, METHOD_TESTS),
            s.config_used(d),
        ]
    )


__all__ = ["FIGURES", "render"]
