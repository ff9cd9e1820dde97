"""The joint dynamic search: the operating point and the defect found together, with the shaft's dynamics on.

Where the quasi-static chain cannot hold a record (a light load in a wide clearance: the shaft rings on its few
loaded rollers after every defect edge), its stepwise search takes operating-point effects as stand-ins for the
groove's dynamics, its residual lifts the floor the evidence is measured against, and the defect it picks (if any)
is a matter of chance (docs/validation/bearing_diagnosis.md, "Every record ends with a verdict"). :func:`joint_search`
fits instead, with ``shaft_dynamics`` on:

1. the dynamic healthy model: the quasi-static final model without its defects, with the load, the clearance and the
   load share (those it lacks added) and the shaft's dynamics at the rig file's mass and damping, fitted from its own
   values, from the best points of a (clearance, load) grid (:data:`~.healthy.HEALTHY_GRID`, each point's misfit of
   the dynamic chain with the load share at its least-squares value) and from the best end of a few steps' fits of
   the grid's next points (:func:`~.healthy.fit_from_grid`, as the lines rule's dynamic healthy model);
2. for each fault type (:data:`~.effects.FAULT_TYPES`): the defect's own starts (its angles one roller pitch apart,
   scanned with a trial width, :meth:`~piezobearing.diagnosis.effect.Effect.starts`) at each of the grid's
   :data:`SCREEN_POINTS` best points and at the healthy fit, each start's misfit of the dynamic chain evaluated (the
   screen), and the type's model fitted from the :data:`~.healthy.HEALTHY_STARTS` best;
3. the floor measured again (:func:`~.floor.noise_floor`) on the residual of the best of those fits, where it is
   below the floor the search ran with (the groove's own lines and rings lift the floor measured on the record or on
   a quasi-static residual by 1.8-6.6 sigma on the feasibility draws' inner grooves);
4. the types ranked by their BIC on that floor; the best accepted where it passes the engine's selection rule over
   the dynamic healthy model (:func:`~piezobearing.diagnosis.selection.accepted`) and is identified (its width's
   95 % interval excludes zero and stays under the catalogue's widest defect, its angle's does not span the
   circle, :func:`.rung.unidentified_reason`).

The floor is white (``NoiseFloor.input_noise`` 0 for a voltage record): a fit's values do not depend on its level,
and a chi2 on the floor measured again is the fit's chi2 times the ratio of the variances.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...fitting.least_squares import InfeasibleError
from ..effect import StartContext
from ..engine import refit
from ..fit import ModelFit, fit_model
from ..selection import Candidate, accepted, step_entry, strength
from .effects import CATALOGUE, FAULT_TYPES
from .effects.outer_race_defect import TRIAL_WIDTH_M
from .effects.shaft_dynamics import LaggedMatch
from .floor import noise_floor
from .healthy import (
    HEALTHY_GRID,
    HEALTHY_SCREEN,
    HEALTHY_STARTS,
    fit_from_grid,
    grid_points,
    healthy_start_values,
    share_misfit,
)
from .model import BearingModel
from .representations import fitted_kinematics
from .rung import RUNG_PROFILE_EVALUATIONS, unidentified_defects, unidentified_reason

#: The grid points (of :data:`~.healthy.HEALTHY_GRID`'s 30, best first by the dynamic healthy chain's misfit) each
#: defect's starts are scanned at, besides the dynamic healthy fit's own point. A cost choice: each point costs
#: one scan of the defect's Z angles per type (33 evaluations of the dynamic chain for the paper's 11 rollers).
SCREEN_POINTS = 3

#: The operating point the dynamic healthy model frees (where the quasi-static final model lacks them).
OPERATING = ("radial_load", "clearance", "load_share")


def healthy_model(qs: ModelFit) -> BearingModel:
    """The quasi-static final model ``qs`` without its defects, with :data:`OPERATING` and ``shaft_dynamics``."""
    model = BearingModel(tuple(e for e in qs.model.effects if e.name not in FAULT_TYPES))
    for name in (*OPERATING, "shaft_dynamics"):
        if name not in model.names:
            model = model.with_effect(CATALOGUE[name])
    return model


#: The defects of an ``explained`` record are held against a healthy bearing with the shaft's dynamics
#: (:func:`defects_against_dynamics`) only where the quasi-static model before the search's first defect leaves less
#: than this many times the floor's NRMSE: a defect whose whole signature is of the size of the noise, as the
#: structure a rig's shaft or pedestal other than the rig file's leaves on a healthy bearing (a pedestal of half the
#: stiffness at 25.6 kHz: 0.98 times the floor before a false 0.40 mm groove). A cost choice: the check is a fit of
#: the dynamic chain (0.8 s of CPU on that record, 39 s on the paper's 2 s record, whose groove leaves 5.3 times the
#: floor before it is selected and stands by a BIC of 1.2e5).
NEAR_FLOOR = 2.0


def defects_against_dynamics(d, config: dict) -> dict:
    """The start of the ``dynamic_rung`` entry of a quasi-static diagnosis ``d`` that ends ``explained``: whether its
    defects stand against a healthy bearing with the shaft's dynamics.

    A defect the quasi-static search selects may stand in for the dynamics of a healthy bearing whose shaft or
    pedestal is not the rig file's (a pedestal of half the stiffness, at 25.6 kHz: a 0.40 mm groove 23 deg from the
    sensor, ``explained``; docs/validation/bearing_diagnosis.md). The dynamic healthy model (:func:`healthy_model`:
    the final model without its defects, with the operating point and ``shaft_dynamics``) is fitted once from the
    final model's values and the rig file's shaft (one start), where the quasi-static model before the search's
    first defect leaves less than :data:`NEAR_FLOOR` times the floor.
    The defects stand where the final model's BIC is lower than that model's by more than ``min_delta_bic`` (the
    rule an effect passes to be selected); otherwise the dynamic rung is tried with every defect held to the rule
    with the dynamics on (``hold_defects``: :func:`~.rung.dynamic_rung`). With ``bearing_diagnosis.dynamic_rung:
    off``, without a defect the search selected (a configured one is the user's), or on a rig without the shaft's
    dynamics, nothing is fitted."""
    explained = {"tried": False, "accepted": False, "why": "the quasi-static verdict is explained"}
    faults = [n for n in d.selected if n in FAULT_TYPES]
    if not faults or config["bearing_diagnosis"].get("dynamic_rung", "auto") == "off" or d.record.rig.dynamics is None:
        return explained
    first = next((i for i, st in enumerate(d.steps) if st.get("added") in FAULT_TYPES), 0)
    before = d.steps[first - 1] if first > 0 else None
    if before is None or before["nrmse"] >= NEAR_FLOOR * before["noise_floor_nrmse"]:
        return explained  # a configured defect, or one whose signature is larger than the dynamics leave
    rec, v, qs = d.record, np.asarray(d.voltage_V, dtype=float), d.final
    model = healthy_model(qs)
    base, _ = healthy_start_values(model, qs, rec, v)
    f = fit_model(model, rec, v, d.floor, start=base, starts=[{}], max_nfev=d.settings.max_nfev, ftol=d.settings.ftol)
    f.model.release()
    margin, needed = float(f.bic - qs.bic), float(d.settings.min_delta_bic)
    check = {"model": f.model.label, "nrmse": f.nrmse, "bic": f.bic, "defects_bic": qs.bic, "bic_margin": margin,
             "needed": needed, "stands": margin > needed}
    said = (f"the healthy bearing with the shaft's dynamics ({f.model.label}; NRMSE {100 * f.nrmse:.3g} %) has a BIC "
            f"{margin:+.4g} above the quasi-static model with {', '.join(faults)}, where the selection rule asks more "
            f"than {needed:.4g}")
    if check["stands"]:
        return {**explained, "why": f"the quasi-static verdict is explained, and {said}", "against_dynamics": check}
    return {"tried": True, "accepted": False, "evidence": [], "hold_defects": True, "against_dynamics": check,
            "why": f"the quasi-static verdict is explained, but {said}: each defect is held to the rule with the "
                   "shaft's dynamics on"}


def screen(effect, model: BearingModel, base: dict, points: list[dict], rec, v: np.ndarray) -> list[tuple[float, dict]]:
    """The defect's starts at each operating point of ``points``, each with the misfit of ``model`` (healthy + the
    defect) at it, best first. A groove (outer or inner race) is placed by :func:`place` (its events
    cross-correlated with the healthy dynamic chain's residual) besides its own starts
    (:meth:`~piezobearing.diagnosis.effect.Effect.starts`: its angles one pitch apart scanned), a roller's pit by
    its own starts."""
    vc = v - v.mean()
    healthy = BearingModel(tuple(e for e in model.effects if e.name != effect.name))
    out = []
    for pt in points:
        vals = {**base, **pt}
        try:
            mv = healthy.simulate(vals, rec)
        except InfeasibleError:
            continue
        starts = effect.starts(StartContext(rec, v, mv, vals))
        if effect.name in PLACED:
            starts = [*starts, *place(effect.name, model, vals, mv, rec, v)]
        for s in starts:
            trial = {**vals, **s}
            try:
                m = model.simulate(trial, rec)
            except InfeasibleError:
                continue
            e, share = share_misfit(vc, m)
            out.append((e, {**pt, **s, "load_share_ratio": vals.get("load_share_ratio", 1.0) * share}))
    out.sort(key=lambda x: x[0])
    return out


#: The grooves :func:`place` places, with their angle's key.
PLACED = {"outer_race_defect": "outer_defect_angle_rad", "inner_race_defect": "inner_defect_angle_rad"}
#: Starts :func:`place` returns per operating point.
PLACE_KEEP = 3


def place(name: str, model: BearingModel, values: dict, healthy_V: np.ndarray, rec, v: np.ndarray) -> list[dict]:
    """Starts of a groove of effect ``name`` with the dynamics on, found by cross-correlation.

    The dynamic chain with a groove of :data:`~.effects.outer_race_defect.TRIAL_WIDTH_M` at each angle a_k = k x pitch
    (an outer groove: those within the load zone, +-100 deg of the sensor) less the healthy chain ``healthy_V`` is one
    event per meeting of the groove and a roller, its dip and the shaft's ring. A groove dth further on meets the
    rollers dth / omega later (omega: the cage's angular speed for the stationary outer race, the shaft's less the
    cage's, negated, for the inner race turning with the shaft): the residual ``v - healthy_V`` is cross-correlated
    with each a_k's events at lags within half a roller pitch, resolved to 1/:data:`~.effects.shaft_dynamics.UPSAMPLE` of a sample (:class:`~.effects.shaft_dynamics.LaggedMatch`; the misfit
    of an inner groove rises from 1.0 to 3.3 times its least 0.05 rad off its angle: a fold of the residual over the
    roller-to-groove angle does not place it finely enough). Each a_k's best lag with a positive amplitude gives an
    angle and a width (the dip grows about as the width squared); the :data:`PLACE_KEEP` that explain most of the
    residual are returned."""
    rig = rec.rig
    key = PLACED[name]
    wkey = key.replace("angle_rad", "width_m")
    pitch = rig.pitch_rad
    kin = fitted_kinematics(values, rec)
    omega_c = 2 * np.pi * kin["frequencies"]["ftf_Hz"]
    omega = omega_c if name == "outer_race_defect" else -(2 * np.pi * kin["shaft_Hz"] - omega_c)
    match = LaggedMatch(v - healthy_V, rec.dt_s, omega, pitch)
    scored = []
    for k in range(rig.geometry.n_rollers):
        ak = float(np.angle(np.exp(1j * k * pitch)))
        if name == "outer_race_defect" and abs(ak) > np.radians(100.0):
            continue
        try:
            dv = model.simulate({**values, key: ak, wkey: TRIAL_WIDTH_M}, rec) - healthy_V
        except InfeasibleError:
            continue
        best = match(dv)
        if best is None:
            continue
        lag, amp, energy = best
        if amp > 0:
            angle = float(np.angle(np.exp(1j * (ak + lag * omega))))
            scored.append((amp * amp * energy, {key: angle, wkey: float(np.clip(TRIAL_WIDTH_M * np.sqrt(amp),
                                                                                  0.05e-3, 2.9e-3))}))
    scored.sort(key=lambda x: -x[0])
    return [t for _, t in scored[:PLACE_KEEP]]


def healthy_start(f: ModelFit, model: BearingModel, rec) -> dict:
    """The values of the healthy ``model`` at a type's fit ``f``: its operating point, the cage at the same speed
    (a cage slip the healthy model lacks folded into the shaft's speed: the roller passage sees only the cage)."""
    keys = model.defaults(rec)
    vals = {k: x for k, x in f.values.items() if k in keys}
    slip = f.values.get("cage_slip_ratio", 0.0)
    if "cage_slip_ratio" not in keys and slip and "speed_deviation_ratio" in keys:
        vals["speed_deviation_ratio"] = (1 + f.values.get("speed_deviation_ratio", 0.0)) * (1 - slip) - 1
    return vals


def kinematics(name: str, model: BearingModel, values: dict) -> list[dict]:
    """The kinematic starts of a defect of type ``name`` on ``model`` at its healthy fit's ``values``: the fit's
    own, and, for a defect that turns with the shaft or spins with a roller (inner race, roller) where the fit holds
    the shaft's speed below the rig file's (``shaft_speed``) and no cage slip, the shaft at the rig file's speed
    with the cage slipping as much (the same cage speed: the roller passage cannot tell them apart, an inner
    groove's passage at BPFI = Z (f_r - FTF) can). A record with a 2.4 % slip whose healthy fit takes the shaft
    2.4 % slow turns an inner groove 1.2 rad off its place over a 0.5 s record at 1000 rpm."""
    dev = values.get("speed_deviation_ratio")
    if name == "outer_race_defect" or "cage_slip" in model.names or dev is None or dev >= 0:
        return [{}]
    lo, hi = next((p.lower, p.upper) for p in CATALOGUE["cage_slip"].params(None))
    if -dev > hi:
        return [{}]
    return [{"cage_slip_ratio": 0.0}, {"speed_deviation_ratio": 0.0, "cage_slip_ratio": float(-dev)}]


def _rescaled(f: ModelFit, ratio: float) -> tuple[float, float]:
    """(chi2, BIC) of ``f`` on a white floor whose variance is ``1 / ratio`` times the one it was fitted on."""
    chi2 = f.result.chi2 * ratio + f.result.log_det
    return chi2, chi2 + f.n_free * np.log(f.result.n_data)


def joint_search(d, settings, progress=None) -> tuple[dict, dict]:
    """The joint dynamic search on the quasi-static diagnosis ``d`` (module docstring).

    Returns (the fits: ``{"healthy": ModelFit, <type's effect>: ModelFit, "floor": NoiseFloor}``, the entry of
    ``dynamic_rung.joint``: the healthy model's and each type's NRMSE, chi2 and BIC on the floor measured again,
    their BIC drop and share of the healthy model's misfit, the type's values and Jacobian intervals, identified or
    not, the floor (before, after, how), the best type and whether it is accepted, and the evaluations spent)."""
    note = progress or (lambda _m: None)
    rec, v, floor = d.record, np.asarray(d.voltage_V, dtype=float), d.floor
    vc = v - v.mean()
    qs = d.final
    model = healthy_model(qs)
    base, own = healthy_start_values(model, qs, rec, v)
    grid = grid_points(model, base, rec, vc)
    evaluations = len(HEALTHY_GRID[0]) * len(HEALTHY_GRID[1])
    note(f"joint search: dynamic healthy model ({model.label}) from {HEALTHY_STARTS} of {len(grid)} grid points "
         f"and the best of {HEALTHY_SCREEN} screened")
    healthy = fit_from_grid(model, rec, v, floor, base, grid, settings)
    # the shaft's mass and damping at the rig file's values at every point: the healthy fit may take a damping
    # as a stand-in for a groove's ring (draw 2 of validation/bearing_feasibility.py: 26 N s/m against the file's
    # 1500, where a groove placed with the file's damping explains 40 % of the misfit and one with the fit's none)
    points = [{**{k: healthy.values[k] for k in ("radial_clearance_m", "radial_load_N", "load_share_ratio")}, **own},
              *({**pt, **own} for _, pt in grid[:SCREEN_POINTS])]
    fits: dict = {"healthy": healthy}
    screened = {}
    for name in FAULT_TYPES:
        if name not in d.problem.catalogue:
            continue
        effect = CATALOGUE[name]
        tm, kin = model, kinematics(name, model, healthy.values)
        if len(kin) > 1:
            tm = tm.with_effect(CATALOGUE["cage_slip"])
        tm = tm.with_effect(effect)
        hv = {**tm.defaults(rec), **healthy.values}
        cands = screen(effect, tm, hv, [{**pt, **k} for k in kin for pt in points], rec, v)
        evaluations += 2 * len(cands)
        screened[name] = len(cands)
        if not cands:
            continue
        note(f"joint search: + {name}, fitted from {min(HEALTHY_STARTS, len(cands))} of {len(cands)} screened starts")
        try:
            f = fit_model(tm, rec, v, floor, start=hv, starts=[s for _, s in cands[:HEALTHY_STARTS]],
                          max_nfev=settings.max_nfev, ftol=settings.ftol)
        except InfeasibleError:
            continue
        f.model.release()
        fits[name] = f
    types = [n for n in fits if n in FAULT_TYPES]
    judged = judge(healthy, {n: fits[n] for n in types}, floor, rec, settings)
    confirm = with_scatter(judged, model, healthy, fits, rec, v, floor, settings, note)
    best = (confirm or judged)["ranked"][0] if (confirm or judged)["ranked"] else None
    final = confirm or judged
    ok = bool(best and final["types"][best]["passes_rule"] and final["types"][best]["identified"])
    fits["floor"] = final.pop("floor_fit")
    judged.pop("floor_fit", None)
    entry = {
        **judged, "best": best, "accepted": ok, "with_roller_scatter": confirm,
        "grid_points": len(grid), "screen_points": len(points), "evaluations_screened": evaluations,
        "starts_screened": screened,
    }
    return fits, entry


def with_scatter(judged: dict, model: BearingModel, healthy: ModelFit, fits: dict, rec, v, floor, settings,
                 note) -> dict | None:
    """Every type of ``judged`` with a BIC drop above the rule's, and the healthy model, refitted with the rollers'
    scatter (``fits`` updated), judged again (:func:`judge`); None where no type is a contender or the model has the
    scatter already."""
    contenders = [n for n in judged["ranked"] if judged["types"][n]["delta_bic"] > settings.min_delta_bic]
    confirm = None
    if contenders and "roller_scatter" not in model.names:
        # every type with a BIC drop above the rule's, and the healthy model, again with the rollers' scatter: a
        # roller's pit takes a roller a micrometre small as a stand-in (the healthy draws 1 and 7 of
        # validation/bearing_feasibility.py: a pit explained 19-20 % of the healthy dynamic model's misfit, at the
        # rule's share), and which type an inner groove's record prefers can change with the scatter
        note(f"joint search: {', '.join(contenders)} and the healthy model with roller_scatter")
        sc = CATALOGUE["roller_scatter"]
        hs = _with(healthy, sc, rec, v, floor, settings)
        typed = {n: f for n in contenders if (f := _with(fits[n], sc, rec, v, floor, settings)) is not None}
        if hs is not None and typed:
            # the healthy model with the scatter also from each contender's operating point and scatter: a
            # defect must explain what no operating point any fit found does (draw 0 of the feasibility draws: the
            # outer groove's fit found a load and scatter 26 % of the healthy model's misfit better, an inner
            # groove's record)
            try:
                again = fit_model(hs.model, rec, v, floor, start=dict(hs.values),
                                  starts=[healthy_start(t, hs.model, rec) for t in typed.values()],
                                  max_nfev=settings.max_nfev, ftol=settings.ftol)
                again.model.release()
                if again.chi2 < hs.chi2:
                    hs = again
            except InfeasibleError:
                pass
            confirm = judge(hs, typed, floor, rec, settings)
            fits.update(typed, healthy=hs)
    return confirm


def _with(f: ModelFit, effect, rec, v, floor, settings) -> ModelFit | None:
    """``f``'s model with ``effect`` added, fitted from ``f``'s values (the effect's neutral values); None where
    that start has no solution."""
    try:
        out = fit_model(f.model.with_effect(effect), rec, v, floor, start=dict(f.values), max_nfev=settings.max_nfev,
                        ftol=settings.ftol)
    except InfeasibleError:
        return None
    out.model.release()
    return out


def judge(healthy: ModelFit, typed: dict, floor, rec, settings) -> dict:
    """The types' fits ``typed`` against the healthy dynamic fit on the floor measured again on the best residual
    of them all (where lower than ``floor``): each type's NRMSE, chi2, BIC, BIC drop and share of the healthy
    model's misfit (the engine's rule), identified or not (Jacobian intervals); the types ranked by BIC."""
    best_fit = min([healthy, *typed.values()], key=lambda f: f.result.chi2)
    fl = noise_floor(best_fit.residual_V, rec.dt_s, None if floor.quiet_mask is None else ~floor.quiet_mask)
    ratio = 1.0
    if fl.voltage_noise_V < floor.voltage_noise_V:
        ratio = (floor.voltage_noise_V / fl.voltage_noise_V) ** 2
    else:
        fl = floor
    h_chi2, h_bic = _rescaled(healthy, ratio)
    h_excess = h_chi2 - (healthy.result.n_data - healthy.n_free)
    out = {}
    for n, f in typed.items():
        chi2, bic = _rescaled(f, ratio)
        drop = h_chi2 - chi2
        share = float(np.clip(drop / max(h_excess, drop, 1e-12), 0.0, 1.0))
        c = Candidate(CATALOGUE[n], f, float(h_bic - bic), share)
        _, wkey, akey = FAULT_TYPES[n]
        ci = f.result.ci95
        out[n] = {
            "nrmse": f.nrmse, "chi2": chi2, "bic": float(bic), "delta_bic": float(h_bic - bic),
            "strength": strength(float(h_bic - bic)), "excess_explained": share, "passes_rule": accepted(c, settings),
            "identified": unidentified_reason(n, ci) is None,
            "values": {k: f.values[k] for k in f.values if "defect" in k or k in OPERATING_VALUES},
            "ci95": {wkey: ci.get(wkey), akey: ci.get(akey)},
        }
    return {
        "healthy": {"model": healthy.model.label, "nrmse": healthy.nrmse, "chi2": h_chi2, "bic": float(h_bic),
                    "values": {k: healthy.values[k] for k in healthy.values if k in OPERATING_VALUES}},
        "types": out, "ranked": sorted(out, key=lambda n: out[n]["bic"]),
        "floor": {"before_V": floor.voltage_noise_V, "after_V": fl.voltage_noise_V,
                  "measured_on": best_fit.model.label, "nrmse": healthy.floor_nrmse / np.sqrt(ratio)},
        "floor_fit": fl,
    }


#: The operating point's values the ``joint`` entry reports beside a defect's.
OPERATING_VALUES = ("radial_clearance_m", "radial_load_N", "load_share_ratio", "speed_deviation_ratio",
                    "cage_slip_ratio", "shaft_mass_kg", "bearing_damping_N_s_per_m")


def joint_rung(d, problem, settings, progress=None, final_steps: int | None = None):
    """The joint dynamic search (:func:`joint_search`) on the diagnosis ``d`` (of ``problem``) that the quasi-static
    search and the dynamic rung left ``unexplained``, and its diagnosis where it is accepted.

    Tried only where the dynamic healthy model passes the engine's selection rule over ``d``'s final model (the
    structure ``d`` leaves is what the shaft's dynamics take; where it does not, a defect with the dynamics on is not
    the answer either): the entry's ``healthy_over_final``. The best type's diagnosis replaces ``d`` where that type
    is accepted (the rule over the dynamic healthy model, identified), its BIC on the floor measured again is below
    ``d``'s final model's on that floor, and its final model's honest intervals
    (:func:`~piezobearing.diagnosis.engine.refit`, on the search's step; ``final_steps`` is not used: a refit of the
    whole model at the finer step costs several CPU minutes) still place the defect
    (:func:`.rung.unidentified_defects`). Returns (diagnosis, the ``dynamic_rung.joint`` entry)."""
    note = progress or (lambda _m: None)
    fits, entry = joint_search(d, settings, progress)
    entry["tried"] = True
    fl = fits["floor"]
    ratio = (d.floor.voltage_noise_V / fl.voltage_noise_V) ** 2
    d_chi2, d_bic = _rescaled(d.final, ratio)
    h_chi2 = entry["healthy"]["chi2"] if entry.get("with_roller_scatter") is None else \
        entry["with_roller_scatter"]["healthy"]["chi2"]
    h = fits["healthy"]
    h_bic = h_chi2 + h.n_free * np.log(h.result.n_data)
    drop = d_chi2 - h_chi2
    share = float(np.clip(drop / max(d_chi2 - (d.final.result.n_data - d.final.n_free), drop, 1e-12), 0.0, 1.0))
    hc = Candidate(CATALOGUE["shaft_dynamics"], h, float(d_bic - h_bic), share)
    passes = accepted(hc, settings)
    entry["healthy_over_final"] = {"delta_bic": float(d_bic - h_bic), "excess_explained": share, "passes_rule": passes,
                                   "final_bic": float(d_bic)}
    best = entry["best"]
    judged = entry["with_roller_scatter"] or entry
    why = None
    if not passes:
        why = "the dynamic healthy model does not pass the selection rule over the final model"
    elif not entry["accepted"]:
        why = f"the best type ({best}) is not accepted over the dynamic healthy model" if best else "no type fitted"
    elif judged["types"][best]["bic"] >= d_bic:
        why = f"the best type ({best}) does not lower the final model's BIC on the floor measured again"
    if why:
        entry["replaced"] = False
        entry["why"] = why
        note(f"joint search: {why}")
        return d, entry
    f = fits[best]
    rp = replace(problem, floor=fl, profile_evaluations=RUNG_PROFILE_EVALUATIONS)
    added = [n for n in f.model.names if n not in d.final.model.names]
    c = Candidate(CATALOGUE[best], f, float(judged["types"][best]["delta_bic"]), judged["types"][best]["excess_explained"])
    dj = replace(d, problem=rp, final=f, fits=[*d.fits, h, f],
                 steps=[*d.steps, step_entry(h, " + ".join(n for n in h.model.names if n not in d.final.model.names), hc),
                        step_entry(f, best, c)],
                 selected=list(dict.fromkeys(n for n in [*d.selected, *added] if n in f.model.names)))
    # the intervals on the search's step: a refit at ``final_steps`` of the whole model (the rollers' scatter
    # among its parameters) cost 280 s of CPU on a 0.5 s record (draw 2 of validation/bearing_feasibility.py)
    note(f"joint search: {best} accepted; the final model's intervals")
    dj = refit(dj, None, progress)
    bad = unidentified_defects(dj)
    if bad:
        entry["replaced"] = False
        entry["why"] = f"the final model's intervals do not place {best}: {bad[0]['reason']}"
        note(f"joint search: {entry['why']}")
        return d, entry
    entry["replaced"] = True
    entry["why"] = f"{best} accepted over the dynamic healthy model and below the final model's BIC"
    return dj, entry


def joint_wanted(d, config: dict) -> bool:
    """Whether the joint search is tried on ``d`` (the quasi-static diagnosis, after the dynamic rung where it ran):
    with ``bearing_diagnosis.dynamic_rung`` and ``joint_search`` both ``auto`` (the search is part of the dynamic
    rung; ``joint_search: off`` leaves it out alone) where ``d`` is still
    ``unexplained``, whatever it selects (the rung carries one defect type: the quasi-static search's or the lines
    rule's). Whether the shaft's dynamics take the structure ``d`` leaves is then judged by :func:`joint_rung` (the
    dynamic healthy model against ``d``'s final model), and a type replaces ``d``'s answer only where its BIC is
    lower than ``d``'s final model's."""
    bd = config["bearing_diagnosis"]
    return bd.get("dynamic_rung", "auto") != "off" and bd.get("joint_search", "off") != "off" \
        and d.verdict == "unexplained"
