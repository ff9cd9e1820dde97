"""The running bearing as a diagnosis subject: the sensor voltage of a running rig against its model.

:class:`BearingSubject` gives the engine (:mod:`piezobearing.diagnosis.engine`)
the record (:func:`piezobearing.io.read_bearing_record`: ``time_s,
voltage_V[, speed_rpm]`` in any DAQ format), the baseline model with its
nuisance parameters and their starts (:mod:`.model`), the catalogue
(:mod:`.effects`), the noise floor measured from the record, the roller
passages as segments, and the representations (:mod:`.representations`);
it hides effects in a synthetic record and states the user's answer, the
``fault`` entry of ``diagnosis.json``.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ...bearing.lpm import BearingGeometry
from ...bearing.shaft_dynamics import ShaftDynamics
from ...bearing.surrogate import InfluenceLine, cage_phase
from ...io import MIN_BEARING_RATE_HZ, BearingRecord, average_blocks, read_bearing_record
from ...sensor.calibration import SensorCircuit
from ...sensor.response import sensor_model
from ...signals.detection import noise_std_for_snr
from ...threads import single_blas_thread
from ..effect import Catalogue, EffectError, StartContext
from ..engine import diagnose
from ..fit import fit_model
from ..noise import NoiseFloor, robust_diff_std, white_level
from ..record import Segments
from ..selection import Candidate, add_effect, step_entry, strength
from ..settings import DiagnosticsSettings
from ..subject import Problem
from . import chain, report
from .effects import CATALOGUE, FAULT_TYPES, RUNGS
from .effects.shaft_speed import roller_pass_line_Hz
from .model import BearingModel, RigRecord
from .representations import REPRESENTATIONS, passages

#: Phases of the baseline's start scan over one roller pitch.
PHASE_SCAN = 24
#: Roller passages the overlay figure shows at the full rate (where the baseline misses most).
ZOOM_PASSAGES = 12
#: Final NRMSE below this share of the record's floor: the floor is measured again on the final residual.
REMEASURE_BELOW = 0.8


def rig_from_config(config: dict, influence: InfluenceLine, time_s: np.ndarray, tach_Hz=None,
                    harmonic: tuple[np.ndarray, np.ndarray] | None = None) -> chain.Rig:
    """The chain's fixed part from the config (bearing, sensor, signals.sensor_fem_correction, bearing_diagnosis)
    and an influence line; ``harmonic``: the sensor FEM's (frequency [Hz], |V/F| [V/N]) of this configuration
    (the workflow's), else the paper sensor's (:func:`piezobearing.sensor.response.sensor_model`)."""
    b, bd = config["bearing"], config["bearing_diagnosis"]
    t = np.asarray(time_s, dtype=float)
    circuit = SensorCircuit.from_config(config["sensor"], bd["resistance_ohm"])
    nyquist = 0.5 / float(np.median(np.diff(t))) if t.size > 1 else np.inf
    return chain.Rig(
        BearingGeometry.from_config(b),
        influence,
        sensor_model(config, circuit, nyquist, harmonic),
        bd["gain_factor"],
        b["radial_load_N"],
        b["radial_clearance_m"],
        b["shaft_speed_rpm"] / 60.0,
        t,
        None if tach_Hz is None else np.asarray(tach_Hz, dtype=float),
        ShaftDynamics.from_config(b),
    )


def rig_record(rec: BearingRecord, config: dict, influence: InfluenceLine, harmonic=None) -> RigRecord:
    tach = None if rec.speed_rpm is None else rec.speed_rpm / 60.0
    rig = rig_from_config(config, influence, rec.time_s, tach, harmonic)
    return RigRecord(
        rec.time_s, None, "voltage", "V", rig=rig,
        speed_tolerance_ratio=config["bearing_diagnosis"]["speed_tolerance_ratio"],
    )


def model_rate(rec: BearingRecord, max_rate_Hz: float) -> tuple[BearingRecord, dict]:
    """The record at the rate the model is held at, and what was done (``model_rate`` of diagnosis.json).

    The quasi-static model holds the rings' equilibrium at every instant, not the shaft's mass on its rollers:
    the shaft-on-rollers mode (near 2.5 kHz for the paper's rig in the dynamic LPM), which every roller
    passage and every groove's edge excites, is beyond it. A record sampled faster than ``max_rate_Hz``
    (``bearing_diagnosis.max_model_rate_Hz``) is averaged in blocks of n = ceil(f_s / max_rate_Hz) samples
    (:func:`piezobearing.io.average_blocks`: the box filter the model assumes for one DAQ sample, so the model
    is exact for the averaged record); n is lowered where f_s / n would fall below the slowest rate a record may
    have (:data:`piezobearing.io.MIN_BEARING_RATE_HZ`). Returns the record and ``{"record_rate_Hz",
    "model_rate_Hz", "block_samples", "max_model_rate_Hz", "reason"}``.
    """
    fs = rec.sample_rate_Hz
    n = max(int(np.ceil(fs / max_rate_Hz * (1 - 1e-9))), 1)
    while n > 1 and fs / n < MIN_BEARING_RATE_HZ:
        n -= 1
    if n == 1:
        reason = (f"recorded at {fs:.6g} Hz, held as it is (bearing_diagnosis.max_model_rate_Hz = {max_rate_Hz:g} Hz"
                  + (")" if fs <= max_rate_Hz * (1 + 1e-9) else
                     f"; no block of whole samples brings it below that and above {MIN_BEARING_RATE_HZ:g} Hz: the "
                     "model may miss the shaft's resonance in it)"))
    else:
        reason = (f"recorded at {fs:.6g} Hz, above bearing_diagnosis.max_model_rate_Hz = {max_rate_Hz:g} Hz: averaged "
                  f"in blocks of {n} samples to {fs / n:.6g} Hz (the box filter the model assumes for one DAQ sample), "
                  "which takes out the shaft-on-rollers resonance near 2.5 kHz that the quasi-static model does not hold")
    out = average_blocks(rec, n)
    return out, {"record_rate_Hz": float(fs), "model_rate_Hz": float(out.sample_rate_Hz), "block_samples": n,
                 "max_model_rate_Hz": float(max_rate_Hz), "reason": reason}


def noise_floor(v: np.ndarray, dt_s: float, clipped: np.ndarray | None = None) -> NoiseFloor:
    """The voltage's white level over the whole record (one long segment: the bearing's lines are narrow).

    The periodogram of the longest power-of-two stretch, 5-45% of f_s,
    line-free trimmed mean (:func:`piezobearing.diagnosis.noise.white_level`):
    the roller-pass harmonics are lines a few bins wide, left out.
    """
    mask = np.ones(v.size, dtype=bool) if clipped is None else ~clipped
    seg = int(2 ** np.floor(np.log2(max(mask.sum(), 64))))
    var, _ = white_level(v, mask, dt_s, segment=seg)
    return NoiseFloor(
        float(np.sqrt(var)), 0.0, float(mask.sum() * dt_s), 1,
        "whole record: line-free trimmed mean of the periodogram, 5-45% of fs", mask,
    )


def baseline_starts(rec: RigRecord, v: np.ndarray) -> tuple[dict, list[dict]]:
    """Start speed from the roller-pass line, then the best start phases of a scan over one pitch."""
    rig = rec.rig
    start: dict = {"dc_offset_V": float(np.mean(v))}
    if rig.tach_Hz is None:
        bpfo = rig.frequencies(rig.shaft_speed_Hz)["bpfo_Hz"]
        tol = rec.speed_tolerance_ratio
        f = roller_pass_line_Hz(v, rec.dt_s, bpfo, max(tol, 1e-3))
        start["shaft_speed_Hz"] = float(np.clip(rig.shaft_speed_Hz * f / bpfo, rig.shaft_speed_Hz * (1 - tol), rig.shaft_speed_Hz * (1 + tol)))
    scores = []
    vc = v - v.mean()
    for ph in np.arange(PHASE_SCAN) * rig.pitch_rad / PHASE_SCAN:
        m = chain.voltage(rig, {**start, "start_phase_rad": float(ph)})
        m = m - m.mean()
        scores.append((float(np.sum((vc - m) ** 2)), float(ph)))
    scores.sort()
    return start, [{"start_phase_rad": ph} for _, ph in scores[:2]]


def segments(rec: RigRecord, values: dict) -> Segments:
    """The roller passages over the sensor at the start values (the per-passage view uses each fit's own)."""
    rig = rec.rig
    speed = values.get("shaft_speed_Hz", rig.shaft_speed_Hz) if rig.tach_Hz is None else rig.tach_Hz
    phi = cage_phase(rec.time_s, speed, rig.geometry, values.get("start_phase_rad", 0.0))
    a, b, c = passages(phi, rig.pitch_rad)
    return Segments("passage", "roller_over_sensor", a, b, c)


class BearingSubject:
    """The running bearing (see the module docstring)."""

    name = "bearing"
    catalogue = CATALOGUE
    figures = ("overlay", "per_passage", "synchronous_average", "envelope", "spectrum", "ranking", "ladder")

    def check_config(self, config: dict) -> None:
        CATALOGUE.resolve(config["bearing_diagnosis"]["effects"], "bearing_diagnosis.effects")
        hidden_values(config["bearing"]["hidden_effects"], None)

    def read(self, path: str, config: dict) -> BearingRecord:
        b = config["bearing"]
        return read_bearing_record(path, b.get("channels"), b.get("wav_full_scale_V"))

    def problem(self, obs: tuple, config: dict) -> Problem:
        """``obs``: (record, influence line) or (record, influence line, the sensor FEM's harmonic response)."""
        rec, influence, *rest = obs
        rr = rig_record(rec, config, influence, rest[0] if rest else None)
        v = np.asarray(rec.voltage_V, dtype=float)
        start, starts = baseline_starts(rr, v)
        configured = tuple(CATALOGUE.resolve(config["bearing_diagnosis"]["effects"], "bearing_diagnosis.effects"))
        return Problem(
            rr, v, BearingModel(), start, starts, configured, catalogue_for(rec.speed_rpm is not None),
            noise_floor(v, rr.dt_s, rec.clipped), segments(rr, {**start, **starts[0]}), REPRESENTATIONS,
            zoom_segments=ZOOM_PASSAGES,
        )

    def synthesise(self, config: dict, seed: int, hidden_effects: list[dict], influence: InfluenceLine,
                   harmonic=None) -> BearingRecord:
        return synthesise(config, seed, hidden_effects, influence, harmonic)

    def answer(self, diagnosis) -> dict:
        return {"fault": fault_answer(diagnosis)}

    def report(self, d: dict, figures: dict[str, str]) -> str:
        return report.render(d, figures)

    def diagnose(self, obs, config: dict, progress=None):
        """Run the engine on ``(record, influence line)``; returns the diagnosis and its JSON-ready dict.

        A record sampled faster than ``bearing_diagnosis.max_model_rate_Hz`` is first averaged in blocks of
        whole samples down to a rate the model holds (:func:`model_rate`; the dict's ``model_rate`` says so).

        The record's own spectrum gives an upper bound of the floor: a fault
        whose lines (BPFI with shaft sidebands, 2 x BSF with cage sidebands)
        fill every bin lifts it. :func:`floor_prepass` measures the floor
        again, before the engine, on the residual of the best fault fitted
        alone (the engine then runs once). Should the final model still leave
        less than 0.8 x the floor (a lift the pre-pass did not catch), the
        floor is measured again on the final model's residual and the engine
        runs once more; ``noise_floor.method`` says which.

        A defect the record cannot pin down (:func:`unidentified_defects`: its width's interval holds zero, or
        its angle's spans the circle) is taken out of the catalogue and the engine runs again without it
        (``fault.unidentified`` names it). Where the quasi-static verdict is ``unexplained`` with a fault's
        lines or a defect selected, the dynamic rung is tried (:func:`dynamic_rung`; ``dynamic_rung`` of the
        dict says what it gave).
        """
        settings = DiagnosticsSettings.from_config(config.get("diagnostics"))
        rec, rate = model_rate(obs[0], config["bearing_diagnosis"]["max_model_rate_Hz"])
        obs = (rec, *obs[1:])
        note = progress or (lambda _msg: None)
        # the fits' linear algebra is on matrices of n x (a few) values: a second BLAS thread only waits
        # (each SVD of the trust-region step 70x slower on a loaded 2-core machine, benchmarks/bench_diagnosis_bearing.py)
        with single_blas_thread():
            fits: dict = {}
            problem = floor_prepass(self.problem(obs, config), settings, rec.clipped, progress, fits)
            d = diagnose(problem, settings, progress, fits.get("baseline"))
            if d.final.nrmse < REMEASURE_BELOW * d.final.floor_nrmse:
                fl = noise_floor(d.final.residual_V, problem.record.dt_s, rec.clipped)
                fl = replace(fl, method=f"{fl.method}, of the final model's residual: the record's own "
                             f"({problem.floor.voltage_noise_V:.4g} V) was lifted by the fault's lines")
                problem = replace(problem, floor=fl)
                d = diagnose(problem, settings, progress)
            d, problem, dropped = without_unidentified(d, problem, settings, progress)
            rung = {"tried": False, "accepted": False, "why": "the quasi-static verdict is explained"}
            if d.verdict == "unexplained" and not any(e.name in RUNGS for e in problem.configured):
                rung = rung_wanted(d, config)
                if rung["tried"]:
                    c0 = time.process_time()
                    d, rung = dynamic_rung(d, problem, settings, progress, rung)
                    d, problem, more = without_unidentified(d, problem, settings, progress)
                    dropped += more
                    note(f"dynamic rung: {time.process_time() - c0:.1f} s CPU "
                         f"({'accepted' if rung['accepted'] else 'not accepted'})")
        answer = self.answer(d)
        answer["fault"]["unidentified"] = dropped
        return d, {**d.to_dict(answer), "model_rate": rate, "dynamic_rung": rung}


#: Width of a defect's 95 % interval in angle beyond which it does not place the defect [rad].
FULL_TURN_RAD = 2 * np.pi


def unidentified_defects(d) -> list[dict]:
    """The selected defects the record cannot pin down: the width's 95 % interval holds zero (or is missing), or
    the angle's spans the circle; each ``{"effect", "ci95", "reason"}``. Operating conditions keep their
    one-sided intervals (a clearance bounded from below) and are not judged here."""
    ci = d.final.result.ci95
    out = []
    for name in d.selected:
        if name not in FAULT_TYPES:
            continue
        _, wkey, pkey = FAULT_TYPES[name]
        w, a = ci.get(wkey), ci.get(pkey)
        reason = None
        if w is None or w[0] is None or not np.all(np.isfinite(w)) or w[0] <= 0.0:
            reason = f"the interval of {wkey} holds zero"
        elif name != "rolling_element_defect" and (a is None or a[0] is None or not np.all(np.isfinite(a))
                                                   or a[1] - a[0] >= FULL_TURN_RAD):
            reason = f"the interval of {pkey} spans the circle"
        if reason:
            out.append({"effect": name, "ci95": {wkey: w, pkey: a}, "reason": reason})
    return out


def without_unidentified(d, problem: Problem, settings, progress=None, rounds: int = 2):
    """The diagnosis again without the defects :func:`unidentified_defects` finds (at most ``rounds`` times);
    returns (diagnosis, problem, [the defects taken out])."""
    dropped: list[dict] = []
    for _ in range(rounds):
        bad = unidentified_defects(d)
        if not bad:
            break
        dropped += bad
        names = {b["effect"] for b in bad}
        cat = Catalogue("bearing")
        for name, e in problem.catalogue.items():
            if name not in names:
                cat.register(e)
        problem = replace(problem, catalogue=cat,
                          configured=tuple(e for e in problem.configured if e.name not in names))
        (progress or (lambda _m: None))(f"not identified, left out: {', '.join(sorted(names))}")
        d = diagnose(problem, settings, progress)
    return d, problem, dropped


def rung_wanted(d, config: dict) -> dict:
    """Whether the dynamic rung is tried on an ``unexplained`` quasi-static diagnosis, and why (the start of the
    ``dynamic_rung`` entry): with ``bearing_diagnosis.dynamic_rung: auto``, where a defect is selected or the
    residual shows a fault's lines (:func:`fault_evidence`): the shaft's ring after each dip and the deeper
    modulation of a moving defect are what the quasi-static chain leaves there. Other structure (a healthy
    bearing's bumps off by a housing's dynamics) is not the shaft's, and a fit of the dynamic chain costs a
    hundred times the quasi-static one, so it is not tried there."""
    mode = config["bearing_diagnosis"].get("dynamic_rung", "auto")
    if mode == "off":
        return {"tried": False, "accepted": False, "why": "bearing_diagnosis.dynamic_rung is off"}
    faults = [n for n in d.selected if n in FAULT_TYPES]
    evidence = fault_evidence(d)
    if not faults and not evidence:
        return {"tried": False, "accepted": False,
                "why": "the quasi-static verdict is unexplained, but no defect is selected and no fault's lines are "
                "left: the structure is not the shaft's ring on a fault"}
    why = (f"the quasi-static model selects {', '.join(faults)} and leaves structure" if faults else
           f"the residual shows the {evidence[0]['type'].replace('_', ' ')}'s lines and no defect is selected")
    return {"tried": True, "accepted": False, "why": why, "evidence": evidence}


def dynamic_rung(d, problem: Problem, settings, progress=None, rung: dict | None = None):
    """The engine once more with the shaft's dynamics (``shaft_dynamics``), judged against the quasi-static diagnosis.

    Configured: the quasi-static selection's first defect (its fit warm-starts the rung); where no defect is
    selected, the defect of the fault type whose lines the residual shows most (:func:`fault_evidence`), fitted
    quasi-statically first; then ``shaft_dynamics``, whose starts place an outer-race groove with the dynamics on
    (the pair: a groove the quasi-static chain places a pitch away). Searched, by the engine's stepwise rule with
    the dynamics on: the rest of the quasi-static selection (operating conditions and later defects, often
    stand-ins for the dynamics the quasi-static chain lacks). The rung is accepted by the engine's rule
    for one step (:func:`~piezobearing.diagnosis.selection.accepted`: its BIC drop over the quasi-static final
    model above ``min_delta_bic`` and at least ``min_share`` of that model's misfit above the floor explained)
    where none of its defects is unidentified (:func:`unidentified_defects`); the diagnosis returned is then the
    rung's, else the quasi-static one. Returns
    (diagnosis, the ``dynamic_rung`` entry: why, evidence, accepted, the BIC drop and share, the ladder:
    baseline, quasi-static final, with the dynamics, floor NRMSE). ``rung``: :func:`rung_wanted`'s entry.
    """
    rung = dict(rung or rung_wanted(d, {"bearing_diagnosis": {"dynamic_rung": "auto"}}))
    faults = [n for n in d.selected if n in FAULT_TYPES]
    pair = [] if faults else [EFFECT_OF_TYPE[ev["type"]] for ev in rung.get("evidence", [])[:1]]
    pair = [n for n in pair if n in problem.catalogue]
    first = [*faults[:1], *pair]
    cat = Catalogue("bearing")
    for n in d.selected:
        if n not in first:
            cat.register(warm(CATALOGUE[n], d.final.values, d.record))
    add = [CATALOGUE[n] for n in first if CATALOGUE[n] not in problem.configured]
    rp = replace(problem, configured=(*problem.configured, *add, CATALOGUE["shaft_dynamics"]), catalogue=cat,
                 profile_evaluations=RUNG_PROFILE_EVALUATIONS)
    (progress or (lambda _m: None))("dynamic rung: + " + " + ".join([*pair, "shaft_dynamics"]))
    dr = diagnose(rp, settings, progress, d.baseline)
    bad = unidentified_defects(dr)
    drop = d.final.chi2 - dr.final.chi2
    share = float(np.clip(drop / max(d.final.excess, drop, 1e-12), 0.0, 1.0))
    delta_bic = float(d.final.bic - dr.final.bic)
    ok = delta_bic > settings.min_delta_bic and share >= settings.min_share and not bad
    if ok and dr.final.nrmse < REMEASURE_BELOW * dr.final.floor_nrmse:
        # the floor was lifted by the fault's lines the quasi-static model left: measured again on the rung's
        # residual, and the rung run with it (as the quasi-static diagnosis does)
        qm = problem.floor.quiet_mask
        fl = noise_floor(dr.final.residual_V, problem.record.dt_s, None if qm is None else ~qm)
        fl = replace(fl, method=f"{fl.method}, of the dynamic rung's final residual: the floor before "
                     f"({problem.floor.voltage_noise_V:.4g} V) was lifted by the fault's lines")
        (progress or (lambda _m: None))("dynamic rung: floor measured again")
        dr = diagnose(replace(rp, floor=fl), settings, progress)
    rung.update(
        accepted=bool(ok),
        unidentified=bad,
        delta_bic=delta_bic,
        strength=strength(delta_bic),
        excess_explained=share,
        quasi_static={"selected": list(d.selected), "verdict": d.verdict, "nrmse": d.final.nrmse,
                      "fault": fault_answer(d)["statement"]},
        dynamic={"selected": list(dr.selected), "configured": [e.name for e in rp.configured],
                 "verdict": dr.verdict, "nrmse": dr.final.nrmse},
        ladder=[
            {"model": "baseline", "nrmse": d.baseline.nrmse},
            {"model": "quasi-static: " + d.final.model.label, "nrmse": d.final.nrmse},
            {"model": "dynamic: " + dr.final.model.label, "nrmse": dr.final.nrmse},
            {"model": "noise floor", "nrmse": dr.final.floor_nrmse},
        ],
    )
    rung["pair"] = pair
    return (merged(d, dr, share, pair) if ok else d), rung


def warm(effect, values: dict, record):
    """``effect`` with one more start first: its parameters' ``values`` (the quasi-static final fit's), so that the
    rung's search refits it from where the quasi-static search left it (a clearance 8 um short of the record's
    is a better start than the effect's own)."""
    start = {p.name: values[p.name] for p in effect.params(record) if p.name in values}

    class Warm(type(effect)):
        def starts(self, ctx):
            return [dict(start), *super().starts(ctx)]

    return Warm()


def merged(d, dr, share: float, pair: list[str]):
    """The rung's diagnosis ``dr`` read as steps after the quasi-static one ``d``: the quasi-static ladder, then
    ``shaft_dynamics`` added (its fit with the quasi-static selection, its evidence over the quasi-static final
    model), then the rung's own search; ``selected`` the quasi-static selection, ``shaft_dynamics`` and the rung's
    additions; the configured model (and its tests) the user's."""
    rung_fit = dr.configured
    c = Candidate(CATALOGUE["shaft_dynamics"], rung_fit, float(d.final.bic - rung_fit.bic), share)
    dr.steps = [*d.steps, step_entry(rung_fit, " + ".join([*pair, "shaft_dynamics"]), c), *dr.steps[1:]]
    dr.fits = [*d.fits, rung_fit, *dr.fits[1:]]
    dr.selected = [*d.selected, *pair, "shaft_dynamics", *dr.selected]
    dr.selected = list(dict.fromkeys(n for n in dr.selected if n in {e.name for e in dr.final.model.effects}))
    dr.configured = d.configured
    dr.tests = {**dr.tests, "configured": d.tests["configured"]}
    dr.ranking = d.ranking
    dr.problem = replace(dr.problem, catalogue=d.problem.catalogue)
    return dr


#: Most evaluations of the dynamic chain the rung's interval checks and profiles may spend (the engine's 600 would
#: cost 1.5-2 CPU minutes on a 2 s record at 2550 Hz, 0.15-0.2 s each; intervals beyond it keep the Jacobian's,
#: flagged in ``ci_method``).
RUNG_PROFILE_EVALUATIONS = 120
#: The catalogue effect of each fault type.
EFFECT_OF_TYPE = {kind: name for name, (kind, _w, _a) in FAULT_TYPES.items()}
#: A fault's lines name it (where no defect is selected) when at least two of its first three lines stand this far
#: above the white floor in the final residual's spectrum [dB]. Set between measured values: the largest residual
#: line a healthy record of the dynamic LPM leaves at a roller-pass harmonic against the quasi-static model is
#: 11.5-12.4 dB (docs/validation/bearing_diagnosis.md, 25.6 kHz), the weakest line of a missed groove 26.6 dB.
LINES_DB = 20.0


def fault_evidence(d) -> list[dict]:
    """The fault families the final residual still shows, strongest first: ``{"type", "lines", "envelope",
    "strongest_dB"}``. A family counts where the envelope view finds one of its bands above the detector's
    family-wise threshold (:class:`~.representations.EnvelopeBands`) or where at least two of its first three
    lines stand :data:`LINES_DB` above the floor in the spectrum test's findings."""
    env = d.judgements.get("envelope", {}).get("final")
    env_found = env.findings if env is not None else []
    bands = {"outer_race": ("BPFO",), "inner_race": ("BPFI",), "rolling_element": ("2xBSF", "BSF")}
    out = []
    for kind in ("outer_race", "inner_race", "rolling_element"):
        lines, df = _line_spectra(d, kind)[:2]
        first = lines[:3] if kind == "outer_race" else lines[:9]
        hits = []
        for u in d.unexplained:
            if u.get("test") != "spectrum" or u.get("kind") != "narrowband":
                continue
            f = u["frequency_Hz"]
            label, fl = min(first, key=lambda x: abs(x[1] - f))
            if abs(fl - f) <= max(LINE_TOLERANCE * fl, 2 * df) and u["excess_dB"] >= LINES_DB:
                hits.append({"line": label, "frequency_Hz": float(f), "excess_dB": float(u["excess_dB"])})
        envs = [{"band": e["band"], "frequency_Hz": e["frequency_Hz"], "ratio": e["ratio"]} for e in env_found
                if e["band"].split("x")[-1] in bands[kind] or e["band"] in bands[kind]]
        if len({h["line"] for h in hits}) >= 2 or envs:
            out.append({"type": kind, "lines": hits, "envelope": envs,
                        "strongest_dB": max([h["excess_dB"] for h in hits], default=0.0)})
    out.sort(key=lambda e: (-len(e["lines"]), -e["strongest_dB"]))
    return out


def quiet_level(residual_V: np.ndarray, clipped: np.ndarray | None = None) -> float:
    """The white noise level [V] of a residual that is noise plus sparse events, from its quiet samples.

    :func:`~piezobearing.diagnosis.noise.robust_diff_std`: the median absolute deviation of the first
    differences, x 1.4826 / sqrt(2) (the differences take out the slow misfit, the median the sparse
    events). A fault's dips and bursts fill every bin of the spectrum but few samples: at 2550 Hz and
    30 dB this gives 0.28 x the record's spectral floor for the inner-race and the rolling-element
    records of the tests, 0.95 for the healthy one and 0.90-5.3 for every other catalogue effect
    (measured).
    """
    r = np.asarray(residual_V, dtype=float)
    return robust_diff_std(r if clipped is None else r[~clipped])


def floor_prepass(p: Problem, settings, clipped: np.ndarray | None, progress=None, fits: dict | None = None) -> Problem:
    """The noise floor measured once more, before the engine, where a fault's lines have lifted it.

    The baseline is fitted with the record's floor. Where its residual's
    quiet level (:func:`quiet_level`) is below :data:`REMEASURE_BELOW` x that
    floor (the floor is lifted by lines that fill the spectrum but few
    samples), each fault of the catalogue (:data:`~.effects.FAULT_TYPES`) is
    fitted alone on top, as the engine's first ranking does
    (:func:`~piezobearing.diagnosis.selection.add_effect`); where the best
    leaves less than :data:`REMEASURE_BELOW` x the record's floor, the floor
    is measured on that residual the same way as on the record
    (:func:`noise_floor`) and ``p`` is returned with it; otherwise ``p``
    unchanged. A white floor's level does not move the fits, only the
    evidence: the engine's run with this floor is the second run of the old
    two-pass method, found with four fits instead of a whole run. Where ``p`` is returned unchanged, the
    baseline's fit is put in ``fits["baseline"]`` (the engine's own first fit, the same numbers: not fitted twice).
    """
    v, rec = np.asarray(p.voltage_V, dtype=float), p.record
    note = progress or (lambda _msg: None)
    note("floor pre-pass: baseline")
    base = fit_model(p.baseline, rec, v, p.floor, start=p.baseline_start, starts=p.baseline_starts,
                     max_nfev=settings.max_nfev, ftol=settings.ftol)
    base.model.release()
    if fits is not None:
        fits["baseline"] = base  # taken back below if the floor changes
    if quiet_level(base.residual_V, clipped) >= REMEASURE_BELOW * p.floor.voltage_noise_V:
        return p
    best = base
    for name in FAULT_TYPES:
        if name in p.catalogue:
            note(f"floor pre-pass: baseline + {name}")
            f = add_effect(base, p.catalogue[name], rec, v, p.floor, settings)
            f.model.release()
            if f.nrmse < best.nrmse:
                best = f
    if best.nrmse >= REMEASURE_BELOW * best.floor_nrmse:
        return p
    if fits is not None:
        fits.pop("baseline")
    fl = noise_floor(best.residual_V, rec.dt_s, clipped)
    fl = replace(fl, method=f"{fl.method}, of the residual of {best.model.label} fitted before the search "
                 f"(pre-pass): the record's own ({p.floor.voltage_noise_V:.4g} V) was lifted by the fault's lines")
    return replace(p, floor=fl)


#: The running-bearing subject.
SUBJECT = BearingSubject()


def catalogue_for(tachometer: bool) -> Catalogue:
    """The catalogue a record is searched with: the rungs (:data:`~.effects.RUNGS`) are added by the subject, not
    ranked; with a tachometer the shaft's speed is measured, so ``shaft_speed`` (a deviation from it) would only be
    ``cage_slip`` under another name, and is left out."""
    out = Catalogue("bearing")
    for name, e in CATALOGUE.items():
        if name not in RUNGS and not (tachometer and name == "shaft_speed"):
            out.register(e)
    return out


def hidden_values(specs: list[dict], record: RigRecord | None, key: str = "bearing.hidden_effects") -> tuple[BearingModel, dict]:
    """The model and parameter values of ``[{name, params}]`` (unknown names or parameters: one-line EffectError)."""
    model = BearingModel(tuple(CATALOGUE.resolve([s["name"] for s in specs], key)))
    if record is None:
        return model, {}
    values = model.defaults(record)
    for i, (spec, effect) in enumerate(zip(specs, model.effects, strict=True)):
        allowed = {p.name: p for p in effect.params(record)}
        for name, val in (spec.get("params") or {}).items():
            if name not in allowed:
                raise EffectError(
                    f"{key}[{i}].params.{name}: unknown parameter of '{effect.name}'; it has: {', '.join(allowed)}"
                )
            p = allowed[name]
            if not p.lower <= float(val) <= p.upper:
                raise EffectError(f"{key}[{i}].params.{name}: {val} outside [{p.lower:g}, {p.upper:g}]")
            values[name] = float(val)
    return model, values


def synthesise(config: dict, seed: int, hidden_effects: list[dict], influence: InfluenceLine,
               harmonic: tuple[np.ndarray, np.ndarray] | None = None) -> BearingRecord:
    """A synthetic running-bearing record: the chain at the nominal point with the hidden effects, plus noise.

    White Gaussian noise at ``bearing_diagnosis.synthetic_snr_dB`` over the
    noiseless record (seeded by ``seed``); the sensor model as the diagnosis's (``harmonic``: the sensor FEM's
    response of this configuration, :func:`rig_from_config`); the roller set starts at
    ``synthetic_start_phase_deg``; with ``synthetic_tachometer`` the shaft
    speed (times 1 + any hidden ``speed_deviation_ratio``) is written as speed_rpm.
    """
    bd = config["bearing_diagnosis"]
    fs = bd["synthetic_sample_rate_Hz"]
    t = np.arange(int(round(bd["synthetic_duration_s"] * fs))) / fs
    f0 = config["bearing"]["shaft_speed_rpm"] / 60.0
    tach = np.full(t.size, f0) if bd["synthetic_tachometer"] else None
    rig = rig_from_config(config, influence, t, tach, harmonic)
    rr = RigRecord(t, None, "voltage", "V", rig=rig, speed_tolerance_ratio=bd["speed_tolerance_ratio"])
    model, values = hidden_values(hidden_effects, rr)
    values["start_phase_rad"] = float(np.radians(bd["synthetic_start_phase_deg"]))
    v = model.simulate(values, rr)
    rng = np.random.default_rng(seed)
    sigma = noise_std_for_snr(v, bd["synthetic_snr_dB"])
    v = v + sigma * rng.standard_normal(v.size)
    speed = None
    if tach is not None:
        speed = 60.0 * tach * (1 + values.get("speed_deviation_ratio", 0.0))
    return BearingRecord(t, v, speed, "synthetic", (), np.zeros(t.size, dtype=bool))


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


def start_context(rec: RigRecord, v: np.ndarray, model_v: np.ndarray, values: dict) -> StartContext:
    return StartContext(rec, v, model_v, values)
