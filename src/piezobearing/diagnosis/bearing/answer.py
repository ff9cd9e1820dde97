"""The running bearing's answer: the ``fault`` entry of ``diagnosis.json``.

The fault found with its size, position and 95 % intervals, the operating conditions, what one record cannot
tell apart (:func:`non_separable`, :func:`separability`), what of the fault's own lines the model leaves
(:func:`fault_lines_left`, :func:`fault_sidebands`), and, where no defect is selected, the fault its lines still
show (:func:`fault_evidence`): never "no fault" where the residual holds a fault family.
"""

from __future__ import annotations

import numpy as np
from scipy.special import chdtri

from ..selection import add_effect, strength
from .effects import FAULT_TYPES
from .healthy import dynamic_healthy
from .representations import EnvelopeBands

#: Which operating conditions the answer reports, and what each cannot be told apart from.
CONDITIONS = {
    "cage_slip_ratio": "cage_slip",
    "radial_load_N": "radial_load",
    "radial_clearance_m": "clearance",
    "load_share_ratio": "load_share",
    "shaft_speed_Hz": None,
    "speed_deviation_ratio": "shaft_speed",
}


def non_separable(tach: bool) -> list[dict]:
    """The sets of quantities one record cannot tell apart (stated, not hidden), each with the catalogue
    effects that stand for them (``effects``: whose first-ranking evidence :func:`separability` reads)."""
    out = [
        {
            "set": ["load_share_ratio", "sensor.d33_C_per_N", "capacitance C", "circuit and DAQ gain"],
            "why": "all scale the voltage by one factor for a single record",
            "exact": True,
            "effects": ["load_share"],
        },
        {
            "set": ["radial_load_N", "radial_clearance_m", "load_share_ratio"],
            "why": "partly: heavier load, smaller clearance and a larger share all raise the bumps; only the load "
            "zone's shape tells them apart (see the fit's correlations)",
            "exact": False,
            "effects": ["radial_load", "clearance", "load_share"],
        },
        {
            "set": ["outer_race 2 x BSF", "BPFO"],
            "why": "2 x BSF can sit within a bin or two of BPFO in a short record (for this bearing "
            "2 x BSF / BPFO = 0.98)",
            "exact": False,
            "effects": ["outer_race_defect", "rolling_element_defect"],
        },
    ]
    if not tach:
        out.insert(
            1,
            {
                "set": ["cage_slip_ratio", "shaft_speed_Hz"],
                "why": "without a tachometer only the roller-pass rate Z x FTF (1 - slip) is seen, unless an "
                "inner-race defect shows the shaft rate",
                "exact": False,
                "effects": ["cage_slip", "shaft_speed"],
            },
        )
    return out


def separability(sets: list[dict], ranking: list, correlation: dict) -> list[dict]:
    """What this record says about each non-separable set (:func:`non_separable`).

    ``evidence``: the BIC drop of each of the set's effects fitted alone in
    the first ranking; ``margin_bic`` and ``margin_strength``: the best of
    them over the next (the engine's plain words,
    :func:`~piezobearing.diagnosis.selection.strength`): "decisive" means
    this record did tell them apart, "weak" that it could not;
    ``correlation``: the final fit's correlation of every pair of the set's
    parameters that it fitted (near +-1: only a combination is determined).
    An exact set (the gain's) has no evidence to give: no record separates it.
    """
    first = {c.effect.name: float(c.delta_bic) for c in ranking}
    out = []
    for ns in sets:
        row = dict(ns)
        ev = {e: first[e] for e in ns["effects"] if e in first}
        row["evidence"] = ev
        top = sorted(ev.values(), reverse=True)
        margin = top[0] - top[1] if len(top) > 1 else None
        row["margin_bic"], row["margin_strength"] = margin, strength(margin)
        names = [k for k in ns["set"] if k in correlation]
        row["correlation"] = [
            {"params": [a, b], "correlation": correlation[a][b]} for i, a in enumerate(names) for b in names[i + 1:]
        ]
        out.append(row)
    return out


