"""The running bearing as a diagnosis subject: the sensor voltage of a running rig against its model.

:class:`BearingSubject` gives the engine (:mod:`piezobearing.diagnosis.engine`)
the record (:func:`piezobearing.io.read_bearing_record`: ``time_s,
voltage_V[, speed_rpm]`` in any DAQ format), the baseline model with its
nuisance parameters and their starts (:mod:`.model`), the catalogue
(:mod:`.effects`), the noise floor measured from the record, the roller
passages as segments, and the representations (:mod:`.representations`);
it hides effects in a synthetic record and states the user's answer, the
``fault`` entry of ``diagnosis.json`` (:mod:`.answer`). The noise floor and its
pre-pass are in :mod:`.floor`; the dynamic rung and the defects a record cannot
pin down in :mod:`.rung`; the joint dynamic search in :mod:`.joint`.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ...bearing.geometry import BearingGeometry
from ...bearing.shaft_dynamics import FINAL_STEPS_PER_PERIOD, STEPS_PER_PERIOD, ShaftDynamics
from ...bearing.surrogate import InfluenceLine, cage_phase
from ...io import MIN_BEARING_RATE_HZ, BearingRecord, average_blocks, read_bearing_record
from ...numerics.threads import single_blas_thread
from ...sensor.calibration import SensorCircuit
from ...sensor.response import sensor_model
from ...signals.detection import noise_std_for_snr
from ..effect import Catalogue, EffectError
from ..engine import diagnose
from ..record import Segments
from ..settings import DiagnosticsSettings
from ..subject import Problem
from . import chain, report
from .answer import fault_answer
from .effects import CATALOGUE, RUNGS
from .effects.shaft_speed import roller_pass_line_Hz
from .floor import REMEASURE_BELOW, floor_prepass, noise_floor
from .joint import defects_against_dynamics, joint_rung, joint_wanted
from .model import BearingModel, RigRecord
from .representations import REPRESENTATIONS, passages
from .rung import (
    dynamic_rung,
    dynamic_rung_by_type,
    housing_rung_wanted,
    housing_scan,
    indistinct_defects,
    on_record_shaft,
    rung_wanted,
    without_defects,
    without_unidentified,
)

#: Phases of the baseline's start scan over one roller pitch.
PHASE_SCAN = 24
#: Roller passages the overlay figure shows at the full rate (where the baseline misses most).
ZOOM_PASSAGES = 12


def rig_from_config(config: dict, influence: InfluenceLine, time_s: np.ndarray, tach_Hz=None,
                    harmonic: tuple[np.ndarray, np.ndarray] | None = None) -> chain.Rig:
    """The chain's fixed part from the config (bearing, sensor, signals.sensor_fem_correction, bearing_diagnosis)
    and an influence line; ``harmonic``: the sensor FEM's (frequency [Hz], |V/F| [V/N]) of this configuration
    (the workflow's), else the paper sensor's (:func:`piezobearing.sensor.response.sensor_model`). The dynamic
    rung's step: ``bearing_diagnosis.dynamic_steps_per_period``; a housing mode the rig file gives:
    :func:`housing_mode_of`."""
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
        int(bd.get("dynamic_steps_per_period", STEPS_PER_PERIOD)),
        housing_mode_of(bd),
    )


def housing_mode_of(bd: dict) -> tuple[float, float] | None:
    """The housing mode the rig file gives (``bearing_diagnosis.housing_mode_Hz``, ``housing_mode_damping_ratio``):
    (frequency [Hz], damping ratio [-]), or None."""
    f = bd.get("housing_mode_Hz")
    return None if f is None else (float(f), float(bd["housing_mode_damping_ratio"]))


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
        effects = config["bearing_diagnosis"]["effects"]
        for i, e in enumerate(CATALOGUE.resolve(effects, "bearing_diagnosis.effects")):
            missing = [r for r in e.rides_on if r not in effects[:i]]
            if missing:
                raise EffectError(f"bearing_diagnosis.effects: {e.name} acts through {', '.join(missing)}; "
                                  f"add {', '.join(missing)} before it")
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
            interval_correlation=config["bearing_diagnosis"].get("interval_correlation", "auto") != "off",
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

        A defect the record cannot pin down (:func:`unidentified_defects`: its width's interval holds zero or
        reaches the catalogue's widest defect, or its angle's spans the circle) is taken out of the catalogue and
        the engine runs again without it (``fault.unidentified`` names it). Where the quasi-static verdict is
        ``unexplained`` with a fault's lines or a defect selected, the dynamic rung is tried (:func:`dynamic_rung`; ``dynamic_rung`` of the
        dict says what it gave); where it is ``explained`` with a defect that does not stand against a healthy
        bearing with the shaft's dynamics (:func:`~.joint.defects_against_dynamics`), the rung is tried with the
        defects held to the rule; where it is accepted and the record is still ``unexplained``, the housing mode's
        rung above it (:func:`housing_rung_wanted`; ``dynamic_rung.housing_mode``). Where the record is still
        ``unexplained`` after them and ``joint_search`` is ``auto``, the joint dynamic search (:func:`~.joint.joint_wanted`, :func:`~.joint.joint_rung`:
        the operating point and each defect type fitted together with the shaft's dynamics; ``dynamic_rung.joint``).
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
            held = any(e.name in RUNGS for e in problem.configured)  # the user's model holds a rung already
            rung = {"tried": False, "accepted": False, "why": "the quasi-static verdict is explained"}
            rung = rung if held else rung_start(d, config, note)
            if not held and (d.verdict == "unexplained" or rung["tried"]):
                final_steps = int(config["bearing_diagnosis"].get("dynamic_final_steps_per_period",
                                                                  FINAL_STEPS_PER_PERIOD))
                if rung["tried"]:
                    d, problem, rung, more = run_rungs(d, problem, rung, config, settings, progress, final_steps)
                    dropped += more
                if joint_wanted(d, config):
                    c0 = time.process_time()
                    note("joint search: the operating point and each defect type with the shaft's dynamics")
                    d, rung["joint"] = joint_rung(d, problem, settings, progress, final_steps)
                    note(f"joint search: {time.process_time() - c0:.1f} s CPU "
                         f"({'diagnosis replaced' if rung['joint']['replaced'] else 'diagnosis kept'})")
        answer = self.answer(d)
        answer["fault"]["unidentified"] = dropped
        return d, {**d.to_dict(answer), "model_rate": rate, "dynamic_rung": rung}


#: The running-bearing subject.
SUBJECT = BearingSubject()


def run_rungs(d, problem: Problem, rung: dict, config: dict, settings, progress, final_steps: int):
    """The dynamic rung on the quasi-static diagnosis ``d`` (``rung``: :func:`rung_start`'s entry, tried), then the
    housing mode's rung where :func:`housing_rung_wanted`. A rung is accepted only with every defect of its model
    identified (:func:`dynamic_rung`), and otherwise gives back the diagnosis it started from, whose unidentified
    defects are already out; a defect the record cannot tell from the shaft's dynamics (:func:`indistinct_defects`)
    is left out here and the engine runs again without it. Returns (diagnosis, problem, the ``dynamic_rung`` entry,
    [the defects left out])."""
    note = progress or (lambda _msg: None)
    c0 = time.process_time()
    d, rung = dynamic_rung_by_type(d, problem, settings, progress, rung, final_steps,
                                   config["bearing_diagnosis"].get("shaft_mass_scan", "auto") != "off")
    problem = on_record_shaft(problem, rung)
    note(f"dynamic rung: {time.process_time() - c0:.1f} s CPU ({'accepted' if rung['accepted'] else 'not accepted'})")
    if housing_rung_wanted(d, rung):
        c0 = time.process_time()
        entry = housing_scan(d, settings)
        rung["housing_mode"] = entry
        if entry["tried"]:
            d, rung["housing_mode"] = dynamic_rung(
                d, replace(problem, floor=d.problem.floor), settings, progress, entry, final_steps,
                ("housing_mode",), ("dynamic", "housing mode"))
        note(f"housing mode rung: {time.process_time() - c0:.1f} s CPU "
             f"({'accepted' if rung['housing_mode']['accepted'] else 'not accepted'})")
    indistinct = indistinct_defects(d, rung)
    if indistinct:
        d, problem = without_defects(d, problem, settings, progress, indistinct)
    return d, problem, rung, indistinct


def rung_start(d, config: dict, note) -> dict:
    """The start of the ``dynamic_rung`` entry on the quasi-static diagnosis ``d``: on an ``explained`` one, whether its
    defects stand against a healthy bearing with the shaft's dynamics (:func:`~.joint.defects_against_dynamics`); on
    an ``unexplained`` one, whether the rung is wanted (:func:`rung_wanted`). ``note`` says what either cost."""
    c0 = time.process_time()
    if d.verdict == "explained":
        rung = defects_against_dynamics(d, config)
        if "against_dynamics" in rung:
            note(f"defects against the shaft's dynamics: {time.process_time() - c0:.1f} s CPU "
                 f"({'they stand' if rung['against_dynamics']['stands'] else 'held to the rule'})")
        return rung
    rung = rung_wanted(d, config)
    if time.process_time() - c0 > 0.5:  # the lines rule held the record against its best healthy model
        note(f"best healthy model of the lines rule: {time.process_time() - c0:.1f} s CPU")
    return rung


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
    return model, model.spec_values(specs, record, key)


def synthesise(config: dict, seed: int, hidden_effects: list[dict], influence: InfluenceLine,
               harmonic: tuple[np.ndarray, np.ndarray] | None = None) -> BearingRecord:
    """A synthetic running-bearing record: the chain at the nominal point with the hidden effects, plus noise.

    White Gaussian noise at ``bearing_diagnosis.synthetic_snr_dB`` over the
    noiseless record (seeded by ``seed``); the sensor model as the diagnosis's (``harmonic``: the sensor FEM's
    response of this configuration, :func:`rig_from_config`); a hidden ``shaft_dynamics`` integrated at
    ``bearing_diagnosis.dynamic_final_steps_per_period``; the roller set starts at
    ``synthetic_start_phase_deg``; with ``synthetic_tachometer`` the shaft
    speed (times 1 + any hidden ``speed_deviation_ratio``) is written as speed_rpm.
    """
    bd = config["bearing_diagnosis"]
    fs = bd["synthetic_sample_rate_Hz"]
    t = np.arange(int(round(bd["synthetic_duration_s"] * fs))) / fs
    f0 = config["bearing"]["shaft_speed_rpm"] / 60.0
    tach = np.full(t.size, f0) if bd["synthetic_tachometer"] else None
    rig = rig_from_config(config, influence, t, tach, harmonic)
    # a hidden shaft_dynamics at the final refit's step: the record as fine as the model the answer is read from
    rig = replace(rig, steps_per_period=int(bd.get("dynamic_final_steps_per_period", FINAL_STEPS_PER_PERIOD)))
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
