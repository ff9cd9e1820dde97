"""Sections of a diagnosis report: small functions of the diagnosis dict ``d`` that return lines.

Every function reads only ``d`` (the JSON of
:meth:`piezobearing.diagnosis.engine.Diagnosis.to_dict`, with ``source`` and
``config``), plus the wording its subject passes in (what the baseline is,
what the input is called), so that a report can be rebuilt from
``diagnosis.json`` alone. A subject's report is a list of these sections
joined by :func:`join`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from ...fitting.units import unit_of
from ..verdict import peak_where

#: Significant digits a value and its interval start with; more where fewer would print two ends alike.
DIGITS = 4
#: The most significant digits an interval is printed with (its ends may agree to this many: say so).
MAX_DIGITS = 12

#: What the report's columns mean (the ranking's and the ladder's), said once under each table.
DEFINITIONS = (
    "delta BIC = BIC of the model without the effect minus BIC with it (BIC = chi2 + k ln n with the measured "
    "noise): positive favours the effect (> 10 very strong), negative means its extra parameters are not worth "
    "the fit they buy. NRMSE = rms(residual) / rms(measured). Share explained = the part of the misfit above the "
    "floor (chi2 minus its expectation for a correct model) that the effect removes, as a percentage; '-' where "
    "the effect did not help (delta BIC <= 0) or the model it was added to left no misfit above the floor."
)


def pct(x: float) -> str:
    """A fraction [-] shown as a percentage."""
    return f"{100 * x:.2f}%"


def shown_in(name: str) -> str:
    """The unit a parameter's values are shown in (the report's column "shown in"), from its name's suffix."""
    u = unit_of(name)
    return (u.display or "-") if u is not None else "-"


def _scaled(name: str, value: float) -> float:
    u = unit_of(name)
    return value / u.display_scale if u is not None else value


def numbers(name: str, *values: float | None) -> list[str]:
    """``values`` of parameter ``name`` in the unit :func:`shown_in` names, with :data:`DIGITS` significant
    digits or as many more as it takes to print different values differently (an interval's ends, the value
    inside it)."""
    x = [None if v is None else _scaled(name, v) for v in values]
    distinct = len({v for v in x if v is not None})
    for digits in range(DIGITS, MAX_DIGITS + 1):
        out = ["-" if v is None else f"{v:.{digits}g}" for v in x]
        if len({t for t, v in zip(out, x, strict=True) if v is not None}) == distinct:
            return out
    return out


def ci(name: str, ci95, value: float | None = None) -> str:
    """The 95% interval ``ci95`` of ``name`` in its shown unit, with enough digits to show its width (and to
    tell its ends from ``value``)."""
    if not ci95:
        return ""
    lo, hi, *_ = numbers(name, ci95[0], ci95[1], value)
    return f"[{lo}, {hi}]"


def value_and_ci(name: str, value: float | None, ci95) -> tuple[str, str]:
    """A value and its interval printed with the same digits (:func:`numbers`)."""
    if not ci95:
        return numbers(name, value)[0], ""
    v, lo, hi = numbers(name, value, ci95[0], ci95[1])
    return v, f"[{lo}, {hi}]"


def param_table(params: dict, ci95: dict) -> list[str]:
    """Parameters with their 95% intervals, each in the unit of its "shown in" column."""
    rows = ["| parameter | shown in | value | 95% interval |", "|---|---|---|---|"]
    for k, v in params.items():
        val, iv = value_and_ci(k, v, ci95.get(k))
        rows.append(f"| `{k}` | {shown_in(k)} | {val} | {iv} |")
    return rows


def share(r: dict) -> str:
    """The share of the misfit an effect explains (a ranking entry or a step), or '-' where it means nothing:
    the effect did not help (delta BIC <= 0) or the model before it had no misfit above its floor."""
    if r.get("excess_explained") is None or r.get("delta_bic") is None or r["delta_bic"] <= 0:
        return "-"
    before, floor = r.get("nrmse_before"), r.get("noise_floor_nrmse")
    if before is not None and floor is not None and before <= floor:
        return "-"
    return pct(r["excess_explained"])


def nrmse_after(r: dict) -> str:
    """A ranking entry's NRMSE with the effect, marked where it is above the NRMSE without it (the refit did
    not reach the optimum of the model that nests the one before: read the entry as 'did not help')."""
    text = pct(r["nrmse"])
    before = r.get("nrmse_before")
    if before is not None and r["nrmse"] > before * (1 + 1e-3):
        text += f" (above {pct(before)} without it: the refit did not converge)"
    return text