def fault_answer(d) -> dict:
    """``fault``: type, size and position with 95% intervals, the operating conditions found, look-alikes.

    ``ci_method`` says how each interval was found (the engine's honest intervals of the final model,
    :func:`~piezobearing.diagnosis.engine.final_intervals`: "jacobian (checked)", "profile", or a
    Jacobian one flagged not honest: not profiled / profile over budget; "not fitted (nominal)").
    """
    values, ci = d.final.values, d.final.result.ci95
    kind, params, ci95 = "none", {}, {}
    for name in d.selected:
        if name in FAULT_TYPES:
            kind, wkey, pkey = FAULT_TYPES[name]
            params = {wkey: values[wkey], pkey: values[pkey]}
            ci95 = {wkey: ci.get(wkey), pkey: ci.get(pkey)}
            if name == "rolling_element_defect":
                params["roller_defect_index"] = values["roller_defect_index"]
            break
    cond, cond_ci, fitted = {}, {}, []
    rig = d.record.rig
    nominal = {
        "cage_slip_ratio": 0.0,
        "radial_load_N": rig.radial_load_N,
        "radial_clearance_m": rig.radial_clearance_m,
        "load_share_ratio": 1.0,
        "speed_deviation_ratio": 0.0,
    }
    for key in ("cage_slip_ratio", "radial_load_N", "radial_clearance_m", "load_share_ratio", "shaft_speed_Hz", "speed_deviation_ratio"):
        if key in values:
            cond[key] = values[key]
            cond_ci[key] = ci.get(key)
            fitted.append(key)
        elif key in nominal:
            cond[key] = nominal[key]
            cond_ci[key] = None
    intervals = d.identifiability.get("intervals", {})
    how = {
        k: intervals[k]["method"] if k in intervals else "held, not free" if k in values else "nominal, not fitted"
        for k in [*params, *cond]
    }
    how.pop("roller_defect_index", None)  # chosen among the starts, not fitted: no interval
    remaining = fault_lines_left(d, kind) if kind != "none" else []
    sidebands = fault_sidebands(d, kind)
    statement = fault_statement(kind, params, ci95, remaining, sidebands)
    source = "model" if kind != "none" else "none"
    evidence = fault_evidence(d)
    if kind == "none" and evidence:
        kind, source = evidence[0]["type"], "lines"
        statement = lines_statement(evidence[0], "shaft_dynamics" in d.final.model.names)
    elif kind == "none" and getattr(d, "_lines_at_floor", None):
        statement = floor_lines_statement(d._lines_at_floor[0], d._best_healthy)
    elif kind == "none" and getattr(d, "_comb_lines", None):
        statement = comb_statement(d._comb_lines)
    return {
        "type": kind,
        "source": source,
        "evidence": evidence,
        "params": params,
        "ci95": ci95,
        "statement": statement,
        "lines_left": remaining,
        "sidebands": sidebands,
        "operating_conditions": cond,
        "operating_conditions_ci95": cond_ci,
        "fitted_conditions": fitted,
        "ci_method": how,
        "healthy_model": healthy_model_entry(d),
        "shaft_comb": getattr(d, "_comb_lines", []),
        "non_separable": separability(non_separable(rig.tach_Hz is not None), d.ranking, d.final.result.correlation),
    }


#: A residual line belongs to a fault's own line within this share of its frequency, or two bins [-].
LINE_TOLERANCE = 0.005


def family_lines(kind: str, kin: dict, harmonics: int = 3) -> list[tuple[str, float]]:
    """(label, frequency [Hz]) of the lines a fault of ``kind`` puts into the sensor's spectrum: the harmonics
    of its passing rate and, for a moving defect, their sidebands at the rate that carries it through the load
    zone (f_r for the inner race, FTF for a roller)."""
    if kind == "outer_race":
        return [(f"{k}xBPFO", k * kin["bpfo_Hz"]) for k in range(1, harmonics + 1)]
    if kind == "inner_race":
        base, side, sname, bname = kin["bpfi_Hz"], kin["shaft_Hz"], "fr", "BPFI"
    else:
        base, side, sname, bname = 2 * kin["bsf_Hz"], kin["ftf_Hz"], "FTF", "2xBSF"
    out = []
    for k in range(1, harmonics + 1):
        lab = bname if k == 1 else f"{k}x{bname}"
        out += [(lab, k * base), (f"{lab}-{sname}", k * base - side), (f"{lab}+{sname}", k * base + side)]
    return out


