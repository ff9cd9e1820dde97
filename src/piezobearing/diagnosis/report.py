"""The Markdown report of a diagnosis (``DIR/report.md``), rendered from ``diagnosis.json`` alone.

:func:`render` takes the JSON-ready dict of
:meth:`piezobearing.diagnosis.engine.Diagnosis.to_dict` (plus ``source`` and
``config``) and the relative paths of the figures, and returns the text.
"""

from __future__ import annotations

import json

from .engine import peak_where
from .units import format_value

#: Figures of a diagnosis, in the order the report shows them.
FIGURES = ("overlay", "residuals", "spectrum", "correlations", "ranking", "ladder")


def _pct(x: float) -> str:
    return f"{100 * x:.2f}%"


def _ci(name: str, ci) -> str:
    if not ci:
        return ""
    return f"[{format_value(name, ci[0])}, {format_value(name, ci[1])}]"


def _param_table(params: dict, ci95: dict) -> list[str]:
    rows = ["| parameter | value | 95% interval |", "|---|---|---|"]
    for k, v in params.items():
        rows.append(f"| `{k}` | {format_value(k, v)} | {_ci(k, ci95.get(k))} |")
    return rows


def _tests_line(t: dict) -> str:
    w, x, s, tw = t["whiteness"], t["input_correlation"], t["spectrum"], t["time_windows"]
    parts = [
        f"whiteness (Ljung-Box over {w['lags']} lags) p = {w['p']:.2g} ({'white' if w['white'] else 'not white'})",
        f"largest correlation with the force {x['max_abs']:.3f} at {x['lag_of_max_s'] * 1e3:+.0f} ms "
        f"(threshold {x['threshold']:.3f}; {'uncorrelated' if x['uncorrelated'] else 'correlated'})",
        f"{len(s['peaks'])} spectral region(s) above the floor",
        f"{len(tw['flagged'])} time window(s) above the floor",
    ]
    return "; ".join(parts) + "."


def _findings(items: list[dict]) -> list[str]:
    return [f"- **{f['test'].replace('_', ' ')}**: {f['where']}" for f in items] or ["- none"]