def tests_line(t: dict, input_name: str = "input") -> str:
    """The four residual tests of one fit in one sentence."""
    w, x, s, tw = t["whiteness"], t["input_correlation"], t["spectrum"], t["time_windows"]
    parts = [
        f"whiteness (Ljung-Box over {w['lags']} lags) p = {w['p']:.2g} ({'white' if w['white'] else 'not white'})"
    ]
    if x["max_abs"] is not None:
        parts.append(
            f"largest correlation with the {input_name} {x['max_abs']:.3f} at {x['lag_of_max_s'] * 1e3:+.0f} ms "
            f"(threshold {x['threshold']:.3f}; {'uncorrelated' if x['uncorrelated'] else 'correlated'})"
        )
    parts += [
        f"{len(s['peaks'])} spectral region(s) above the floor",
        f"{len(tw['flagged'])} time window(s) above the floor",
    ]
    return "; ".join(parts) + "."


def findings_lines(items: list[dict]) -> list[str]:
    return [f"- **{f['test'].replace('_', ' ')}**: {f['where']}" for f in items] or ["- none"]


def summary_findings(tests: dict, input_name: str = "input", segment: str = "segment") -> list[dict]:
    """A fit's findings rebuilt from its test summary (same wording as the verdict's)."""
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
                "where": f"correlated with the {input_name}: {x['max_abs']:.3f} at lag "
                f"{x['lag_of_max_s'] * 1e3:+.1f} ms",
            }
        )
    for win in tests["time_windows"]["flagged"][:5]:
        ts, te = win["time_s"]
        msg = f"energy {win['max_ratio']:.1f}x the floor at t = {ts:.2f}-{te:.2f} s"
        if segment in win:
            msg += f" ({segment} {win[segment]})"
        out.append({"test": "time_window", "where": msg})
    return out


@dataclass
class Figures:
    """The report's figures (name -> path relative to the report) and the lines they are written into."""

    paths: dict[str, str] = field(default_factory=dict)

    def lines(self, name: str, caption: str) -> list[str]:
        """The figure with its caption, or nothing when it was not drawn."""
        if name not in self.paths:
            return []
        return [f"![{caption}]({self.paths[name]})", "", f"*{caption}*", ""]


def join(sections: list[list[str]]) -> str:
    """The report's text from its sections."""
    return "\n".join(line for s in sections for line in s)


def configured_on(d: dict) -> bool:
    return bool(d["configured"]["effects"])


def headline(d: dict, title: str, baseline: str) -> list[str]:
    """Title, the verdict with the NRMSE of baseline, configured and final model, and where it fails.

    ``baseline`` names the baseline model in a sentence (``The RC baseline (Eq. 6, R fitted)``).
    """
    base, conf, final = d["baseline"], d["configured"], d["final"]
    sel = ", ".join(f"`{s}`" for s in d["selected"]) or "nothing"
    out = [f"# {title}", ""]
    out.append(
        f"**Verdict: {d['verdict']}.** {baseline} leaves NRMSE {pct(base['nrmse'])} "
        f"against a noise floor of {pct(base['noise_floor_nrmse'])} "
        f"({base['nrmse'] / base['noise_floor_nrmse']:.2f}x). "
        + (
            f"With `model.effects` = {conf['effects']} the configured model leaves {pct(conf['nrmse'])}. "
            if configured_on(d)
            else ""
        )
        + f"The stepwise search added {sel}; the final model leaves {pct(final['nrmse'])} against its floor "
        f"of {pct(final['noise_floor_nrmse'])} ({final['nrmse'] / final['noise_floor_nrmse']:.2f}x)."
    )
    out.append("")
    return out


def verdict_paragraph(d: dict, input_name: str = "input") -> list[str]:
    """What the verdict means: consistent with the noise, or the structure left and where."""
    if d["verdict"] == "explained":
        return [
            "The final residual is consistent with the measured noise: white, uncorrelated with the "
            f"{input_name}, no frequency and no time window above the floor.",
            "",
            *outside(d),
        ]
    return [
        "Structure remains in the final residual that no effect of the catalogue explains. Where:",
        "",
        *findings_lines(d["unexplained"]),
        "",
        *outside(d),
    ]


def outside(d: dict) -> list[str]:
    """What the structure outside the catalogue looks like (trend, input dependence, stuck samples), with the
    mechanisms each suggests; stuck samples are always said, the others where the verdict is unexplained."""
    o = d.get("outside_catalogue") or {}
    keys = ("stuck",) if d.get("verdict") == "explained" else ("trend", "input_dependence", "stuck")
    items = [o[k] for k in keys if k in o and o[k].get("where")]
    if not items:
        return []
    out = ["What it looks like, and what could cause it:", ""]
    out += [f"- {i['where']}. Suggests: {i['mechanisms']}." for i in items]
    return out + [""]