def _fit_kinematics(d, fit) -> tuple[float, dict]:
    """The shaft's speed [Hz] and the bearing's frequencies (:meth:`Rig.frequencies`) at a fit's speed and slip."""
    values, rig = fit.values, d.record.rig
    shaft = float(values.get("shaft_speed_Hz", rig.shaft_speed_Hz) if rig.tach_Hz is None else np.mean(rig.tach_Hz))
    shaft *= 1.0 + values.get("speed_deviation_ratio", 0.0)
    # a fit may put the slip a hair below zero (its bound allows a cage a little fast); the lines' places are
    # those of no slip then, within a bin
    return shaft, rig.frequencies(shaft, max(values.get("cage_slip_ratio", 0.0), 0.0))


def _line_spectra(d, kind: str, fit=None) -> tuple[list[tuple[str, float]], float, np.ndarray, np.ndarray, float]:
    """The fault's own lines (:func:`family_lines` at the final fit's speeds), the bin width [Hz], the record's
    and the final model's Hann-windowed amplitude spectra, and the white floor's power in one such bin [V^2].
    ``fit``: another fit of the record in the final's place."""
    fit = d.final if fit is None else fit
    lines = family_lines(kind, _fit_kinematics(d, fit)[1])
    v = np.asarray(d.voltage_V, dtype=float)
    n = v.size
    w = np.hanning(n)
    rec_a = np.abs(np.fft.rfft((v - v.mean()) * w))
    mod = np.asarray(fit.model_V, dtype=float)
    mod_a = np.abs(np.fft.rfft((mod - mod.mean()) * w))
    floor = d.problem.floor.voltage_noise_V ** 2 * float(np.sum(w**2))
    return lines, 1.0 / (n * d.record.dt_s), rec_a, mod_a, floor


def _residual_spectrum(d, fit) -> tuple[np.ndarray, float, float]:
    """The Hann-windowed amplitude spectrum of ``fit``'s residual, its bin width [Hz] and the white floor's power in
    one bin [V^2] (as :func:`_line_spectra`'s)."""
    res = np.asarray(fit.residual_V, dtype=float)
    w = np.hanning(res.size)
    floor = d.problem.floor.voltage_noise_V ** 2 * float(np.sum(w**2))
    return np.abs(np.fft.rfft((res - res.mean()) * w)), 1.0 / (res.size * d.record.dt_s), floor


def _peak(a: np.ndarray, f_Hz: float, df_Hz: float) -> float:
    """The largest of a spectrum's three bins around ``f_Hz``."""
    k = int(round(f_Hz / df_Hz))
    return float(a[max(k - 1, 0):k + 2].max())


def fault_lines_left(d, kind: str) -> list[dict]:
    """The residual lines the final model leaves at the found fault's own lines (:func:`family_lines`).

    For each narrowband finding of the verdict within :data:`LINE_TOLERANCE` of one of them: its label and
    frequency, its level above the noise floor, and the record's line against the model's, 20 log10 of
    their Hann-windowed amplitude spectra's ratio at the peak (positive: the record's is the stronger) [dB].
    """
    lines, df, rec_a, mod_a, _ = _line_spectra(d, kind)
    out = []
    for u in d.unexplained:
        if u.get("test") != "spectrum" or u.get("kind") != "narrowband":
            continue
        f = u["frequency_Hz"]
        label, fl = min(lines, key=lambda x: abs(x[1] - f))
        if abs(fl - f) > max(LINE_TOLERANCE * fl, 2 * df):
            continue
        diff = 20 * np.log10(_peak(rec_a, f, df) / max(_peak(mod_a, f, df), 1e-300))
        out.append({"line": label, "frequency_Hz": float(f), "excess_dB": float(u["excess_dB"]),
                    "record_over_model_dB": float(diff)})
    return out