def render(d: dict, figures: dict[str, str] | None = None) -> str:
    """The report as Markdown; ``figures`` maps :data:`FIGURES` names to paths relative to the report."""
    figures = figures or {}
    fl = d["noise_floor"]
    base, conf, final = d["baseline"], d["configured"], d["final"]
    configured_on = bool(conf["effects"])
    out: list[str] = []
    add = out.append

    def fig(name: str, caption: str) -> None:
        if name in figures:
            add(f"![{caption}]({figures[name]})")
            add("")
            add(f"*{caption}*")
            add("")

    add(f"# Model versus measurement: `{d.get('source', 'measurement')}`")
    add("")
    verdict = d["verdict"]
    sel = ", ".join(f"`{s}`" for s in d["selected"]) or "nothing"
    add(
        f"**Verdict: {verdict}.** The RC baseline (Eq. 6, R fitted) leaves NRMSE {_pct(base['nrmse'])} "
        f"against a noise floor of {_pct(base['noise_floor_nrmse'])} "
        f"({base['nrmse'] / base['noise_floor_nrmse']:.2f}x). "
        + (
            f"With `model.effects` = {conf['effects']} the configured model leaves {_pct(conf['nrmse'])}. "
            if configured_on
            else ""
        )
        + f"The stepwise search added {sel}; the final model leaves {_pct(final['nrmse'])} against its floor "
        f"of {_pct(final['noise_floor_nrmse'])} ({final['nrmse'] / final['noise_floor_nrmse']:.2f}x)."
    )
    add("")
    if verdict == "explained":
        add(
            "The final residual is consistent with the measured noise: white, uncorrelated with the force, "
            "no frequency and no time window above the floor."
        )
    else:
        add("Structure remains in the final residual that no effect of the catalogue explains. Where:")
        add("")
        out.extend(_findings(d["unexplained"]))
    add("")

    # ---------------------------------------------------------------- the measurement and its floor
    add("## The measurement and its noise floor")
    add("")
    add(
        f"{d['n_samples']} samples at {d['sample_rate_Hz']:.6g} Hz ({d['duration_s']:.3g} s), "
        f"{d['n_impulses']} impulses, voltage rms {d['voltage_rms_V'] * 1e3:.1f} mV."
    )
    add("")
    add(
        f"Noise floor measured in {fl['n_stretches']} quiet stretches between impulses ({fl['quiet_s']:.2f} s; "
        f"{fl['method']}): voltage channel {fl['voltage_noise_V'] * 1e3:.3g} mV rms, force channel "
        f"{fl['force_noise_N'] * 1e3:.3g} mN rms. A correct model leaves the voltage channel's noise plus the "
        "force channel's noise carried through the model, S(f) = s_v^2 + s_f^2 |G(f)|^2; for the baseline "
        f"that is {base['noise_floor_rms_V'] * 1e3:.2f} mV rms, NRMSE {_pct(base['noise_floor_nrmse'])}."
    )
    add("")

    # ---------------------------------------------------------------- baseline
    add("## 1. Compare: the model over the measurement")
    add("")
    add(f"Baseline fit (chi2/n = {base['chi2_per_sample']:.3g}, NRMSE {_pct(base['nrmse'])}):")
    add("")
    out.extend(_param_table(base["params"], base["ci95"]))
    add("")
    if configured_on:
        add(
            f"Configured model (`model.effects` = {conf['effects']}; NRMSE {_pct(conf['nrmse'])}, "
            f"floor {_pct(conf['noise_floor_nrmse'])}):"
        )
        add("")
        out.extend(_param_table(conf["params"], conf["ci95"]))
        add("")
    fig(
        "overlay",
        "Measured voltage with the baseline and the final model; below, the impulse where the "
        "baseline misses most.",
    )

    # ---------------------------------------------------------------- where it fails
    add("## 2. Where the baseline fails")
    add("")
    add(
        "Residual tests on the residual whitened by the floor (each at "
        f"{base['tests']['test_significance']:.2g}, family-wise {4 * base['tests']['test_significance']:.2g}): "
        + _tests_line(base["tests"])
    )
    add("")
    out.extend(_findings(_baseline_findings(base["tests"])))
    add("")
    fig(
        "residuals",
        "Residual against time (impulses shaded, windows above the floor in red) and the error "
        "of each impulse.",
    )
    fig("spectrum", "Residual spectrum against the noise floor and the detection threshold.")
    fig(
        "correlations",
        "Autocorrelation of the whitened residual and its cross-correlation with the force, "
        "with the 99% band of white noise (dotted: the family-wise threshold).",
    )
    imp = d.get("per_impulse", {})
    if imp.get("baseline"):
        add("| impulse | t (s) | peak force (N) | NRMSE baseline | NRMSE final | residual / floor (final) |")
        add("|---|---|---|---|---|---|")
        for b, f in zip(imp["baseline"], imp["final"], strict=True):
            add(
                f"| {b['impulse']} | {b['time_force_peak_s']:.2f} | {b['force_peak_N']:.2f} | {_pct(b['nrmse'])} | "
                f"{_pct(f['nrmse'])} | {f['excess_ratio']:.2f} |"
            )
        add("")

    # ---------------------------------------------------------------- ranking
    add("## 3. Which effect is missing")
    add("")
    add(
        "Each effect of the catalogue was added to the "
        + ("configured" if configured_on else "baseline")
        + " model in turn and refitted. Evidence: the drop of the Bayesian information criterion "
        "(BIC = chi2 + k ln n with the measured noise; > 10 is very strong), the share of the misfit above "
        "the floor the effect explains, the NRMSE after, and whether the residual becomes white."
    )
    add("")
    add("| rank | effect | delta BIC | share explained | NRMSE after | white after | fitted |")
    add("|---|---|---|---|---|---|---|")
    for i, r in enumerate(d["ranking"]):
        white = "yes" if r["white"] else "no"
        add(
            f"| {i + 1} | `{r['effect']}` | {r['delta_bic']:.4g} | {_pct(r['excess_explained'])} | "
            f"{_pct(r['nrmse'])} | {white} | {r['summary'].replace('|', '/')} |"
        )
    add("")
    w = d.get("winner")
    if w:
        add(f"**Most likely missing: `{w['effect']}`** ({w['title']}). {w['physics']}")
        add("")
        add(f"Fitted: {w['summary']}.")
        add("")
        out.extend(_param_table(w["params"], w["ci95"]))
        add("")
    else:
        best = d["ranking"][0] if d["ranking"] else None
        st = d.get("settings", {})
        tried = [s["added"] for s in d.get("dropped_steps", [])]
        if best and best["effect"] in tried:
            add(
                f"No effect was kept. The best candidate, `{best['effect']}` (delta BIC {best['delta_bic']:.3g}), "
                f"explains only {_pct(best['excess_explained'])} of the misfit and the residual keeps structure "
                "after the search: it would stand in for a mechanism outside the catalogue (see the verdict)."
            )
            add("")
        elif best:
            add(
                f"No effect is supported by the evidence (best: `{best['effect']}`, delta BIC "
                f"{best['delta_bic']:.3g} against the {st.get('min_delta_bic')} needed, share "
                f"{_pct(best['excess_explained'])} against {st.get('min_share')})."
            )
            add("")
    fig("ranking", "Evidence for each effect of the catalogue (BIC drop when added).")

    # ---------------------------------------------------------------- ladder
    add("## 4. Adding effects: the error ladder")
    add("")
    add("| step | model | NRMSE | noise floor | delta BIC | share explained |")
    add("|---|---|---|---|---|---|")
    add(f"| 0 | baseline | {_pct(base['nrmse'])} | {_pct(base['noise_floor_nrmse'])} | | |")
    for i, s in enumerate(d["steps"]):
        if i == 0 and not configured_on:
            continue
        name = " + ".join(["baseline", *s["effects"]])
        db = "" if s["delta_bic"] is None else f"{s['delta_bic']:.4g}"
        sh = "" if s["excess_explained"] is None else _pct(s["excess_explained"])
        step = "configured" if i == 0 else str(i)
        add(f"| {step} | {name} | {_pct(s['nrmse'])} | {_pct(s['noise_floor_nrmse'])} | {db} | {sh} |")
    add("")
    for s in d.get("dropped_steps", []):
        add(f"- Tried and dropped: `{s['added']}` ({s['reason']}).")
    if d.get("dropped_steps"):
        add("")
    fig("ladder", "NRMSE after each step, with the noise floor of each model.")

    # ---------------------------------------------------------------- final
    add("## 5. The final model")
    add("")
    add(
        f"Effects: {final['effects'] or 'none (baseline)'}; NRMSE {_pct(final['nrmse'])}, floor "
        f"{_pct(final['noise_floor_nrmse'])}, chi2/n {final['chi2_per_sample']:.3g}."
    )
    add("")
    out.extend(_param_table(final["params"], final["ci95"]))
    add("")
    add("Residual tests: " + _tests_line(final["tests"]))
    add("")
    add(f"**Verdict: {verdict}.**")
    add("")
    if verdict == "unexplained":
        out.extend(_findings(d["unexplained"]))
        add("")
        add(
            "Look for a mechanism at these frequencies, times and lags (a resonance of the fixture, a "
            "non-linear contact, an interference source); add it as an effect module to test it."
        )
        add("")

    # ---------------------------------------------------------------- method and config
    add("## How this was computed")
    add("")
    add(
        "- Fit: maximum likelihood with both channels noisy (errors in variables). The model is fitted on the "
        "force with its noise removed above twice its band, weighting each frequency by the floor of that "
        "input, so that a delay or a lead cannot fit the carried force noise; the residual, NRMSE and tests "
        "above use the recorded force as it is. NRMSE = rms(residual) / rms(measured voltage)."
    )
    add(
        "- Tests on the residual whitened by the floor: Ljung-Box; largest cross-correlation with the force "
        "(Bonferroni over lags); averaged periodogram against the chi-square quantile (Bonferroni over "
        "frequencies); energy in windows (Bonferroni over windows)."
    )
    st = d.get("settings", {})
    add(
        f"- Selection: an effect is added when its BIC drop exceeds {st.get('min_delta_bic')} and it explains "
        f"at least {st.get('min_share')} of the misfit above the floor; if structure remains, additions that "
        f"explained less than {st.get('min_share_if_unexplained')} at their step are dropped."
    )
    add("")
    if "config" in d:
        add("<details><summary>Configuration used</summary>")
        add("")
        add("```json")
        add(json.dumps(d["config"], indent=2))
        add("```")
        add("")
        add("</details>")
        add("")
    return "\n".join(out)


def _baseline_findings(tests: dict) -> list[dict]:
    """The baseline's findings, rebuilt from its test summary (same wording as the verdict's)."""
    out = []
    for pk in tests["spectrum"]["peaks"][:5]:
        where = peak_where(pk)
        out.append(
            {
                "test": "spectrum",
                "where": f"residual {pk['kind']} {pk['excess_dB']:.1f} dB above the noise floor at {where}",
            }
        )
    w = tests["whiteness"]
    if not w["white"]:
        out.append({"test": "whiteness", "where": f"not white (Ljung-Box p = {w['p']:.2g})"})
    x = tests["input_correlation"]
    if not x["uncorrelated"]:
        out.append(
            {
                "test": "input_correlation",
                "where": f"correlated with the force: {x['max_abs']:.3f} at lag {x['lag_of_max_s'] * 1e3:+.1f} ms",
            }
        )
    for win in tests["time_windows"]["flagged"][:5]:
        ts, te = win["time_s"]
        msg = f"energy {win['max_ratio']:.1f}x the floor at t = {ts:.2f}-{te:.2f} s"
        if "impulse" in win:
            msg += f" (impulse {win['impulse']})"
        out.append({"test": "time_window", "where": msg})
    return out