def filled_gaps_line(g: dict | None) -> str:
    """One line naming the samples filled across gaps of the recorded clock (empty when none were)."""
    if not g or not g.get("n_samples"):
        return ""
    gaps = g["gaps"]
    where = ", ".join(
        f"{x['start_s']:.4g}-{x['stop_s']:.4g} s ({x['samples']} samples, {x['duration_s'] * 1e3:.3g} ms)"
        for x in gaps[:5]
    )
    more = f" and {len(gaps) - 5} more" if len(gaps) > 5 else ""
    return (
        f"{g['n_samples']} samples were not measured but filled across {len(gaps)} gap(s) of the recorded clock "
        f"(at {where}{more}); {g['treatment']}."
    )


def filled_gaps(d: dict) -> list[str]:
    """The paragraph on filled samples (where, how long, how they were treated), or nothing."""
    line = filled_gaps_line(d.get("filled_gaps"))
    return [line, ""] if line else []


def compare(d: dict, figures: Figures, overlay_caption: str) -> list[str]:
    """Section 1: the baseline and the configured model's fitted parameters, and the overlay."""
    base, conf = d["baseline"], d["configured"]
    out = ["## 1. Compare: the model over the measurement", ""]
    out += [f"Baseline fit (chi2/n = {base['chi2_per_sample']:.3g}, NRMSE {pct(base['nrmse'])}):", ""]
    out += param_table(base["params"], base["ci95"]) + [""]
    if configured_on(d):
        out += [
            f"Configured model (`model.effects` = {conf['effects']}; NRMSE {pct(conf['nrmse'])}, "
            f"floor {pct(conf['noise_floor_nrmse'])}):",
            "",
        ]
        out += param_table(conf["params"], conf["ci95"]) + [""]
    return out + figures.lines("overlay", overlay_caption)


def where_it_fails(d: dict, input_name: str = "input", segment: str = "segment") -> list[str]:
    """Section 2 (start): the baseline's residual tests and its findings."""
    base = d["baseline"]
    alpha = base["tests"]["test_significance"]
    return [
        "## 2. Where the baseline fails",
        "",
        f"Residual tests on the residual whitened by the floor (each at {alpha:.2g}, family-wise {4 * alpha:.2g}): "
        + tests_line(base["tests"], input_name),
        "",
        *findings_lines(summary_findings(base["tests"], input_name, segment)),
        "",
    ]


def ranking(d: dict, figures: Figures) -> list[str]:
    """Section 3: every catalogue effect added in turn, by evidence; the most likely missing one."""
    out = ["## 3. Which effect is missing", ""]
    out.append(
        "Each effect of the catalogue was added to the "
        + ("configured" if configured_on(d) else "baseline")
        + " model in turn and refitted. Evidence: delta BIC, the share of the misfit above the floor the "
        "effect explains, the NRMSE with the effect, and whether the residual becomes white."
    )
    out += ["", "| rank | effect | delta BIC | share explained | NRMSE after | white after | fitted |"]
    out.append("|---|---|---|---|---|---|---|")
    for i, r in enumerate(d["ranking"]):
        white = "yes" if r["white"] else "no"
        out.append(
            f"| {i + 1} | `{r['effect']}` | {r['delta_bic']:.4g} | {share(r)} | "
            f"{nrmse_after(r)} | {white} | {r['summary'].replace('|', '/')} |"
        )
    out += ["", DEFINITIONS, ""]
    out += winner(d) + figures.lines(
        "ranking", "Evidence for each effect of the catalogue (delta BIC when added; > 0 favours it)."
    )
    return out


def winner(d: dict) -> list[str]:
    """The most likely missing effect with its physics and fitted values, or why none was kept."""
    w = d.get("winner")
    if w:
        return [
            f"**Most likely missing: `{w['effect']}`** ({w['title']}). {w['physics']}",
            "",
            f"Fitted: {w['summary']}.",
            "",
            *param_table(w["params"], w["ci95"]),
            "",
        ]
    best = d["ranking"][0] if d["ranking"] else None
    st = d.get("settings", {})
    tried = [s["added"] for s in d.get("dropped_steps", [])]
    if best and best["effect"] in tried:
        return [
            f"No effect was kept. The best candidate, `{best['effect']}` (delta BIC {best['delta_bic']:.3g}), "
            f"explains only {share(best)} of the misfit and the residual keeps structure "
            "after the search: it would stand in for a mechanism outside the catalogue (see the verdict).",
            "",
        ]
    if best:
        return [
            f"No effect is supported by the evidence (best: `{best['effect']}`, delta BIC "
            f"{best['delta_bic']:.3g} against the {st.get('min_delta_bic')} needed; share explained: {share(best)}, "
            f"{_pct_setting(st.get('min_share'))} needed).",
            "",
        ]
    return []


