"""The running bearing's diagnosis report (``DIR/report.md``), composed of the engine's sections.

What is the bearing's own: the baseline's name (the healthy bearing at the
nominal point), the record and its floor, the fault answer, the views
(roller passages, synchronous average, envelope with the fault bands,
orders) and the method's wording. Everything comes from ``diagnosis.json``.
"""

from __future__ import annotations

from ..report import sections as s
from .figures import FIGURES


def measurement(d: dict) -> list[str]:
    fl, base = d["noise_floor"], d["baseline"]
    out = [
        "## The record and its noise floor",
        "",
        f"{d['n_samples']} samples at {d['sample_rate_Hz']:.6g} Hz ({d['duration_s']:.3g} s), "
        f"{d.get('n_passages', 0)} roller passages over the sensor, voltage rms {d['voltage_rms_V']:.4g} V.",
        "",
    ]
    rate = d.get("model_rate")
    if rate:
        out += [f"The model is held against the record at {rate['model_rate_Hz']:.6g} Hz: {rate['reason']}.", ""]
    sp = d.get("shaft_speed")
    if sp:
        out += [f"Nominal shaft speed {sp['rpm']:g} rpm ({sp['source']}).", ""]
    out += [
        f"Noise floor from the record itself ({fl['method']}): {fl['voltage_noise_V']:.4g} V rms, "
        f"NRMSE {s.pct(base['noise_floor_nrmse'])}. The model has no measured input: a correct model leaves "
        "this white noise alone.",
        "",
    ]
    for w in d.get("record_warnings", []):
        out += [f"- **record**: {w}", ""]
    return out


def fault(d: dict) -> list[str]:
    """The answer: fault type, size and position with intervals, operating conditions, look-alikes."""
    f = d["fault"]
    out = ["## The fault", ""]
    if f["type"] == "none":
        out.append(no_fault(f, d["verdict"]))
    elif f.get("source") == "lines":
        out.append(f"**Fault: {f['type'].replace('_', ' ')}**, named from its lines: no defect of the model "
                   "reproduces them, so there is no size or position to give.")
        out += ["", *found_and_left(f)]
    else:
        out.append(f"**Fault: {f['type'].replace('_', ' ')}.**")
        out.append("")
        out += s.param_table(f["params"], f["ci95"])
        out += ["", *found_and_left(f)]
    for u in f.get("unidentified") or []:
        out += ["", f"- `{u['effect']}` was left out of the search: {u['reason']} (the record cannot pin it down)."]
    out += ["", "Operating conditions (fitted where the search selected the effect, else the nominal value):", ""]
    out += ["| condition | shown in | value | 95% interval | fitted |", "|---|---|---|---|---|"]
    for k, v in f["operating_conditions"].items():
        val, iv = s.value_and_ci(k, v, f["operating_conditions_ci95"].get(k))
        fitted = "yes" if k in f["fitted_conditions"] else "no"
        out.append(f"| `{k}` | {s.shown_in(k)} | {val} | {iv} | {fitted} |")
    out += ["", "What this record cannot tell apart, and how each interval was found: section 6.", ""]
    return out


def no_fault(f: dict, verdict: str) -> str:
    """The answer where no fault is named: the statement's reason where it gives one (lines set aside as a comb at
    the shaft's orders, or as lines without energy above the floor), else that no defect was selected and why
    that holds."""
    head, _, why = f["statement"].partition(": ")
    if why:
        return f"**{head[0].upper()}{head[1:]}**: {why}."
    if verdict == "explained":
        return "**No fault**: no defect effect was selected (the healthy bearing explains the record)."
    return ("**No fault**: no defect effect was selected, and no fault family's lines stand above the lines "
            "rule's threshold in what the best healthy model leaves (what the model leaves: the verdict above).")


