"""The running bearing's answer: the ``fault`` entry of ``diagnosis.json``.

The fault found with its size, position and 95 % intervals, the operating conditions, what one record cannot
tell apart (:func:`non_separable`, :func:`separability`), what of the fault's own lines the model leaves
(:func:`fault_lines_left`, :func:`fault_sidebands`), and, where no defect is selected, the fault its lines still
show (:func:`fault_evidence`): never "no fault" where the residual holds a fault family.
"""

from __future__ import annotations

import numpy as np

from ..selection import strength
from .effects import FAULT_TYPES

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


def _line_spectra(d, kind: str) -> tuple[list[tuple[str, float]], float, np.ndarray, np.ndarray, float]:
    """The fault's own lines (:func:`family_lines` at the final fit's speeds), the bin width [Hz], the record's
    and the final model's Hann-windowed amplitude spectra, and the white floor's power in one such bin [V^2]."""
    values, rig = d.final.values, d.record.rig
    shaft = float(values.get("shaft_speed_Hz", rig.shaft_speed_Hz) if rig.tach_Hz is None else np.mean(rig.tach_Hz))
    shaft *= 1.0 + values.get("speed_deviation_ratio", 0.0)
    lines = family_lines(kind, rig.frequencies(shaft, values.get("cage_slip_ratio", 0.0)))
    v = np.asarray(d.voltage_V, dtype=float)
    n = v.size
    w = np.hanning(n)
    rec_a = np.abs(np.fft.rfft((v - v.mean()) * w))
    mod = np.asarray(d.final.model_V, dtype=float)
    mod_a = np.abs(np.fft.rfft((mod - mod.mean()) * w))
    floor = d.problem.floor.voltage_noise_V ** 2 * float(np.sum(w**2))
    return lines, 1.0 / (n * d.record.dt_s), rec_a, mod_a, floor


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
#: A fault's lines name it (where no defect is selected) when at least two of its first three carriers stand this
#: far above the white floor in the final residual's spectrum [dB]. Set between measured values: the largest residual
#: line a healthy record of the dynamic LPM leaves at a roller-pass harmonic against the quasi-static model is
#: 11.5-12.4 dB (docs/validation/bearing_diagnosis.md, 25.6 kHz); a 0.6 mm groove 20 deg from the sensor that the
#: quasi-static search misses leaves 20.6, 30.1 and 26.5 dB at 1-3 x BPFO (1 s at 2550 Hz, 30 dB).
LINES_DB = 20.0


def fault_evidence(d) -> list[dict]:
    """The fault families the final residual still shows, most lines first: ``{"type", "lines", "envelope",
    "strongest_dB"}``.

    A family counts where at least two of its first three carriers (k x BPFO, k x BPFI, k x 2 x BSF) stand
    :data:`LINES_DB` above the white floor in the final residual's Hann-windowed spectrum (one bin's power over the
    floor's), or, for a moving defect, where the envelope view finds one of its bands above the detector's
    family-wise threshold (:class:`~.representations.EnvelopeBands`) at a frequency more than two bins from every
    BPFO harmonic. BPFO is the roller passage's own rate: a healthy bearing whose bumps differ from the model's
    leaves envelope lines there (4.1x the envelope floor on a healthy LPM record at 1500 rpm and 25.6 kHz), and
    2 x BSF lies within two bins of BPFO in a 1 s record of the paper's bearing; so the outer race is named by its
    lines' strength alone, and an envelope line near BPFO names no moving defect. Ties go to the outer race (a
    stationary defect, the simplest)."""
    env = d.judgements.get("envelope", {}).get("final")
    env_found = env.findings if env is not None else []
    bands = {"outer_race": ("BPFO",), "inner_race": ("BPFI",), "rolling_element": ("2xBSF", "BSF")}
    res = np.asarray(d.final.residual_V, dtype=float)
    w = np.hanning(res.size)
    res_a = np.abs(np.fft.rfft((res - res.mean()) * w))
    out = []
    for kind in ("outer_race", "inner_race", "rolling_element"):
        lines, df, _, _, floor = _line_spectra(d, kind)
        bpfo = [f for label, f in _line_spectra(d, "outer_race")[0]]
        carriers = lines[:3] if kind == "outer_race" else lines[0:9:3]
        hits = []
        for label, f in carriers:
            level = float(10 * np.log10(_peak(res_a, f, df) ** 2 / floor))
            if level >= LINES_DB:
                hits.append({"line": label, "frequency_Hz": float(f), "excess_dB": level})
        envs = [{"band": e["band"], "frequency_Hz": e["frequency_Hz"], "ratio": e["ratio"]} for e in env_found
                if (e["band"].split("x")[-1] in bands[kind] or e["band"] in bands[kind])
                and min(abs(e["frequency_Hz"] - f) for f in bpfo) > 2 * df]
        if len(hits) >= 2 or (envs and kind != "outer_race"):
            out.append({"type": kind, "lines": hits, "envelope": envs,
                        "strongest_dB": max([h["excess_dB"] for h in hits], default=0.0)})
    out.sort(key=lambda e: -len(e["lines"]))
    return out