def ladder(d: dict, figures: Figures) -> list[str]:
    """Section 4: NRMSE and evidence after each step; the additions tried and dropped."""
    base = d["baseline"]
    out = ["## 4. Adding effects: the error ladder", ""]
    out += [
        "| step | model | NRMSE | noise floor | delta BIC | share explained |",
        "|---|---|---|---|---|---|",
    ]
    out.append(f"| 0 | baseline | {pct(base['nrmse'])} | {pct(base['noise_floor_nrmse'])} | | |")
    for i, s in enumerate(d["steps"]):
        if i == 0 and not configured_on(d):
            continue
        name = " + ".join(["baseline", *s["effects"]])
        db = "" if s["delta_bic"] is None else f"{s['delta_bic']:.4g}"
        sh = "" if s["excess_explained"] is None else share(s)
        step = "configured" if i == 0 else str(i)
        out.append(f"| {step} | {name} | {pct(s['nrmse'])} | {pct(s['noise_floor_nrmse'])} | {db} | {sh} |")
    out += ["", "Columns as defined under the ranking (section 3).", ""]
    for s in d.get("dropped_steps", []):
        out.append(f"- Tried and dropped: `{s['added']}` ({s['reason']}).")
    if d.get("dropped_steps"):
        out.append("")
    return out + figures.lines("ladder", "NRMSE after each step, with the noise floor of each model.")


def final_model(d: dict, input_name: str = "input", advice: str = "") -> list[str]:
    """Section 5: the final model, its tests and the verdict; ``advice`` where structure remains."""
    final = d["final"]
    out = ["## 5. The final model", ""]
    out += [
        f"Effects: {final['effects'] or 'none (baseline)'}; NRMSE {pct(final['nrmse'])}, floor "
        f"{pct(final['noise_floor_nrmse'])}, chi2/n {final['chi2_per_sample']:.3g}.",
        "",
    ]
    out += param_table(final["params"], final["ci95"]) + [""]
    out += [
        "Residual tests: " + tests_line(final["tests"], input_name),
        "",
        f"**Verdict: {d['verdict']}.**",
        "",
    ]
    if d["verdict"] == "unexplained":
        out += findings_lines(d["unexplained"]) + [""]
        if advice:
            out += [advice, ""]
    return out


def identifiability(d: dict) -> list[str]:
    """Section 6: how firmly the record decides each step (runner-up, BIC margin) and the correlations."""
    idf = d.get("identifiability")
    if not idf:
        return []
    out = ["## 6. How firmly the record decides", ""]
    out.append(
        "Strength of a BIC difference in the words of Kass & Raftery (1995): > 10 decisive, 6-10 strong, "
        "2-6 positive, < 2 weak. The margin is how much better the winner of a step fits than its runner-up."
    )
    out.append("")
    if idf["steps"]:
        out += ["| step | added | delta BIC | strength | runner-up | margin (BIC) | margin strength |"]
        out.append("|---|---|---|---|---|---|---|")
        for i, st in enumerate(idf["steps"]):
            ru = f"`{st['runner_up']}`" if st["runner_up"] else "none"
            m = "" if st["margin_bic"] is None else f"{st['margin_bic']:.4g}"
            out.append(
                f"| {i + 1} | `{st['added']}` | {st['delta_bic']:.4g} | {st['strength']} | {ru} | {m} | "
                f"{st['margin_strength'] or ''} |"
            )
        out.append("")
        for st in idf["steps"]:
            if st["margin_strength"] == "weak":
                out += [
                    f"- The record barely separates `{st['added']}` from `{st['runner_up']}` "
                    f"(margin {st['margin_bic']:.2g}): read them as equally likely.",
                    "",
                ]
    stop = idf.get("stop")
    if stop:
        out += [
            f"The search stopped: the best further candidate, `{stop['best']}`, changes the BIC by "
            f"{stop['delta_bic']:.3g} (evidence for it: {stop['strength']}); share explained of the misfit left: "
            f"{share(stop)}.",
            "",
        ]
    for eq in idf.get("equivalences", []):
        a, b = eq["effects"]
        fitted = "; ".join(
            f"`{n}`: {eq[n]['summary']} (delta BIC {eq[n]['delta_bic']:.6g})" for n in (a, b) if n in eq
        )
        out += [
            f"**`{a}` and `{b}` are {eq['statement']}.** "
            + (f"Fitted each alone: {fitted}." if fitted else ""),
            "",
        ]
    pairs = idf["correlated_pairs"]
    if pairs:
        out.append(f"Parameters of the final fit correlated beyond |r| = {idf['correlation_threshold']}:")
        out.append("")
        for p in pairs:
            a, b = p["params"]
            out.append(
                f"- `{a}` and `{b}`: r = {p['correlation']:+.3f}; the record determines a combination of the "
                "two better than either alone."
            )
        out.append("")
    else:
        n = len(idf["correlation"])
        out += [
            f"No pair of the final fit's {n} parameter(s) is correlated beyond |r| = {idf['correlation_threshold']}"
            " (correlations from the Jacobian at the optimum, in `diagnosis.json`).",
            "",
        ]
    out += intervals(idf.get("intervals") or {})
    return out