def found_and_left(f: dict) -> list[str]:
    """What the diagnosis found and what of the fault's own lines its model leaves (``fault.statement``,
    ``fault.lines_left``): each line with the record's level against the model's and above the floor."""
    out = [f"**What it found and what of it remains:** {f.get('statement') or 'no statement'}.", ""]
    left = f.get("lines_left") or []
    if not left:
        return out + ["None of the fault's own lines (its passing rate's harmonics and their sidebands) is left "
                      "above the floor by the final model.", ""]
    out += [
        "The fault's own lines the final model leaves above the floor (record against model: the ratio of their "
        "Hann-windowed amplitude spectra at the line; positive: the record's line is the stronger):",
        "",
        "| line | frequency (Hz) | record over model (dB) | above the floor (dB) |",
        "|---|---|---|---|",
    ]
    for r in left:
        out.append(f"| {r['line']} | {r['frequency_Hz']:.2f} | {r['record_over_model_dB']:+.1f} | "
                   f"{r['excess_dB']:.1f} |")
    return out + [""]


def dynamic_rung(d: dict) -> list[str]:
    """The dynamic rung (``dynamic_rung``): whether the shaft's dynamics were tried, why, and what they bought."""
    r = d.get("dynamic_rung")
    if not r:
        return []
    out = ["## The shaft's dynamics (the dynamic rung)", ""]
    if not r["tried"]:
        return out + [f"Not tried: {r['why']}.", ""] + joint_search(r.get("joint"))
    verdict = "accepted" if r["accepted"] else "not accepted"
    out += [
        f"Tried because {r['why']}: the quasi-static selection{' and ' + ', '.join(r['pair']) if r.get('pair') else ''} "
        f"refitted with `shaft_dynamics`; {verdict} by the selection rule (BIC drop {r['delta_bic']:.4g}, "
        f"{r['strength']}; {100 * r['excess_explained']:.0f} % of the quasi-static model's misfit above the floor "
        "explained). The diagnosis above is the "
        + ("dynamic model's." if r["accepted"] else "quasi-static model's."),
        "",
        *ladder_table(r["ladder"]),
    ]
    out += ["", f"Quasi-static answer: {r['quasi_static']['fault']}.", ""]
    if r.get("left_out"):
        out += [f"Left out with the dynamics on (not supported by the record): {', '.join(r['left_out'])}.", ""]
    if r.get("other_types"):
        said = "; ".join(f"the {o['type'].replace('_', ' ')}'s defect, BIC drop {o['delta_bic']:.4g}, "
                         f"{'accepted' if o['accepted'] else 'not accepted'}" for o in r["other_types"])
        out += [f"Also tried with the defect of another family the residual shows: {said}.", ""]
    out += shaft_mass(r.get("shaft_mass"), r["accepted"])
    return out + housing_rung(r.get("housing_mode")) + joint_search(r.get("joint"))


def shaft_mass(m: dict | None, accepted: bool = True) -> list[str]:
    """The dynamic rung's scan of the shaft's mass (``dynamic_rung.shaft_mass``): held at the rig file's, or found
    other than it, the rung run again with the mass fitted (``accepted``: whether the rung was)."""
    if not m or "rig_kg" not in m:
        return []
    if not m["tried"]:
        return [f"The shaft's mass is the rig file's, {m['rig_kg']:.3g} kg: {m['why'].removeprefix('not fitted: ')}.", ""]
    out = f"The shaft's mass: {m['why']}; the rung ran again from {m['start_kg']:.3g} kg with the mass fitted"
    if not m.get("kept"):
        return [out + f", and that fit was not kept (BIC drop {m.get('delta_bic', float('nan')):.4g}).", ""]
    ci = m.get("ci95") or [None, None]
    where = f" [{ci[0]:.4g}, {ci[1]:.4g}]" if ci[0] is not None else ""
    if not accepted:
        return [out + f" ({m.get('fitted_kg', m.get('search_kg', m['start_kg'])):.4g} kg), and the rung was not "
                "accepted with it either: the record's misfit is not the shaft's mass.", ""]
    if not m.get("identified", True):
        return [out + f" (BIC drop {m['delta_bic']:.4g}), but the final fit does not pin the mass down "
                f"({m['fitted_kg']:.4g}{where} kg): the record does not tell the shaft's mass; weigh it and give "
                "`bearing.shaft_mass_kg` in the rig file.", ""]
    out += (f" (BIC drop {m['delta_bic']:.4g}): **{m['fitted_kg']:.4g}{where} kg, not the rig file's "
            f"{m['rig_kg']:.3g} kg**. Check `bearing.shaft_mass_kg` in the rig file (the shaft's and inner ring's "
            "mass this bearing carries).")
    alias = m.get("alias")
    if alias:
        others = " or ".join(f"{x:.3g}" for x in alias["masses_kg"]) or "no other mass of the scan's range"
        out += (f" At this record's rate its mode ({alias['mode_Hz']:.4g} Hz) is seen only through its alias at "
                f"{alias['alias_Hz']:.4g} Hz, where a shaft of {others} kg would ring too: the mass found is a hint "
                "to weigh the shaft, not a measurement.")
    return [out, ""]