def fault_sidebands(d, kind: str) -> list[dict]:
    """A moving defect's first line and its sidebands, record against model: BPFI and BPFI -/+ f_r for the
    inner race, 2 x BSF and 2 x BSF -/+ FTF for a roller (the modulation through the load zone, where the
    quasi-static model and a dynamic bearing differ most); empty for the outer race.

    Each: label, frequency [Hz], the record's line over the model's (20 log10 of their Hann-windowed amplitude
    spectra's ratio at the peak, positive: the record's is the stronger) [dB], and the record's line above the
    white floor (10 log10 of its power over the floor's in one bin) [dB]: a line near 0 dB above the floor is
    noise in the record, and its difference from the model's says nothing.
    """
    if kind not in ("inner_race", "rolling_element"):
        return []
    lines, df, rec_a, mod_a, floor = _line_spectra(d, kind)
    out = []
    for label, f in lines[:3]:
        r, m = _peak(rec_a, f, df), _peak(mod_a, f, df)
        out.append({"line": label, "frequency_Hz": float(f), "record_over_model_dB": float(20 * np.log10(r / max(m, 1e-300))),
                    "record_above_floor_dB": float(10 * np.log10(r**2 / floor))})
    return out


def lines_statement(ev: dict, dynamics: bool) -> str:
    """One line for a fault named from its lines alone (no defect of the model reproduces them)."""
    kind = ev["type"].replace("_", " ")
    parts = [f"{h['line']} ({h['frequency_Hz']:.1f} Hz) {h['excess_dB']:.1f} dB above the floor" for h in ev["lines"]]
    parts += [f"envelope line at {e['band']} ({e['frequency_Hz']:.1f} Hz) {e['ratio']:.1f}x its floor" for e in ev["envelope"]]
    need = ("beyond the shaft's dynamics it needs an effect outside the catalogue (a housing mode in the band, "
            "a second defect)" if dynamics else "it needs the shaft's dynamics on its rollers (shaft_dynamics)")
    return (f"{kind} from its lines: " + ", ".join(parts[:4]) + f"; the model selects no defect that reproduces "
            f"them: {need}")


def floor_lines_statement(ev: dict, healthy) -> str:
    """One line for lines that stand above the floor where the best healthy model leaves no energy above it
    (:func:`above_floor`): no fault, and why."""
    parts = [f"{h['line']} ({h['frequency_Hz']:.1f} Hz) {h['excess_dB']:.1f} dB above the floor" for h in ev["lines"]]
    return (f"no fault: {', '.join(parts[:4])} stand above the floor, but the best healthy model leaves the record at "
            f"its floor (NRMSE {100 * healthy.nrmse:.2f} % against {100 * healthy.floor_nrmse:.2f} %): lines without "
            "energy above the floor are not a fault's signature (a housing mode in the band makes them of the roller "
            "passage's own harmonics near it; so does a narrowband interference)")


def comb_statement(aside: list[dict]) -> str:
    """One line for fault lines a shaft-synchronous comb takes (:func:`shaft_comb`): no fault, and why."""
    parts = [f"{h['line']} ({h['frequency_Hz']:.1f} Hz) {h['excess_dB']:.1f} dB" for e in aside for h in e["lines"]]
    orders = sorted({m for e in aside for m in e["comb_orders"]})
    return (f"no fault named: {', '.join(parts[:4])} above the floor lie on a comb of lines at the shaft's orders "
            f"({orders[0]}-{orders[-1]} x shaft): a source locked to the shaft puts them there, a loose part, a rub, "
            "an unbalance, or an inner-race defect the rollers meet once a turn in a narrow load zone; a record "
            "long enough to resolve k BPFI + j f_r from the whole orders tells the inner race apart")


