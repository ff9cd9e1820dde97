"""The running-bearing diagnosis across a rig's plausible range: every record ends with a verdict.

Draws a rig file and a record's hidden truth (:func:`piezobearing.diagnosis.bearing.lpm_records.draw_conditions`:
the file's load 100-2000 N and clearance 0-60 um; the record's load within x/÷ 1.5 of it, clearance 0-60 um,
slip 0-3 %, speed -3..+3 %, roller scatter 0-2 um, a groove 0.1-1.2 mm at any angle on any race or a roller in
two draws of three), makes the record with the dynamic LPM (0.5 s at 2550 Hz, 30 dB) and diagnoses it (the
first ranking: ``diagnostics.max_steps`` 1; ``--max-steps 4`` the config's full ladder). Writes each draw's
conditions, verdict and selection, the steps kept and those cut (each with the share of the misfit it explained),
the families the lines rule reads, the fault's type, source, values and intervals, whether the dynamic rung was
tried and accepted, the joint dynamic search's entry in short (:func:`joint_row`), and the diagnosis's CPU time,
or its error, and the count of crashes.

    python validation/bearing_feasibility.py --draws 40 --out results/validation/bearing_feasibility.json \
        [--influence results/bearing/influence_line_healthy.csv]

With ``--envelope-only`` it makes the same records and runs the envelope detector of ``piezobearing detect``
(:mod:`piezobearing.signals.detectors.envelope`, its default settings, the record's rig-file speed) on each instead
of the diagnosis: whether the record itself shows a fault family above the detector's threshold (each family's
call and margin over its threshold).

With ``--visibility`` it makes the same records and measures, without any search, whether each record shows its
hidden defect and which model could hold it (:func:`visibility`): the defect's own signal (the noiseless record less
the noiseless record of the same draw without the defect) in units of the record's true noise, the lines of the
record less that healthy record at k x BPFI, k x BPFI -/+ f_r and k x BPFO above the true white floor, the engine's
measured floor (:func:`~piezobearing.diagnosis.bearing.floor.noise_floor` of the record) over the true noise, the
same floor of the record less the healthy record (what the defect alone lifts it by), and
the residual the quasi-static chain and the dynamic chain (``shaft_dynamics`` at the rig file's mass and damping)
leave at the draw's hidden truth, unfitted, in units of the true noise (1.0: the model holds the record).

    python validation/bearing_feasibility.py --visibility --draws 24 --out results/validation/bearing_feasibility_visibility.json

``--first N`` starts at draw N (the draws are seeded by their index: draw N is the same record in any run).
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from piezobearing import config as cfg
from piezobearing.bearing.geometry import BearingGeometry, kinematic_frequencies
from piezobearing.diagnosis.bearing.answer import _peak
from piezobearing.diagnosis.bearing.effects import CATALOGUE, FAULT_TYPES
from piezobearing.diagnosis.bearing.floor import noise_floor
from piezobearing.diagnosis.bearing.lpm_records import draw_conditions, lpm_record
from piezobearing.diagnosis.bearing.model import BearingModel
from piezobearing.diagnosis.bearing.subject import SUBJECT
from piezobearing.signals.detection import noise_std_for_snr
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.stages.bearing_diagnosis import influence_from_config, read_influence

#: The record's parameters that are no catalogue effect's: the draw's speed goes into the nuisance shaft speed.
NOT_EFFECTS = ("shaft_speed", "shaft_dynamics", "mains_pickup")


def visibility(rig: dict, influence, hidden: dict, rec, index: int) -> dict:
    """Whether the record ``rec`` of draw ``index`` shows its hidden defect, and which model holds it (the
    module docstring, ``--visibility``); all levels against the record's true noise sigma."""
    kw = dict(sample_rate_Hz=2550.0, duration_s=0.5, seed=index)
    clean = lpm_record(rig, influence, hidden, snr_dB=float("inf"), **kw).voltage_V
    sigma = noise_std_for_snr(clean, 30.0)
    healthy_truth = {k: x for k, x in hidden.items() if not k.startswith(("outer_defect", "inner_defect", "roller_defect"))}
    healthy = lpm_record(rig, influence, healthy_truth, snr_dB=float("inf"), **kw).voltage_V
    v = rec.voltage_V
    dt = 1.0 / kw["sample_rate_Hz"]
    p = SUBJECT.problem((rec, influence), rig)
    r = p.record
    shaft = rig["bearing"]["shaft_speed_rpm"] / 60.0 * (1.0 + hidden["speed_deviation_ratio"])
    kin = r.rig.frequencies(shaft, hidden["cage_slip_ratio"])
    n = v.size
    w = np.hanning(n)
    floor = sigma**2 * float(np.sum(w**2))
    res = v - healthy
    spec = np.abs(np.fft.rfft((res - res.mean()) * w))
    df = 1.0 / (n * dt)

    def levels(base: float, shift: float = 0.0) -> list[float]:
        return [round(float(10 * np.log10(_peak(spec, k * base + shift, df) ** 2 / floor)), 1)
                for k in range(1, int(0.45 / dt // base) + 1)]

    out = {"sigma_V": sigma, "engine_floor_over_sigma": noise_floor(v, dt).voltage_noise_V / sigma,
           "floor_without_healthy_over_sigma": noise_floor(v - healthy, dt).voltage_noise_V / sigma,
           "defect_rms_over_sigma": float(np.std(clean - healthy) / sigma),
           "lines_dB": {"kBPFI": levels(kin["bpfi_Hz"]), "kBPFI-fr": levels(kin["bpfi_Hz"], -kin["shaft_Hz"]),
                        "kBPFI+fr": levels(kin["bpfi_Hz"], kin["shaft_Hz"]), "kBPFO": levels(kin["bpfo_Hz"])}}
    names = [name for name, e in CATALOGUE.items() if name not in NOT_EFFECTS
             and any(q.name in hidden for q in e.params(r))]
    truth = {k: x for k, x in hidden.items() if k != "speed_deviation_ratio"}
    for label, extra in (("quasi_static", []), ("dynamic", ["shaft_dynamics"])):
        model = BearingModel(tuple(CATALOGUE[k] for k in [*names, *extra]))
        values = {**model.defaults(r), **truth, "shaft_speed_Hz": shaft,
                  "start_phase_rad": float(np.radians(rig["bearing_diagnosis"]["synthetic_start_phase_deg"]))}
        if extra:
            dyn = r.rig.dynamics
            values.update(shaft_mass_kg=dyn.shaft_mass_kg, bearing_damping_N_s_per_m=dyn.bearing_damping_N_s_per_m)
        left = v - model.simulate(values, r)
        out[f"{label}_at_truth_over_sigma"] = float(np.std(left) / sigma)
    out["defects"] = [k for k in FAULT_TYPES if any(q.name in hidden for q in CATALOGUE[k].params(r))]
    return out


def joint_row(j: dict | None, said: list[str]) -> dict | None:
    """The joint dynamic search's entry (``dynamic_rung.joint``) in short: whether it replaced the diagnosis and why,
    the dynamic healthy model against the final one, each type's BIC drop, share and whether it passes and is
    identified, the floor before and after, its CPU (the console's line among ``said``)."""
    if not j:
        return None
    judged = j.get("with_roller_scatter") or j
    cpu = [float(m.split()[2]) for m in said if m.startswith("joint search: ") and m.split()[3:5] == ["s", "CPU"]]
    return {"replaced": j.get("replaced"), "why": j.get("why"), "best": j.get("best"),
            "healthy_over_final": j.get("healthy_over_final"), "cpu_s": cpu[-1] if cpu else None,
            "floor_V": [judged["floor"]["before_V"], judged["floor"]["after_V"]],
            "healthy_nrmse": judged["healthy"]["nrmse"],
            "types": {n: {k: t[k] for k in ("delta_bic", "excess_explained", "passes_rule", "identified", "nrmse")}
                      for n, t in j["types"].items()},
            "with_roller_scatter": None if j.get("with_roller_scatter") is None else {
                n: {k: t[k] for k in ("delta_bic", "excess_explained", "passes_rule", "identified", "nrmse")}
                for n, t in j["with_roller_scatter"]["types"].items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=40)
    ap.add_argument("--out", default="results/validation/bearing_feasibility.json")
    ap.add_argument("--influence", default=None, help="influence_line_healthy.csv (default: solved from the config)")
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--max-steps", type=int, default=1,
                    help="diagnostics.max_steps (1: the first ranking; the config's 4: the full ladder)")
    ap.add_argument("--joint", choices=["auto", "off"], default="auto",
                    help="bearing_diagnosis.joint_search (off: the diagnosis without the joint dynamic search)")
    ap.add_argument("--interval-correlation", choices=["auto", "off"], default="auto",
                    help="bearing_diagnosis.interval_correlation (off: the intervals of white residuals)")
    ap.add_argument("--first", type=int, default=0, help="the first draw (draw i is the same record in any run)")
    ap.add_argument("--visibility", action="store_true",
                    help="measure whether each record shows its defect and which model holds it, instead of the diagnosis")
    ap.add_argument("--envelope-only", action="store_true",
                    help="run the envelope detector on each record instead of the diagnosis")
    ap.add_argument("--steps-per-period", type=int, default=None,
                    help="bearing_diagnosis.dynamic_steps_per_period, the dynamic rung's search step (default: the config's)")
    args = ap.parse_args()
    config = cfg.load()
    config["diagnostics"]["max_steps"] = args.max_steps
    config["bearing_diagnosis"]["joint_search"] = args.joint
    config["bearing_diagnosis"]["interval_correlation"] = args.interval_correlation
    if args.steps_per_period:
        config["bearing_diagnosis"]["dynamic_steps_per_period"] = args.steps_per_period
    influence = read_influence(args.influence) if args.influence else influence_from_config(config)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows = []
    for i in range(args.first, args.first + args.draws):
        rig, hidden = draw_conditions(np.random.default_rng([args.seed, i]), copy.deepcopy(config))
        row = {"draw": i, "rig_radial_load_N": rig["bearing"]["radial_load_N"],
               "rig_radial_clearance_m": rig["bearing"]["radial_clearance_m"], "hidden": hidden}
        try:
            rec = lpm_record(rig, influence, hidden, 2550.0, 0.5, 30.0, i)
            if args.envelope_only:
                shaft_Hz = rig["bearing"]["shaft_speed_rpm"] / 60.0
                kin = kinematic_frequencies(BearingGeometry.from_config(rig["bearing"]), shaft_Hz).to_dict()
                e = envelope_detector.detect(rec.voltage_V, rec.sample_rate_Hz, kin, envelope_detector.Settings())
                row.update(verdict=e.fault_type, envelope={
                    "fault_type": e.fault_type,
                    "margin_dB": {t: f.margin_dB for t, f in e.families.items()},
                    "detected": {t: f.detected for t, f in e.families.items()}})
                rows.append(row)
                out.write_text(json.dumps({"command": "python validation/bearing_feasibility.py --envelope-only",
                                           "draws": len(rows), "rows": rows}, indent=1))
                print(f"draw {i}: envelope detector {e.fault_type}", flush=True)
                continue
            if args.visibility:
                row.update(verdict="measured", visibility=visibility(rig, influence, hidden, rec, i))
                rows.append(row)
                out.write_text(json.dumps({"command": "python validation/bearing_feasibility.py --visibility",
                                           "draws": len(rows), "rows": rows}, indent=1))
                vis = row["visibility"]
                print(f"draw {i}: {vis['defects']} defect {vis['defect_rms_over_sigma']:.2f} sigma, quasi-static at the "
                      f"truth {vis['quasi_static_at_truth_over_sigma']:.2f}, dynamic {vis['dynamic_at_truth_over_sigma']:.2f}, "
                      f"engine floor {vis['engine_floor_over_sigma']:.2f} sigma", flush=True)
                continue
            c0 = time.process_time()
            said: list[str] = []
            d = SUBJECT.diagnose((rec, influence), rig, progress=said.append)[1]
            rung = d.get("dynamic_rung") or {}
            row.update(verdict=d["verdict"], selected=d["selected"], fault_type=d["fault"]["type"],
                       fault_source=d["fault"].get("source"), cpu_s=time.process_time() - c0,
                       steps=[[st.get("added"), st.get("excess_explained")] for st in d["steps"][1:]],
                       dropped_steps=[[st.get("added"), st.get("excess_explained")] for st in d["dropped_steps"]],
                       lines=[[ev["type"], [[h["line"], h["excess_dB"]] for h in ev["lines"]]] for ev in d["fault"]["evidence"]],
                       dynamic_rung={"tried": rung.get("tried"), "accepted": rung.get("accepted")},
                       fault_params=d["fault"]["params"], fault_ci95=d["fault"]["ci95"], joint=joint_row(rung.get("joint"), said))
        except Exception as e:  # noqa: BLE001 - what this script counts
            row.update(verdict=None, error=f"{type(e).__name__}: {e}")
        rows.append(row)
        crashes = sum(r["verdict"] is None for r in rows)
        out.write_text(json.dumps({"command": "python validation/bearing_feasibility.py", "draws": len(rows),
                                   "crashes": crashes, "rows": rows}, indent=1))
        print(f"draw {i}: {row.get('verdict')} {row.get('fault_type')} ({row.get('fault_source')}) "
              f"{row.get('selected', row.get('error'))}, {row.get('cpu_s', 0):.0f} s", flush=True)


if __name__ == "__main__":
    main()