def joint_search(j: dict | None) -> list[str]:
    """The joint dynamic search (``dynamic_rung.joint``): the dynamic healthy model and each defect type fitted with
    the operating point, the floor measured again, and whether a type replaced the answer."""
    if not j:
        return []
    judged = j.get("with_roller_scatter") or j
    fl = judged["floor"]
    hof = j.get("healthy_over_final") or {}
    out = [
        "### The joint search: the operating point and each defect type with the dynamics on", "",
        f"The dynamic healthy model ({judged['healthy']['model']}) leaves NRMSE {s.pct(judged['healthy']['nrmse'])}"
        + (f" (BIC drop {hof['delta_bic']:.4g} over the final model before the search)" if hof else "")
        + f"; the floor measured again on the best dynamic residual ({fl['measured_on']}): {fl['after_V']:.4g} V "
          f"against {fl['before_V']:.4g} V before. {'A type replaced the answer' if j.get('replaced') else 'The answer is kept'}: "
          f"{j.get('why', '')}.", "",
        "| type | NRMSE | BIC drop over the dynamic healthy model | share of its misfit | passes the rule | identified |",
        "|---|---|---|---|---|---|",
    ]
    rows = [(n, j["types"][n]) for n in j["ranked"]]
    if j.get("with_roller_scatter"):
        rows += [(f"{n} (with roller_scatter)", t) for n, t in j["with_roller_scatter"]["types"].items()]
    for n, t in rows:
        out.append(f"| {n} | {s.pct(t['nrmse'])} | {t['delta_bic']:.4g} | {100 * t['excess_explained']:.0f} % | "
                   f"{'yes' if t['passes_rule'] else 'no'} | {'yes' if t['identified'] else 'no'} |")
    return out + [""]


def housing_rung(h: dict | None) -> list[str]:
    """The housing mode's rung (``dynamic_rung.housing_mode``), tried where the dynamic rung left the record
    unexplained."""
    if not h:
        return []
    if not h["tried"]:
        return ["## A housing mode (the rung above the shaft's dynamics)", "", f"Not tried: {h['why']}.", ""]
    verdict = "accepted" if h["accepted"] else "not accepted"
    out = [
        "## A housing mode (the rung above the shaft's dynamics)", "",
        f"Tried: {h['why']}. The dynamic model refitted with `housing_mode`; {verdict} by the selection rule "
        f"(BIC drop {h['delta_bic']:.4g}, {h['strength']}; {100 * h['excess_explained']:.0f} % of the dynamic "
        "model's misfit above the floor explained).",
        "",
        *ladder_table(h["ladder"]),
    ]
    if h.get("left_out"):
        out += ["", f"Left out with the housing mode on (not supported by the record): {', '.join(h['left_out'])}."]
    return out + [""]


def ladder_table(ladder: list[dict]) -> list[str]:
    """A rung's ladder (model, NRMSE) as a table's lines."""
    return ["| model | NRMSE |", "|---|---|", *(f"| {row['model']} | {s.pct(row['nrmse'])} |" for row in ladder)]