def fault_statement(kind: str, params: dict, ci95: dict, remaining: list[dict], sidebands: list[dict] | None = None) -> str:
    """One line: the fault found with its size and interval, how a moving defect's sidebands differ from the
    model's (:func:`fault_sidebands`), and what of its own lines the model leaves above the floor."""
    if kind == "none":
        return "no fault"
    wkey = next(k for k in params if k.endswith("width_m"))
    lo, hi = ci95.get(wkey) or (float("nan"), float("nan"))
    text = f"{kind.replace('_', ' ')} {params[wkey] * 1e3:.3g} mm [{lo * 1e3:.3g}, {hi * 1e3:.3g}] (95 %)"
    if sidebands:
        carrier, *sides = sidebands
        name = carrier["line"] + " ± " + sides[0]["line"].split("-")[-1]
        text += f"; its sidebands at {name} differ from the model's by " + " and ".join(
            f"{r['record_over_model_dB']:+.1f} dB ({r['line']}, {r['frequency_Hz']:.1f} Hz, "
            f"{r['record_above_floor_dB']:.1f} dB above the floor)" for r in sides)
        text += f", the line at {carrier['line']} by {carrier['record_over_model_dB']:+.1f} dB"
    if remaining:
        text += ("; left above the floor: " if sidebands else "; its lines differ from the model's: ") + ", ".join(
            f"{r['line']} ({r['frequency_Hz']:.1f} Hz) {r['record_over_model_dB']:+.1f} dB, "
            f"{r['excess_dB']:.1f} dB above the floor" for r in remaining)
    return text


#: The catalogue effect of each fault type.
EFFECT_OF_TYPE = {kind: name for name, (kind, _w, _a) in FAULT_TYPES.items()}
#: How many bins around each carrier the lines rule reads (:func:`_peak`), and the top of the band it reads them in
#: (a share of the sampling rate: the white floor's band, :func:`~.floor.noise_floor`, ends at 45 %).
PEAK_BINS, CARRIER_BAND = 3, 0.45