def intervals(iv: dict) -> list[str]:
    """How each 95% interval of the final fit was found: the Jacobian's (checked) or the profile likelihood's."""
    if not iv:
        return []
    factors = correlation_factors(iv)
    prof = {k: i for k, i in iv.items() if i["method"] != "jacobian (checked)"}
    out = [
        f"95% intervals of the final fit: {len(iv) - len(prof)} of {len(iv)} from the Jacobian, checked (chi2 "
        "rises by the threshold within 25% at both ends along the profile line)"
        + ("." if not prof else "; where not, the profile likelihood (the others refitted at each trial value):"),
        "",
    ]
    if prof:
        out += [
            "| parameter | shown in | value | interval | Jacobian's interval | chi2 rise at the Jacobian's ends "
            "| method |"
        ]
        out.append("|---|---|---|---|---|---|---|")
        for k, i in prof.items():
            rise = ", ".join(f"{r:.2f}" for r in i["rise_at_jacobian_ends"])
            bound = " (reaches the bound)" if any(i["at_bound"]) else ""
            val, iv = value_and_ci(k, i["value"], i["ci"])
            out.append(
                f"| `{k}` | {shown_in(k)} | {val} | {iv}{bound} | {ci(k, i['jacobian_ci'], i['value'])} | "
                f"{rise} x D | {i['method']} |"
            )
        out.append("")
    return out + factors


def correlation_factors(iv: dict) -> list[str]:
    """The factors the intervals were widened by for the residual's autocorrelation (``correlation_factor`` of
    each interval; none: nothing said)."""
    f = {k: i["correlation_factor"] for k, i in iv.items() if i.get("correlation_factor") is not None}
    if not f:
        return []
    top = max(f, key=f.get)
    wide = sorted((k for k in f if f[k] > 1.0), key=lambda k: -f[k])
    listed = ", ".join(f"`{k}` {f[k]:.3g}" for k in wide[:6]) or "none above 1"
    return [
        f"Each interval is widened for the residual's autocorrelation: its variance times the factor of the "
        f"parameter's HAC (Newey-West) variance over the Gauss-Newton one, read from the whitened residual where "
        f"the parameter's Jacobian column lives (1: a white residual there; the half-width grows by its square "
        f"root). Largest: `{top}` {f[top]:.3g}; above 1: {listed}.",
        "",
    ]


def method(d: dict, fit_line: str, tests_line_: str) -> list[str]:
    """How this was computed: the fit, the tests (subject wording) and the selection rule (from settings)."""
    st = d.get("settings", {})
    return [
        "## How this was computed",
        "",
        fit_line,
        tests_line_,
        f"- Selection: an effect is added when its delta BIC exceeds {st.get('min_delta_bic')} and it explains "
        f"at least {_pct_setting(st.get('min_share'))} of the misfit above the floor; if structure remains, "
        f"additions that explained less than {_pct_setting(st.get('min_share_if_unexplained'))} at their step "
        "are dropped.",
        "",
    ]


def _pct_setting(x) -> str:
    """A fraction setting [-] as a percentage, as the report shows every share ('?' when not recorded)."""
    return "?" if x is None else f"{100 * x:g}%"


def config_used(d: dict) -> list[str]:
    """The configuration the diagnosis ran with, folded."""
    if "config" not in d:
        return []
    return [
        "<details><summary>Configuration used</summary>",
        "",
        "```json",
        json.dumps(d["config"], indent=2),
        "```",
        "",
        "</details>",
        "",
    ]