def sensor_model(d: dict) -> list[str]:
    """Which model turned the force into voltage: the RC circuit alone or times the sensor FEM's correction,
    and where the correction came from (``sensor_model`` of diagnosis.json)."""
    m = d.get("sensor_model")
    if not m:
        return []
    rc = (f"the RC circuit of Eq. 6 (R = {m['resistance_ohm'] / 1e6:.4g} MOhm, C = {m['capacitance_F'] * 1e9:.4g} "
          f"nF, tau = RC = {m['tau_s']:.4g} s, d33/C = {m['open_circuit_gain_V_per_N']:.4g} V/N)")
    c = m.get("fem_correction")
    if m.get("model") == "rc" or not c:
        text = f"Force to voltage: {rc} alone, gain {m['gain_V_per_N']:.4g} V/N ({m['source']})."
    else:
        lo, hi = c["frequencies_Hz"]
        text = (f"Force to voltage: {rc} times the sensor FEM's correction {m['fem_factor']:.4g} (the median of "
                f"|H_FEM| / |H_RC| at {c['n_frequencies']} frequencies, {lo:.4g}-{hi:.4g} Hz, below the record's "
                f"Nyquist frequency; spread {c['min']:.4g}-{c['max']:.4g}), gain {m['gain_V_per_N']:.4g} V/N. "
                f"The correction comes from {m['source']}.")
    return ["## The sensor model", "", text, ""]


def separability(d: dict) -> list[str]:
    """Section 6, the bearing's part: the look-alikes with this record's evidence, and how each interval of
    the answer was found (after the engine's margins, correlations and profiled intervals)."""
    f = d["fault"]
    out = ["### What this record cannot tell apart", ""]
    for n in f["non_separable"]:
        names = ", ".join(f"`{x}`" for x in n["set"])
        line = f"- {names}: {n['why']}."
        if n.get("exact"):
            line += " Exact: no record separates them; a fitted `load_share_ratio` is the share times the circuit's gain over the configured one."
        ev = n.get("evidence") or {}
        if len(ev) > 1:
            line += " This record, each fitted alone (delta BIC): " + ", ".join(
                f"`{e}` {v:.4g}" for e, v in sorted(ev.items(), key=lambda x: -x[1])
            )
            chosen = [e for e in ev if e in d.get("selected", [])]
            if max(ev.values()) <= 2.0:
                line += ": none of them is needed here."
            elif not chosen:
                line += ": none of them was selected (alone, each stood in for what was)."
            else:
                told = "told apart here" if n["margin_strength"] in ("decisive", "strong") else "not told apart here"
                line += f"; the best over the next by {n['margin_bic']:.3g}: {n['margin_strength']} ({told})."
        for c in n.get("correlation", []):
            a, b = c["params"]
            line += f" Final fit: r(`{a}`, `{b}`) = {c['correlation']:+.3f}."
        out.append(line)
    out += ["", "### How each interval of the answer was found", ""]
    ivs = d.get("identifiability", {}).get("intervals", {})
    factors = any("correlation_factor" in i for i in ivs.values())
    out += ["| quantity | shown in | value | 95% interval | found by |" + (" correlation factor |" if factors else ""),
            "|---|---|---|---|---|" + ("---|" if factors else "")]
    values = {**f["params"], **f["operating_conditions"]}
    cis = {**f["ci95"], **f["operating_conditions_ci95"]}
    for k, how in f.get("ci_method", {}).items():
        iv = ivs.get(k, {})
        bound = " (reaches the bound: the record does not close it there)" if any(iv.get("at_bound", ())) else ""
        val, interval = s.value_and_ci(k, values[k], cis.get(k))
        fac = (f" {iv['correlation_factor']:.3g} |" if "correlation_factor" in iv else " - |") if factors else ""
        out.append(f"| `{k}` | {s.shown_in(k)} | {val} | {interval}{bound} | {how} |{fac}")
    out += [
        "",
        "Jacobian (checked): the Gauss-Newton interval, whose ends raise chi2 by the threshold within 25% "
        "along the profile line; profile: the others refitted at each trial value (the cost is not quadratic "
        "there); not honest (not profiled / profile over budget): the Jacobian's, kept because the engine's "
        "profile budget was spent, read it as a rough width."
        + (" Correlation factor: the widening for the residual's autocorrelation, as in the engine's intervals "
           "above." if factors else ""),
        "",
    ]
    return out


