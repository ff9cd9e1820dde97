"""The running bearing's dynamic rung and the defects a record cannot pin down.

Where the quasi-static diagnosis ends ``unexplained`` with a defect selected or a fault's lines left
(:func:`rung_wanted`), :func:`dynamic_rung` runs the engine once more with ``shaft_dynamics`` and keeps it where it
passes the selection rule; :func:`without_unidentified` runs the engine again without a selected defect whose width
interval holds zero or reaches the catalogue's widest defect, or whose angle interval spans the circle
(:func:`unidentified_defects`), and :func:`without_defects` without one the record cannot tell from the shaft's
dynamics (:func:`indistinct_defects`). Above an accepted dynamic rung that leaves the record ``unexplained``, the
housing mode's rung (:func:`housing_rung_wanted`,
:func:`housing_scan`) runs :func:`dynamic_rung` once more with ``housing_mode``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from ..effect import Catalogue, StartContext
from ..engine import diagnose, refit
from ..fit import fit_model
from ..selection import Candidate, step_entry, strength
from ..subject import Problem
from . import chain
from .answer import EFFECT_OF_TYPE, fault_answer, fault_evidence
from .effects import CATALOGUE, FAULT_TYPES, RUNGS
from .effects.base import MAX_DEFECT_WIDTH_M
from .effects.housing_mode import best_mode
from .effects.shaft_dynamics import DAMPING_BOUNDS, place_groove
from .floor import REMEASURE_BELOW, noise_floor
from .model import BearingModel

#: Width of a defect's 95 % interval in angle beyond which it does not place the defect [rad].
FULL_TURN_RAD = 2 * np.pi


def unidentified_defects(d) -> list[dict]:
    """The defects of the final model the record cannot pin down (:func:`unidentified_reason`), selected or
    configured (a rung's run configures the quasi-static selection); each ``{"effect", "ci95", "reason"}``.
    Operating conditions keep their one-sided intervals (a clearance bounded from below) and are not judged here."""
    ci = d.final.result.ci95
    out = []
    for name in dict.fromkeys([*d.selected, *(e.name for e in d.final.model.effects)]):
        if name not in FAULT_TYPES:
            continue
        reason = unidentified_reason(name, ci)
        if reason:
            _, wkey, pkey = FAULT_TYPES[name]
            out.append({"effect": name, "ci95": {wkey: ci.get(wkey), pkey: ci.get(pkey)}, "reason": reason})
    return out


def unidentified_reason(name: str, ci: dict) -> str | None:
    """Why the 95 % intervals ``ci`` do not place the defect ``name`` (a key of ``FAULT_TYPES``): its width's holds
    zero (or is missing) or reaches the widest defect the catalogue holds (:data:`~.effects.base.MAX_DEFECT_WIDTH_M`:
    the fit runs to its bound, and the record's structure is no defect of the catalogue), or its angle's spans the
    circle (a roller's pit: any spin); None where they place it."""
    _, wkey, pkey = FAULT_TYPES[name]
    w, a = ci.get(wkey), ci.get(pkey)
    if w is None or w[0] is None or not np.all(np.isfinite(w)) or w[0] <= 0.0:
        return f"the interval of {wkey} holds zero"
    if w[1] >= MAX_DEFECT_WIDTH_M:
        return (f"the interval of {wkey} reaches the widest defect the catalogue holds "
                f"({MAX_DEFECT_WIDTH_M * 1e3:g} mm): the fit runs to its bound")
    if name != "rolling_element_defect" and (a is None or a[0] is None or not np.all(np.isfinite(a))
                                             or a[1] - a[0] >= FULL_TURN_RAD):
        return f"the interval of {pkey} spans the circle"
    return None


def without_unidentified(d, problem: Problem, settings, progress=None, rounds: int = 2):
    """The diagnosis again without the defects :func:`unidentified_defects` finds (at most ``rounds`` times);
    returns (diagnosis, problem, [the defects taken out])."""
    dropped: list[dict] = []
    for _ in range(rounds):
        bad = unidentified_defects(d)
        if not bad:
            break
        dropped += bad
        d, problem = without_defects(d, problem, settings, progress, bad)
    return d, problem, dropped


def without_defects(d, problem: Problem, settings, progress, bad: list[dict]):
    """The diagnosis again with the defects of ``bad`` (``{"effect", ...}`` each) out of the catalogue and the
    configured effects; returns (diagnosis, problem)."""
    names = {b["effect"] for b in bad}
    cat = Catalogue("bearing")
    for name, e in problem.catalogue.items():
        if name not in names:
            cat.register(e)
    problem = replace(problem, catalogue=cat, configured=tuple(e for e in problem.configured if e.name not in names))
    (progress or (lambda _m: None))(f"not identified, left out: {', '.join(sorted(names))}")
    return diagnose(problem, settings, progress), problem


def indistinct_defects(d, rung: dict) -> list[dict]:
    """The selected defects the record cannot tell from the shaft's dynamics on a healthy bearing: where a defect did
    not stand against that model (:func:`~.joint.defects_against_dynamics`: its BIC within the selection rule's margin)
    and the rung, tried with the defects held to the rule, was not accepted, neither answer passes the rule against
    the other. Each ``{"effect", "ci95", "reason"}``, as :func:`unidentified_defects`'s; none otherwise."""
    check = rung.get("against_dynamics")
    if not check or check["stands"] or rung["accepted"] or not rung.get("hold_defects"):
        return []
    ci = d.final.result.ci95
    reason = (f"the record cannot tell it from the shaft's dynamics on a healthy bearing ({check['model']}: its BIC "
              f"{check['bic_margin']:+.4g} against the defect's, where the selection rule asks more than "
              f"{check['needed']:.4g}; with the dynamics on, the defect is not accepted either): weigh the shaft and "
              "measure the pedestal's stiffness, and give them in the rig file")
    return [{"effect": n, "ci95": {k: ci.get(k) for k in FAULT_TYPES[n][1:]}, "reason": reason}
            for n in d.selected if n in FAULT_TYPES]


def rung_wanted(d, config: dict) -> dict:
    """Whether the dynamic rung is tried on an ``unexplained`` quasi-static diagnosis, and why (the start of the
    ``dynamic_rung`` entry): with ``bearing_diagnosis.dynamic_rung: auto``, where a defect is selected or the
    residual shows a fault's lines (:func:`fault_evidence`): the shaft's ring after each dip and the deeper
    modulation of a moving defect are what the quasi-static chain leaves there; and where the rig file gives a
    housing mode (``bearing_diagnosis.housing_mode_Hz``: the rung then holds it, :func:`rung_effects`). Other
    structure (a healthy bearing's bumps off by a housing's dynamics the rig file does not give) is not the shaft's,
    and an evaluation of the dynamic chain costs 12-50 times the quasi-static one
    (benchmarks/bench_shaft_dynamics.py), so it is not tried there."""
    mode = config["bearing_diagnosis"].get("dynamic_rung", "auto")
    if mode == "off":
        return {"tried": False, "accepted": False, "why": "bearing_diagnosis.dynamic_rung is off"}
    faults = [n for n in d.selected if n in FAULT_TYPES]
    evidence = fault_evidence(d)
    given = d.problem.record.rig.housing_mode
    if not faults and not evidence and given is not None:
        return {"tried": True, "accepted": False, "evidence": [],
                "why": (f"the rig file gives a housing mode ({given[0]:.5g} Hz): its ring after every roller passage "
                        "is structure the quasi-static chain leaves on any bearing")}
    if not faults and not evidence:
        return {"tried": False, "accepted": False,
                "why": "the quasi-static verdict is unexplained, but no defect is selected and no fault's lines with "
                "energy above the floor are left: the structure is not the shaft's ring on a fault"}
    why = (f"the quasi-static model selects {', '.join(faults)} and leaves structure" if faults else
           f"the residual shows the {evidence[0]['type'].replace('_', ' ')}'s lines and no defect is selected")
    return {"tried": True, "accepted": False, "why": why, "evidence": evidence}


def at_steps(problem: Problem, steps: int | None) -> Problem | None:
    """``problem`` with its rig's dynamic rung at ``steps`` per period of the shaft's mode (a rig of its own: its
    caches hold the other step's forces); None where that is the rig's step already (or ``steps`` is None)."""
    if steps is None or int(steps) == problem.record.rig.steps_per_period:
        return None
    return on_rig(problem, steps_per_period=int(steps))


def own_rig(rig, **changes):
    """``rig`` with ``changes``, a rig of its own: its caches (forces, grids) start empty, since they hold the old
    rig's."""
    return replace(rig, cache={}, grid={}, **changes)


def on_rig(problem: Problem, **changes) -> Problem:
    """``problem`` on a rig of its own with ``changes`` (:func:`own_rig`)."""
    rec = problem.record
    return replace(problem, record=replace(rec, rig=own_rig(rec.rig, **changes)))


def chi2_drop(d, here: float, best: float) -> float:
    """The chi2 a scan's best takes off ``d``'s fit: the misfit ``here`` less the scan's ``best`` (sums of squares,
    means taken out: :func:`~.chain.centred_ss`) over the floor's variance."""
    return float((here - best) / d.floor.voltage_noise_V**2)


def rung_effects(problem: Problem) -> tuple[str, ...]:
    """The effects the dynamic rung adds: ``shaft_dynamics``, and ``housing_mode`` where the rig file gives the mode."""
    return ("shaft_dynamics", "housing_mode") if problem.record.rig.housing_mode is not None else ("shaft_dynamics",)


def dynamic_rung(d, problem: Problem, settings, progress=None, rung: dict | None = None,
                 final_steps: int | None = None, rungs: tuple[str, ...] | None = None,
                 steps: tuple[str, str] = ("quasi-static", "dynamic"), scan_mass: bool = True):
    """The engine once more with the shaft's dynamics (``shaft_dynamics``), judged against the quasi-static diagnosis.

    Configured: the quasi-static selection in its order (their fits start the rung where the quasi-static search
    left them); where no defect is selected, the defect of the fault type whose lines the residual shows most
    (:func:`fault_evidence`), fitted quasi-statically first; then ``shaft_dynamics``, whose starts place an
    outer-race groove with the dynamics on (the pair: a groove the quasi-static chain places a pitch away). Then
    every effect but the quasi-static search's first defect (the pair's defect too) is held to the selection rule
    with the dynamics on
    (:func:`stand_ins`), and the rung runs again without those the record does not support (a load change or a
    second defect the quasi-static search took as a stand-in for the ring). The rung is accepted by the engine's rule
    for one step (:func:`~piezobearing.diagnosis.selection.accepted`: its BIC drop over the quasi-static final
    model above ``min_delta_bic`` and at least ``min_share`` of that model's misfit above the floor explained)
    where none of its defects is unidentified (:func:`unidentified_defects`); the diagnosis returned is then the
    rung's, else the quasi-static one. Returns
    (diagnosis, the ``dynamic_rung`` entry: why, evidence, accepted, the BIC drop and share, the ladder:
    baseline, quasi-static final, with the dynamics, floor NRMSE). ``rung``: :func:`rung_wanted`'s entry.

    The search's runs keep the Jacobian's intervals (``diagnose(..., intervals=False)``): their final models are
    only compared and refitted. Where the rung passes the rule's BIC drop and share, its final model is refitted
    at ``final_steps`` per period of the shaft's mode (``bearing_diagnosis.dynamic_final_steps_per_period``; the
    search's step leaves a bias in a groove's width of the order of its interval) and its honest intervals are
    computed there (:func:`~piezobearing.diagnosis.engine.refit`); the defects are judged identified on those.
    Where it does not pass, its defects are judged on the Jacobian's intervals (the entry's ``unidentified``).

    With ``scan_mass`` (``bearing_diagnosis.shaft_mass_scan: auto``) the rung's first fit is judged against a shaft
    of another mass (:func:`mass_rung`, the entry's ``shaft_mass``).

    ``rungs``: the effects the rung adds (:func:`rung_effects` by default); with one that mimics a defect among
    them (``mimics_defects``: ``housing_mode``, whose ring after each roller passage is a short dip a narrow groove
    under the sensor mimics) the quasi-static search's first defect is held to the selection rule too, as it is where
    ``rung`` says ``hold_defects`` (:func:`~.joint.defects_against_dynamics`). The subject runs this once more with
    ``rungs=("housing_mode",)`` on an accepted rung's diagnosis that is still ``unexplained``; ``steps`` then name
    the models before and after in the entry's ladder.
    """
    rung = dict(rung or rung_wanted(d, {"bearing_diagnosis": {"dynamic_rung": "auto"}}))
    rungs = rungs or rung_effects(problem)
    faults = [n for n in d.selected if n in FAULT_TYPES]
    pair = [] if faults else [EFFECT_OF_TYPE[ev["type"]] for ev in rung.get("evidence", [])[:1]]
    pair = [n for n in pair if n in problem.catalogue]
    names = [*d.selected, *pair]
    add = [CATALOGUE[n] for n in names if CATALOGUE[n] not in problem.configured]
    new = [CATALOGUE[n] for n in rungs if CATALOGUE[n] not in (*problem.configured, *add)]
    rp = replace(problem, configured=(*problem.configured, *add, *new),
                 catalogue=Catalogue("bearing"), profile_evaluations=RUNG_PROFILE_EVALUATIONS)
    note = progress or (lambda _m: None)
    label = " + ".join([*pair, *rungs])
    note(f"{steps[1]} rung: + {label}")
    dr = diagnose(rp, settings, progress, d.baseline, intervals=False)
    if scan_mass and "shaft_dynamics" in rungs and not rp.record.rig.fit_shaft_mass:
        rung["shaft_mass"], dr, rp = mass_rung(d, dr, rp, settings, progress, rungs, steps)
    # the quasi-static selection's other effects, each held to the selection rule with the dynamics on
    exempt = [] if rung.get("hold_defects") or any(CATALOGUE[n].mimics_defects for n in rungs) else faults[:1]
    weak = stand_ins(dr, [n for n in names if n not in exempt and n not in rungs and n not in RUNGS], settings)
    if weak:
        note(f"{steps[1]} rung: without {', '.join(weak)} (not supported with {' and '.join(rungs)})")
        rp = replace(rp, configured=tuple(e for e in rp.configured if e.name not in weak))
        dr = diagnose(rp, settings, progress, d.baseline, intervals=False)
    rung["left_out"] = weak
    drop = d.final.chi2 - dr.final.chi2
    share = float(np.clip(drop / max(d.final.excess, drop, 1e-12), 0.0, 1.0))
    delta_bic = float(d.final.bic - dr.final.bic)
    passes = delta_bic > settings.min_delta_bic and share >= settings.min_share
    if passes:
        dr, rp = final_model(dr, rp, problem, settings, progress, final_steps)
    bad = unidentified_defects(dr)
    ok = passes and not bad
    if (rung.get("shaft_mass") or {}).get("kept"):
        # judged again on the final refit's interval: a mass it does not pin down is not the record's shaft
        fitted = float(dr.final.values["shaft_mass_kg"])
        rung["shaft_mass"].update(fitted_kg=fitted, ci95=dr.final.result.ci95.get("shaft_mass_kg"),
                                  identified=mass_identified(dr, fitted),
                                  alias=alias_masses(dr.record.rig, dr.final.values, fitted))
    rung["steps_per_period"] = {"search": rp.record.rig.steps_per_period, "final": dr.record.rig.steps_per_period}
    rung.update(accepted=bool(ok), unidentified=bad, effects=list(rungs), delta_bic=delta_bic,
                strength=strength(delta_bic), excess_explained=share, **ladder_entry(d, dr, rp, steps), pair=pair)
    return (merged(d, dr, share, pair, rungs) if ok else d), rung


def dynamic_rung_by_type(d, problem: Problem, settings, progress, rung: dict, final_steps: int, scan_mass: bool):
    """:func:`dynamic_rung` where no defect is selected: with the defect of the fault type whose lines the residual
    shows most (``rung["evidence"]``, :func:`fault_evidence`'s order) and, where that rung is not accepted, with
    each next type the residual shows, until one is. Lines a ring of the shaft leaves can outnumber a groove's: a
    shaft of twice the rig file's mass rings at 1.8 kHz, folded to 0.76 kHz at 2550 Hz, where the 11th and 14th
    2 x BSF lines stand above the floor beside the inner-race groove's BPFI (docs/validation/bearing_diagnosis.md).
    The entry of the rung kept (the first accepted, else the first tried) gains ``other_types``: each other type
    tried, with its BIC drop and whether it was accepted. Where a defect is selected, :func:`dynamic_rung` once."""
    evidence = rung.get("evidence") or []
    d1, first = dynamic_rung(d, problem, settings, progress, rung, final_steps, scan_mass=scan_mass)
    if first["accepted"] or len(evidence) < 2 or any(n in FAULT_TYPES for n in d.selected):
        return d1, first
    tried = [first]
    for k in range(1, len(evidence)):
        (progress or (lambda _m: None))(f"dynamic rung: not accepted with the {evidence[k - 1]['type']}'s defect; "
                                        f"again with the {evidence[k]['type']}'s (its lines too are left)")
        dk, entry = dynamic_rung(d, problem, settings, progress, {**rung, "evidence": evidence[k:]}, final_steps,
                                 scan_mass=scan_mass)
        entry["evidence"] = evidence
        tried.append(entry)
        if entry["accepted"]:
            return dk, _with_others(entry, tried, evidence)
    return d1, _with_others(first, tried, evidence)


def _with_others(kept: dict, tried: list[dict], evidence: list[dict]) -> dict:
    """``kept`` with ``other_types``: the type, BIC drop and acceptance of every other rung of ``tried``."""
    return {**kept, "other_types": [{"type": ev["type"], "delta_bic": e["delta_bic"], "accepted": e["accepted"]}
                                     for ev, e in zip(evidence[:len(tried)], tried, strict=True) if e is not kept]}


#: The dynamic rung's scan of the shaft's mass, coarse then fine: the rig file's mass times 2^(k/8) for |k| <= 16
#: (a quarter to four times it, steps of 9 %, 4.4 % in the mode's frequency: a ring of a few periods keeps its phase
#: within a radian), then 2^(j/64) for |j| <= 4 around the best (steps of 1.1 %); the fit with the mass free takes it
#: from there.
MASS_SCAN_COARSE = 2.0 ** (np.arange(-16, 17) / 8)
MASS_SCAN_FINE = 2.0 ** (np.arange(-4, 5) / 64)
#: The scan runs on the record's first this many seconds [s]: 35 roller passages of the paper's bearing at 1000 rpm,
#: each ringing the shaft; its cost is then the same on a 2 s record as on a 0.5 s one.
MASS_SCAN_S = 0.5


def mass_scan(d, settings) -> dict:
    """The dynamic rung's scan of the shaft's mass on ``d``'s final model (the rung's search at the rig file's mass,
    held where its mode lies above the record's Nyquist frequency): the chain's voltage at each mass of
    :data:`MASS_SCAN_COARSE`, then :data:`MASS_SCAN_FINE` around the best, every other value as fitted, and the
    chi2 the best mass takes off the fitted model's (the residual's sum of squares over the floor's variance, means
    taken out; every mass at the fitted damping and at the rig file's, which a fit at the wrong mass may have
    raised to damp a ring it cannot match) against
    what the selection rule asks of one parameter, ``min_delta_bic`` + ln n. A shaft heavier or lighter than the rig
    file's rings at another frequency, whose alias a box-averaging DAQ passes (for 2 kg on the paper's rig at
    2550 Hz: 1.8 kHz, at 0.7 kHz a third as strong): ``tried`` where the scan takes off more than the rule asks,
    and the rung then runs again from that mass with the mass fitted (:func:`with_shaft_mass`).

    With an outer-race groove in the model, each coarse mass also places the groove anew
    (:func:`~.effects.shaft_dynamics.place_groove`): a groove 20-26 deg from the sensor, whose sensor force its ring
    dominates, is placed a roller pitch away by a fit at the wrong mass, and the scan at that place would not see the
    right mass. The scan runs on the record's first :data:`MASS_SCAN_S` (:func:`window`): two evaluations of the
    dynamic chain per mass, about a dozen with a groove to place, 75-430 in all."""
    values = dict(d.final.values)
    if d.record.rig.dynamics is None or values.get("shaft_mass_kg", 0.0) <= 0:
        return {"tried": False, "kept": False, "why": "not scanned: the model holds no shaft dynamics"}
    m0 = float(values["shaft_mass_kg"])
    # what the model adds to the chain's (an interference's), then the record's first MASS_SCAN_S
    other = d.final.model_V - chain.voltage(d.record.rig, values)
    record, n = window(d.record, MASS_SCAN_S)
    rig = record.rig
    v = (np.asarray(d.voltage_V, dtype=float) - other)[:n]
    groove = values.get("outer_defect_width_m", 0.0) > 0

    # the rig file's damping at every mass: a fit at the wrong mass damps the ring it cannot match
    c0 = float(np.clip(rig.dynamics.bearing_damping_N_s_per_m, *DAMPING_BOUNDS))

    def at(m: float, place: bool, start: dict = values, damping: float = c0) -> tuple[float, dict]:
        """The least misfit at mass ``m`` and ``damping``: the values ``start``, or the groove placed anew."""
        vals = {**start, "shaft_mass_kg": float(m), "bearing_damping_N_s_per_m": damping}
        best = (chain.misfit(rig, v, vals), vals)
        if place:
            ctx = StartContext(record, v, d.final.model_V[:n], vals)
            for t in place_groove(ctx, {"shaft_mass_kg": float(m), "bearing_damping_N_s_per_m": damping}):
                e = chain.misfit(rig, v, {**vals, **t})
                if e < best[0]:
                    best = (e, {**vals, **t})
        return best

    fitted = float(values["bearing_damping_N_s_per_m"])
    coarse = [min(at(m, groove), at(m, False, values, fitted), key=lambda x: x[0]) for m in m0 * MASS_SCAN_COARSE]
    k = int(np.argmin([e for e, _ in coarse]))
    base = coarse[k][1]
    fine = [at(m, False, base, base["bearing_damping_N_s_per_m"]) if r != 1.0 else coarse[k] for m, r in
            zip(base["shaft_mass_kg"] * MASS_SCAN_FINE, MASS_SCAN_FINE, strict=True)]
    j = int(np.argmin([e for e, _ in fine]))
    best, start = fine[j][0], fine[j][1]
    drop = chi2_drop(d, chain.misfit(rig, v, values), best)
    needed = float(settings.min_delta_bic + np.log(v.size))
    m = float(start["shaft_mass_kg"])
    placed = groove and abs(start["outer_defect_angle_rad"] - values["outer_defect_angle_rad"]) > 0
    said = (f"the scan's best shaft mass, {m:.3g} kg against the rig file's {m0:.3g} kg"
            + (f" (the groove placed anew at {start['outer_defect_angle_rad']:.3f} rad)" if placed else "")
            + f", takes {drop:.4g} off chi2, where the selection rule asks of one parameter more than {needed:.4g}")
    tried = bool(drop > needed)
    return {"tried": tried, "kept": False, "rig_kg": m0, "start_kg": m, "chi2_drop": drop, "needed": needed,
            "start": {k: float(x) for k, x in start.items() if k.startswith("outer_defect_")},
            "why": said if tried else f"not fitted: {said}"}


def window(record, seconds: float):
    """The record's first ``seconds`` (all of it where shorter) as a record of its own, on a rig of its own: (record,
    its number of samples). The chain on it is the chain on the whole record, cut (the same start phase, speed and
    pre-roll)."""
    n = min(record.n, max(2, int(round(seconds / record.dt_s))))
    if n == record.n:
        return record, n
    rig = record.rig
    sub = own_rig(rig, time_s=rig.time_s[:n], tach_Hz=None if rig.tach_Hz is None else rig.tach_Hz[:n])
    return replace(record, time_s=record.time_s[:n], rig=sub, _cache={},
                   input=None if record.input is None else record.input[:n],
                   filled=None if record.filled is None else record.filled[:n]), n


def alias_masses(rig, values: dict, mass_kg: float) -> dict | None:
    """Where the shaft's mode at ``mass_kg`` (at the operating point of ``values``) lies above the record's Nyquist
    frequency, the record sees it only through its alias: the mode, the frequency it folds to, and the other masses
    of the scan's range (:data:`MASS_SCAN_COARSE` times the rig file's) whose modes fold to the same frequency,
    {"mode_Hz", "alias_Hz", "masses_kg"}; None where the mode lies below Nyquist. Only the box average's
    attenuation and the ring's decay tell those masses apart: on the paper's rig at 2550 Hz a shaft of 0.5 kg
    (3.7 kHz) and one of 3 kg (1.5 kHz) ring at about the same alias."""
    op = chain.operating(rig, values)

    def mode(m: float) -> float:
        return chain.shaft_mode_Hz(rig, chain.dynamics_of(rig, {**values, "shaft_mass_kg": m}), op)[0]

    fs = 1.0 / rig.dt_s
    f = mode(mass_kg)
    if f < 0.5 * fs:
        return None
    fa = abs(f - fs * round(f / fs))
    lo, hi = rig.dynamics.shaft_mass_kg * MASS_SCAN_COARSE[[0, -1]]
    f_lo, f_hi = mode(hi), mode(lo)  # the heavier shaft rings lower
    targets = {k * fs + sign * fa for k in range(int(f_hi // fs) + 2) for sign in (-1, 1)}
    masses = sorted(float(brentq(lambda m, ft=ft: mode(m) - ft, lo, hi, rtol=1e-10)) for ft in targets
                    if f_lo < ft < f_hi and abs(ft - f) > 1e-6 * f)
    return {"mode_Hz": float(f), "alias_Hz": float(fa), "masses_kg": masses}


def mass_identified(d, mass_kg: float) -> bool:
    """Whether ``d``'s fit pins the shaft's mass down: its 95 % interval is finite, above zero and narrower than the
    mass itself (a fit that drives the mass to zero has dropped the dynamics, not found a shaft)."""
    ci = d.final.result.ci95.get("shaft_mass_kg")
    return bool(ci is not None and ci[0] is not None and np.all(np.isfinite(ci)) and ci[0] > 0
                and ci[1] - ci[0] < mass_kg)


def with_shaft_mass(problem: Problem, mass_kg: float) -> Problem:
    """``problem`` on a rig whose shaft's mass is ``mass_kg`` (the start of ``shaft_mass_kg``), fitted wherever its
    mode lies (``Rig.fit_shaft_mass``); a rig of its own (its caches hold the other mass's forces). The rung's search
    on it places an outer-race groove anew at that mass (``shaft_dynamics``' starts)."""
    dynamics = replace(problem.record.rig.dynamics, shaft_mass_kg=float(mass_kg))
    return on_rig(problem, dynamics=dynamics, fit_shaft_mass=True)


def on_record_shaft(problem: Problem, rung: dict) -> Problem:
    """``problem`` on the shaft the accepted dynamic rung found (``rung["shaft_mass"]`` kept and identified:
    :func:`with_shaft_mass`), so that the rungs above it (the housing mode's, the joint search) run on the record's
    shaft, not the rig file's; else ``problem``."""
    mass = rung.get("shaft_mass") or {}
    if rung.get("accepted") and mass.get("kept") and mass.get("identified"):
        return with_shaft_mass(problem, mass["fitted_kg"])
    return problem


def mass_rung(d, dr, rp: Problem, settings, progress, rungs: tuple[str, ...], steps: tuple[str, str]):
    """The rung's search ``dr`` (of ``rp``, at the rig file's mass) judged against a shaft of another mass: the scan
    (:func:`mass_scan`); where it is tried and takes more off chi2 than the housing mode's scan on the same window
    (a mode in the band rings after every event as a shaft of another mass does; ``rungs`` without
    ``housing_mode``), the search again from the scan's mass with the mass fitted (:func:`with_shaft_mass`), kept
    where its BIC is lower by ``min_delta_bic`` and its mass identified (:func:`mass_identified`). Returns (the
    ``shaft_mass`` entry, the search kept, its problem)."""
    entry = mass_scan(dr, settings)
    if entry["tried"] and "housing_mode" not in rungs:
        wr, n = window(dr.record, MASS_SCAN_S)  # both scans on the same window of the record
        mode, left = best_mode(StartContext(wr, dr.voltage_V[:n], dr.final.model_V[:n], dr.final.values))
        r = np.asarray(dr.voltage_V[:n], dtype=float) - dr.final.model_V[:n]
        mode_drop = chi2_drop(dr, chain.centred_ss(r), left)
        entry["housing_mode_chi2_drop"] = mode_drop
        if mode_drop > entry["chi2_drop"]:
            entry.update(tried=False, why=f"not fitted: {entry['why']}; the housing mode's scan takes more "
                         f"({mode_drop:.4g}, {mode['housing_mode_Hz']:.5g} Hz): the ring is left to the housing mode's rung")
    if not entry["tried"]:
        return entry, dr, rp
    (progress or (lambda _m: None))(f"{steps[1]} rung: again from the scan's shaft mass, {entry['start_kg']:.3g} kg, "
                                    "the mass fitted")
    mp = with_shaft_mass(rp, entry["start_kg"])
    dm = diagnose(mp, settings, progress, d.baseline, intervals=False)
    fitted = float(dm.final.values["shaft_mass_kg"])
    entry.update(delta_bic=float(dr.final.bic - dm.final.bic), search_kg=fitted, identified=mass_identified(dm, fitted))
    entry["kept"] = bool(entry["delta_bic"] > settings.min_delta_bic and entry["identified"])
    return (entry, dm, mp) if entry["kept"] else (entry, dr, rp)


def ladder_entry(d, dr, rp: Problem, steps: tuple[str, str]) -> dict:
    """The rung entry's models: ``before`` (``d``'s) and ``after`` (the rung's ``dr``, of ``rp``), their ladder
    (baseline, before, after, floor NRMSE) named by ``steps``; the first rung's also as ``quasi_static`` and
    ``dynamic``."""
    before = {"selected": list(d.selected), "verdict": d.verdict, "nrmse": d.final.nrmse,
              "fault": fault_answer(d)["statement"]}
    after = {"selected": list(dr.selected), "configured": [e.name for e in rp.configured],
             "verdict": dr.verdict, "nrmse": dr.final.nrmse}
    out = {"before": before, "after": after, "ladder": [
        {"model": "baseline", "nrmse": d.baseline.nrmse},
        {"model": f"{steps[0]}: " + d.final.model.label, "nrmse": d.final.nrmse},
        {"model": f"{steps[1]}: " + dr.final.model.label, "nrmse": dr.final.nrmse},
        {"model": "noise floor", "nrmse": dr.final.floor_nrmse},
    ]}
    if steps == ("quasi-static", "dynamic"):
        out.update(quasi_static=before, dynamic=after)
    return out


def final_model(dr, rp: Problem, problem: Problem, settings, progress, final_steps: int | None):
    """The rung's diagnosis ``dr`` (of ``rp``, without intervals) that passed the rule, made final: run again with
    the floor measured on its residual where the quasi-static model's lines had lifted it (as the quasi-static
    diagnosis does), then refitted at ``final_steps`` per period of the shaft's mode with its honest intervals
    (:func:`at_steps`, :func:`~piezobearing.diagnosis.engine.refit`). Returns (diagnosis, the problem it ran on
    before the refit)."""
    note = progress or (lambda _m: None)
    if dr.final.nrmse < REMEASURE_BELOW * dr.final.floor_nrmse:
        qm = problem.floor.quiet_mask
        fl = noise_floor(dr.final.residual_V, problem.record.dt_s, None if qm is None else ~qm)
        fl = replace(fl, method=f"{fl.method}, of the dynamic rung's final residual: the floor before "
                     f"({problem.floor.voltage_noise_V:.4g} V) was lifted by the fault's lines")
        note("dynamic rung: floor measured again")
        rp = replace(rp, floor=fl)
        dr = diagnose(rp, settings, progress, intervals=False)
    fine = at_steps(rp, final_steps)
    if fine is not None:
        note(f"dynamic rung: final model at {fine.record.rig.steps_per_period} steps per period of the shaft's mode")
        rp.record.rig.grid.clear()
    return refit(dr, fine, progress), rp


def stand_ins(dr, names: list[str], settings) -> list[str]:
    """Which of ``names`` (effects of ``dr``'s final model) the record does not support with the dynamics on: the
    final model refitted without each (from the final values), and the effect kept only where adding it back passes
    the engine's rule (:func:`~piezobearing.diagnosis.selection.accepted`: BIC drop above ``min_delta_bic``, at
    least ``min_share`` of the misfit explained). A quasi-static fit takes a load change or a second defect as a
    stand-in for the ring it cannot model; an operating condition it found (a clearance) keeps its evidence."""
    final, out = dr.final, []
    for n in names:
        effects = tuple(e for e in final.model.effects if e.name != n)
        if len(effects) == len(final.model.effects):
            continue
        own = {p.name for e in final.model.effects if e.name == n for p in e.params(dr.record)}
        f = fit_model(BearingModel(effects), dr.record, dr.voltage_V, dr.floor,
                      start={k: v for k, v in final.values.items() if k not in own},
                      max_nfev=settings.max_nfev, ftol=settings.ftol)
        drop = f.chi2 - final.chi2
        share = float(np.clip(drop / max(f.excess, drop, 1e-12), 0.0, 1.0))
        if not (f.bic - final.bic > settings.min_delta_bic and share >= settings.min_share):
            out.append(n)
    return out


def merged(d, dr, share: float, pair: list[str], rungs: tuple[str, ...] = ("shaft_dynamics",)):
    """The rung's diagnosis ``dr`` read as steps after the quasi-static one ``d``: the quasi-static ladder, then
    ``shaft_dynamics`` added (its fit with the quasi-static selection, its evidence over the quasi-static final
    model), then the rung's own search; ``selected`` the quasi-static selection, ``shaft_dynamics`` and the rung's
    additions; the configured model (and its tests) the user's."""
    rung_fit = dr.configured
    present = {e.name for e in dr.final.model.effects}
    pair = [n for n in pair if n in present]
    c = Candidate(CATALOGUE[rungs[-1]], rung_fit, float(d.final.bic - rung_fit.bic), share)
    dr.steps = [*d.steps, step_entry(rung_fit, " + ".join([*pair, *rungs]), c), *dr.steps[1:]]
    dr.fits = [*d.fits, rung_fit, *dr.fits[1:]]
    dr.selected = list(dict.fromkeys(n for n in [*d.selected, *pair, *rungs, *dr.selected] if n in present))
    dr.configured = d.configured
    dr.tests = {**dr.tests, "configured": d.tests["configured"]}
    dr.ranking = d.ranking
    dr.problem = replace(dr.problem, catalogue=d.problem.catalogue)
    return dr


#: Most evaluations of the dynamic chain the rung's interval checks and profiles may spend (the engine's 600 would
#: cost 1.5-2 CPU minutes on a 2 s record at 2550 Hz, 0.15-0.2 s each; intervals beyond it keep the Jacobian's,
#: flagged in ``ci_method``).
RUNG_PROFILE_EVALUATIONS = 120


def housing_rung_wanted(d, rung: dict) -> bool:
    """Whether the housing mode's rung is tried on the dynamic rung's diagnosis ``d``: the rung was accepted without
    ``housing_mode`` (the rig file gives no mode) and the verdict is still ``unexplained``. A housing's mode below the
    record's Nyquist frequency leaves a ring with the shaft's dynamics on; the rung scans for it
    (:func:`~.effects.housing_mode.best_mode`) and keeps it where it passes the selection rule."""
    return bool(rung.get("accepted")) and d.verdict == "unexplained" and "housing_mode" not in d.selected


def housing_scan(d, settings) -> dict:
    """The housing mode's rung entry before its fit: the scan's best mode on ``d``'s final model
    (:func:`~.effects.housing_mode.best_mode`) and the chi2 it takes off (the residual's sum of squares over the
    floor's variance, both means taken out), against what the selection rule asks of the mode's parameters,
    ``min_delta_bic`` + k ln n. The rung is tried (``tried``) only where the scan's start already takes off more: a
    start that does not is not worth a fit of the dynamic chain (10-30 s of CPU on a 2 s record)."""
    e = CATALOGUE["housing_mode"]
    ctx = StartContext(d.record, d.voltage_V, d.final.model_V, d.final.values)
    start, best = best_mode(ctx)
    r = np.asarray(d.voltage_V, dtype=float) - d.final.model_V
    drop = chi2_drop(d, chain.centred_ss(r), best)
    k = sum(p.vary for p in e.params(d.record))
    needed = float(settings.min_delta_bic + k * np.log(r.size))
    scan = {"start": start, "chi2_drop": drop, "needed": needed}
    mode = f"{start['housing_mode_Hz']:.5g} Hz at {100 * start['housing_mode_damping_ratio']:.3g} %"
    said = f"the scan's best mode ({mode}) changes chi2 by {-drop:+.4g}, where the selection rule asks of its {k} " \
           f"parameters a drop over {needed:.4g}"
    if drop > needed:
        return {"tried": True, "accepted": False, "evidence": [], "scan": scan,
                "why": f"the dynamic rung was accepted and the record is still unexplained; {said}"}
    return {"tried": False, "accepted": False, "scan": scan,
            "why": f"the dynamic rung was accepted and the record is still unexplained, but {said}: no housing mode "
                   "in the band"}