def lines_threshold_dB(alpha: float, carriers: int) -> float:
    """The level above the white floor at which the lines rule (:func:`fault_evidence`: at least two of a family's
    ``carriers`` harmonics above it, three families) names a fault in white noise with probability at most ``alpha``
    [dB].

    One Hann-windowed bin of white noise has |X|^2 / floor ~ Exp(1); the largest of :data:`PEAK_BINS` bins exceeds
    x with probability at most 3 e^-x (union bound), two of K carriers with at most C(K, 2) (3 e^-x)^2; each of the
    three families gets alpha / 3: x = ln(27 C(K, 2) / alpha) / 2."""
    pairs = max(carriers * (carriers - 1) // 2, 1)
    return float(10 * np.log10(0.5 * np.log(len(FAULT_TYPES) * pairs * PEAK_BINS**2 / alpha)))


def _families(d, fit, aside: list | None = None) -> list[dict]:
    """The fault families whose lines the residual of ``fit`` holds (the rule of :func:`fault_evidence`); the lines a
    shaft-synchronous comb takes (:func:`shaft_comb`) do not count, and go to ``aside`` where given."""
    # the envelope view of the residual of ``fit``, judged with the detector's family-wise threshold
    env = EnvelopeBands().judge(fit, d.problem, d.settings).findings
    bands = {"outer_race": ("BPFO",), "inner_race": ("BPFI",), "rolling_element": ("2xBSF", "BSF")}
    bpfo = [c["frequency_Hz"] for c in carrier_levels(d, "outer_race", fit)]
    df = 1.0 / (d.record.n * d.record.dt_s)
    shaft, kin = _fit_kinematics(d, fit)
    out = []
    for kind in FAMILIES:
        levels = carrier_levels(d, kind, fit)
        threshold = lines_threshold_dB(d.settings.test_alpha, len(levels))
        comb = shaft_comb(d, fit, threshold, [f for _, f in family_lines(kind, kin, len(levels))])
        above = [c for c in levels if c["excess_dB"] >= threshold]
        taken = [c for c in above if _near(c["frequency_Hz"], comb, df)]
        hits = [c for c in above if not _near(c["frequency_Hz"], comb, df)]
        # with a comb, an envelope line on a shaft order is the comb's too
        envs = [{"band": e["band"], "frequency_Hz": e["frequency_Hz"], "ratio": e["ratio"]} for e in env
                if (e["band"].split("x")[-1] in bands[kind] or e["band"] in bands[kind])
                and min(abs(e["frequency_Hz"] - f) for f in bpfo) > 2 * df
                and not (comb.size and _near(e["frequency_Hz"], [shaft * max(round(e["frequency_Hz"] / shaft), 1)], df))]
        if aside is not None and taken:
            aside.append({"type": kind, "lines": taken, "comb_orders": [int(round(f / shaft)) for f in comb]})
        if len(hits) >= 2 or (envs and kind != "outer_race"):
            out.append({"type": kind, "lines": hits, "envelope": envs, "threshold_dB": threshold,
                        "strongest_dB": max([h["excess_dB"] for h in hits], default=0.0)})
    out.sort(key=lambda e: -len(e["lines"]))
    return out


#: How near a fault's carrier lies to a line of a shaft-synchronous comb to take that line's level [bins]: the
#: :data:`PEAK_BINS` read around the carrier and a Hann window's main lobe beyond them (a line 1.5 bins off is 15 dB
#: down, 2.5 bins off 32 dB).
COMB_REACH_BINS = 3.0


def _near(f_Hz: float, lines_Hz: np.ndarray, df_Hz: float) -> bool:
    """Whether ``f_Hz`` lies within :data:`COMB_REACH_BINS` bins of one of ``lines_Hz``."""
    return bool(np.size(lines_Hz)) and float(np.min(np.abs(np.asarray(lines_Hz) - f_Hz))) <= COMB_REACH_BINS * df_Hz


def shaft_comb(d, fit, threshold_dB: float, own_Hz: list[float]) -> np.ndarray:
    """The residual's shaft-synchronous comb [Hz]: each shaft order m f_r below :data:`CARRIER_BAND` f_s whose line
    stands alone above ``threshold_dB`` over the white floor (read as :func:`carrier_levels` reads a carrier; alone:
    the half orders m -/+ 1/2 beside it do not stand) with at least two of the orders m-2 .. m+2 standing alone too;
    an order within :data:`COMB_REACH_BINS` of one of the fault's own lines ``own_Hz`` does not count as a neighbour
    (an inner race's sidebands k BPFI -/+ f_r lie a shaft order from its carrier). A moving defect's forest of
    lines k BPFI + j f_r (k x 2 BSF + j FTF) holds the half and quarter orders as well as the whole ones: no comb.

    A source locked to the shaft (a loose part struck once a turn, a rub, an unbalance's harmonics) puts lines at the
    shaft's orders, and a fault's carrier within reach of one of them takes its level: with BPFO = 4.25 f_r, 8 x BPFO
    is 34 f_r, and 7 x BPFO two bins from 30 f_r in a 0.5 s record. A single line at an order (a fault's carrier that
    is one) is not a comb; white noise puts three orders of five above the rule's threshold with a probability of
    order (3 e^-x)^3, x the threshold's power ratio (below 1e-7 at 8.5 dB). An inner-race defect is locked to the
    shaft too: where the rollers meet it once a turn (a narrow load zone), its lines k BPFI + j f_r lie within a bin
    or two of the whole orders in a short record, and its comb is a loose part's (:func:`comb_statement` says so)."""
    shaft, _ = _fit_kinematics(d, fit)
    res_a, df, floor = _residual_spectrum(d, fit)
    orders = np.arange(1, int(CARRIER_BAND / d.record.dt_s // shaft) + 1)

    def stand(order):
        return 10 * np.log10(_peak(res_a, order * shaft, df) ** 2 / floor) >= threshold_dB

    stands = np.array([stand(m) for m in orders])
    alone = stands & np.array([not stand(m - 0.5) and not stand(m + 0.5) for m in orders])
    own = np.array([_near(m * shaft, own_Hz, df) for m in orders], dtype=bool)
    comb = []
    for i, m in enumerate(orders):
        near = [j for j in range(i - 2, i + 3) if j != i and 0 <= j < orders.size]
        if alone[i] and sum(alone[j] and not own[j] for j in near) >= 2:
            comb.append(m * shaft)
    return np.asarray(comb)


def carrier_levels(d, kind: str, fit=None) -> list[dict]:
    """The carriers of a fault family (k x BPFO, k x BPFI, k x 2 x BSF at the fit's speeds, every harmonic below
    :data:`CARRIER_BAND` x the sampling rate) in the residual of ``fit`` (default: the final model's): each
    ``{"line", "frequency_Hz", "excess_dB", "over_model_dB"}``, the residual's line above the white floor (the largest
    of :data:`PEAK_BINS` bins' power of the Hann-windowed spectrum over the floor's in one bin) and over the fitted
    model's own line at that frequency (the line a model without this fault already puts there: at k x BPFO, the
    roller passage's) [dB]. A groove's dip is short: where a healthy model takes up its first harmonics (a load, a
    clearance), its higher ones stay."""
    fit = d.final if fit is None else fit
    mod_a = _line_spectra(d, kind, fit)[3]
    res_a, df, floor = _residual_spectrum(d, fit)
    kin = _fit_kinematics(d, fit)[1]
    base = {"outer_race": kin["bpfo_Hz"], "inner_race": kin["bpfi_Hz"], "rolling_element": 2 * kin["bsf_Hz"]}[kind]
    name = {"outer_race": "BPFO", "inner_race": "BPFI", "rolling_element": "2xBSF"}[kind]
    top = CARRIER_BAND / d.record.dt_s
    carriers = [(name if k == 1 else f"{k}x{name}", k * base) for k in range(1, int(top // base) + 1)]
    out = []
    for label, f in carriers:
        r = _peak(res_a, f, df)
        out.append({"line": label, "frequency_Hz": float(f), "excess_dB": float(10 * np.log10(r**2 / floor)),
                    "over_model_dB": float(20 * np.log10(r / max(_peak(mod_a, f, df), 1e-300)))})
    return out


#: The operating-point effects of the catalogue: what a healthy bearing may differ from its rig file by. The best
#: healthy model (:func:`best_healthy`) adds each of them to the final model.
OPERATING_POINT = ("shaft_speed", "cage_slip", "radial_load", "clearance", "load_share", "roller_scatter")


#: The fault families in the order ties go (the outer race first: a stationary defect, the simplest).
FAMILIES = ("outer_race", "inner_race", "rolling_element")


def best_healthy(d):
    """The best healthy model of the record, the model a fault's lines are judged against (:func:`fault_evidence`).

    The final model (where it selects no defect) with every operating-point effect of the catalogue
    (:data:`OPERATING_POINT`) it lacks added in turn, each from its own starts on the model before it
    (:func:`~piezobearing.diagnosis.selection.add_effect`) and kept where it lowers chi2, whatever its evidence; where
    that model still leaves a family's lines (:func:`_families`) and energy above the floor (:func:`above_floor`: where
    it leaves none, a better fit cannot make its lines a fault's), also the shaft's dynamics (``shaft_dynamics``, from
    the rig file's values). The stepwise search adds an effect only with evidence of its own, and from a far-off
    operating point (half the load, three times the clearance) each alone may explain too little: its final residual
    then holds the roller passage's own lines at k x BPFO, which are a healthy bearing's; and at a light load with a
    wide clearance the shaft rings on its few loaded rollers at every passage, which the quasi-static chain does not
    hold (:func:`~.healthy.dynamic_healthy`). Computed once per diagnosis (kept on it)."""
    cached = getattr(d, "_best_healthy", None)
    if cached is not None:
        return cached
    current = d.final
    if any(e.name in FAULT_TYPES for e in current.model.effects):
        return current
    present = {e.name for e in current.model.effects}
    for name in OPERATING_POINT:
        if name in present or name not in d.problem.catalogue:
            continue
        f = add_effect(current, d.problem.catalogue[name], d.record, d.voltage_V, d.floor, d.settings)
        f.model.release()
        if f.chi2 < current.chi2:
            current = f
    if "shaft_dynamics" not in present and _families(d, current) and above_floor(d, current):
        f = dynamic_healthy(d, current)
        if f.chi2 < current.chi2:
            current = f
    d._best_healthy = current
    return current


def healthy_model_entry(d) -> dict | None:
    """``fault.healthy_model``: the best healthy model the lines were judged against (:func:`best_healthy`), its
    NRMSE and the floor's; None where it was not fitted (a defect selected, or no family's lines left)."""
    f = getattr(d, "_best_healthy", None)
    if f is None:
        return None
    return {"model": f.model.label, "nrmse": f.nrmse, "noise_floor_nrmse": f.floor_nrmse,
            "threshold_dB": {k: lines_threshold_dB(d.settings.test_alpha, len(carrier_levels(d, k, f)))
                             for k in FAMILIES}}


def fault_evidence(d) -> list[dict]:
    """The fault families the record shows beyond its best healthy model, most lines first: ``{"type", "lines",
    "envelope", "threshold_dB", "strongest_dB"}``.

    Judged on the residual of :func:`best_healthy` (the record minus the best model of a healthy bearing the catalogue
    and the shaft's dynamics hold), never on the final model's alone: BPFO is the roller passage's own rate, and what
    a search leaves of a far-off load, clearance or speed stands at its harmonics as a groove's lines do. A family
    counts where at least two of its carriers (k x BPFO, k x BPFI, k x 2 x BSF below 0.45 f_s; :func:`carrier_levels`)
    stand above :func:`lines_threshold_dB` at the engine's test significance (``diagnostics.significance`` / 4: the
    level white noise reaches there with at most that probability), or, for a moving defect, where the envelope view
    of that residual finds one of its bands above the detector's family-wise threshold
    (:class:`~.representations.EnvelopeBands`) more than two bins from every BPFO harmonic (2 x BSF lies within two
    bins of BPFO in a 1 s record of the paper's bearing). How often the rule names a fault on healthy records far
    from the rig file's operating point, and by how much the missed grooves clear it, is measured by
    ``validation/bearing_fault_lines.py`` (docs/validation/bearing_diagnosis.md). Where the final model's own residual
    holds no family's lines, the best healthy model is not fitted. A carrier within reach of a line of a comb at the
    shaft's orders (:func:`shaft_comb`) does not count: ``fault.shaft_comb`` lists those set aside."""
    aside = []
    d._comb_lines = aside  # the lines a shaft-synchronous comb takes: said in the statement, not a fault's
    if any(n in FAULT_TYPES for n in d.selected) or not _families(d, d.final, aside):
        return []  # a defect is selected, or not even the final model leaves a family's lines: nothing to name
    healthy = best_healthy(d)
    aside.clear()
    families = _families(d, healthy, aside)
    if families and not above_floor(d, healthy):
        d._lines_at_floor = families  # lines without energy above the floor: said in the statement, not a fault
        return []
    return families


def above_floor(d, fit) -> bool:
    """Whether the residual of ``fit`` holds energy above the record's white floor: its chi2 (the residual's sum
    of squares over the floor's variance) beyond the chi-square quantile with n - k degrees of freedom at the
    engine's test significance.

    A fault's lines carry energy: a groove the model misses leaves the best healthy model well above the floor
    (8.8-17.3 % NRMSE against 3.3-3.6 % for the missed grooves of docs/validation/bearing_diagnosis.md). A healthy
    bearing seen through a housing mode inside the band leaves a few of the roller passage's own harmonics near the
    mode 10-12 dB above the floor in single bins while the best healthy model is at the floor: lines without energy,
    which a resonance or a narrowband interference makes, not a fault."""
    r = fit.result
    return bool(r.chi2 > chdtri(r.n_data - r.n_free, d.settings.test_alpha))