def views(d: dict, figures: s.Figures) -> list[str]:
    """The representations: passages, synchronous average, envelope with the fault bands, orders."""
    out = ["## The bearing's views of the residual", ""]
    pp = d.get("per_passage", {})
    if pp:
        out.append(
            f"Error per roller passage: {pp['baseline']['flagged']} of {pp['baseline']['n_passages']} passages "
            f"above the floor for the baseline, {pp['final']['flagged']} for the final model."
        )
        out.append("")
    out += figures.lines("per_passage", "Residual energy of each roller passage over the noise floor.")
    sa = d.get("synchronous_average", {})
    if sa:
        out.append(
            f"Synchronous average over the roller passage ({sa['final']['bins']} bins): largest residual "
            f"{sa['baseline']['max_abs_z']:.1f} standard errors for the baseline, {sa['final']['max_abs_z']:.1f} "
            f"for the final model (band {sa['final']['threshold_z']:.1f})."
        )
        out.append("")
    out += figures.lines(
        "synchronous_average",
        "Measured voltage, baseline and final model averaged over the roller-passage period (0: a roller over "
        "the sensor), and the residuals with the noise band.",
    )
    env = d.get("envelope", {})
    if env:
        lines = sorted(env["final"]["lines"], key=lambda x: -x["residual_ratio"])[:4]
        out.append(
            "Envelope spectrum of the residual at the fault bands (largest, final model): "
            + ", ".join(f"{x['name']} {x['frequency_Hz']:.2f} Hz {x['residual_ratio']:.1f}x" for x in lines)
            + f" (threshold {env['final']['threshold_ratio']:.1f}x the envelope floor)."
        )
        out.append("")
    out += figures.lines("envelope", "Envelope spectra of the measured voltage and the residuals, every fault band marked.")
    od = d.get("orders", {})
    if od and od["final"]["peaks"]:
        out += ["| residual line (Hz) | shaft order | roller-pass order | bearing frequency | excess (dB) |", "|---|---|---|---|---|"]
        for p in od["final"]["peaks"][:6]:
            out.append(
                f"| {p['frequency_Hz']:.2f} | {p['shaft_order']:.3f} | {p['roller_pass_order']:.3f} | "
                f"{p['named'] or '-'} | {p['excess_dB']:.1f} |"
            )
        out.append("")
    return out


METHOD_FIT = (
    "- Fit: maximum likelihood with the noise floor measured from the record (white), over the DFT bins. "
    "The model: the rings' quasi-static load distribution with any defect's drop, times the housing's "
    "influence line (the quasi-static surrogate, docs/theory/bearing_housing.md), through the sensor model (its "
    "section) from the circuit's steady state; nuisance parameters fitted in every model: the roller set's phase at the first sample, the "
    "shaft speed within its tolerance (or the tachometer's), the DC level. NRMSE = rms(residual) / rms(measured)."
)
METHOD_TESTS = (
    "- Tests on the residual whitened by the floor: Ljung-Box; averaged periodogram against the chi-square "
    "quantile (Bonferroni over frequencies); energy in windows; and the bearing's views: energy per roller "
    "passage (Bonferroni over passages), synchronous average against its standard error, the residual's "
    "envelope at every fault band (largest of the band's bins against the envelope floor)."
)
ADVICE = (
    "Look for a mechanism at these frequencies and orders (a loose part striking once per shaft turn, a "
    "coupling, a gear mesh, a housing resonance); add it as an effect module to test it."
)


def render(d: dict, figures: dict[str, str] | None = None) -> str:
    """The report as Markdown; ``figures`` maps :data:`FIGURES` names to paths relative to the report."""
    fig = s.Figures(figures or {})
    return s.join(
        [
            s.headline(
                d,
                f"Running bearing, model versus measurement: `{d.get('source', 'record')}`",
                "The healthy bearing at the nominal operating point (phase, speed and DC level fitted)",
            ),
            s.verdict_paragraph(d, "voltage"),
            fault(d),
            dynamic_rung(d),
            measurement(d),
            sensor_model(d),
            s.compare(
                d,
                fig,
                "Measured voltage with the baseline and the final model over the twelve roller passages where the "
                "baseline misses most (grey: a roller over the sensor), and the residuals.",
            ),
            s.where_it_fails(d, "voltage", "passage"),
            views(d, fig),
            fig.lines("spectrum", "Residual spectrum against the noise floor and the detection threshold."),
            s.ranking(d, fig),
            s.ladder(d, fig),
            s.final_model(d, "voltage", ADVICE),
            s.identifiability(d) + separability(d),
            s.method(d, METHOD_FIT, METHOD_TESTS),
            s.config_used(d),
        ]
    )


__all__ = ["FIGURES", "render"]
