"""The diagnosis's error rates over seeds: every catalogue effect hidden, nothing hidden, two hidden.

A study, not a timing: for each case the paper's default synthetic record
(25 s at 1 kHz, 13 presses, 5 mN force noise, 2 mV voltage noise) is drawn
with ``--seeds`` seeds (1 .. N; the press shapes, sizes and both noises
change with the seed), the effects of the case are hidden in it at their
plausible sizes (each effect's ``example``, the values the tests hide,
stated with their reasons in the effect's module; ``d33_nonlinearity_strong`` is beta = 5e-3 1/N,
+10% sensitivity at 10 N, the upper end of the plausible range, where the
carried force noise is visibly louder at the press peaks), and the whole catalogue is diagnosed with the
default settings. Per case it records how often the verdict is
``explained``, how often the hidden effect(s) come first (for a single
effect: ranked first and selected first; an effect exactly equivalent to the
hidden one, ``Effect.equivalent_to``, counts as found), and the seeds that
failed, with their findings.

The targets: nothing hidden -> ``explained`` in >= 95% of seeds; one
effect hidden -> that effect first and ``explained`` in >= 90%.

Writes results/benchmarks/diagnosis_seeds.json.
Usage: python benchmarks/bench_diagnosis_seeds.py [--seeds 20] [--cases clean,d33_nonlinearity]
       [--duration-s 25] [--rate-Hz 1000] [--out ...]
(``--duration-s``/``--rate-Hz`` override the record's length and sampling rate, the presses scaled
with the length: another rig's record.)
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import piezobearing.config
from piezobearing.diagnosis.calibration.effects import CATALOGUE, ForceRecord
from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
from piezobearing.diagnosis.calibration.subject import diagnose_record
from piezobearing.diagnosis.settings import DiagnosticsSettings
from piezobearing.sensor.calibration import detect_impulses
from piezobearing.stages.calibration import nominal_circuit

#: Each effect's plausible size, its ``example`` (the one home of the hidden values; the module says why).
SINGLE = {name: dict(e.example) for name, e in CATALOGUE.items() if e.example}
MAINS = {"name": "mains_pickup", "params": SINGLE["mains_pickup"]}
DRIFT = {"name": "baseline_drift", "params": SINGLE["baseline_drift"]}
CASES: dict[str, list[dict]] = {"clean": []}
# the cases whose noise follows the signal first (the point of the study), then the rest of the catalogue
CASES["d33_nonlinearity_strong"] = [{"name": "d33_nonlinearity", "params": {"beta_per_N": 5e-3}}]
CASES.update(
    {name: [{"name": name, "params": SINGLE[name]}] for name in ("d33_nonlinearity", "sensitivity_drift")}
)
CASES.update({name: [{"name": name, "params": p}] for name, p in SINGLE.items() if name not in CASES})
CASES["channel_delay+mains_pickup"] = [{"name": "channel_delay", "params": SINGLE["channel_delay"]}, MAINS]
CASES["d33_nonlinearity+baseline_drift"] = [
    {"name": "d33_nonlinearity", "params": SINGLE["d33_nonlinearity"]},
    DRIFT,
]
CASES["sensitivity_drift+channel_delay"] = [
    {"name": "sensitivity_drift", "params": SINGLE["sensitivity_drift"]},
    {"name": "channel_delay", "params": SINGLE["channel_delay"]},
]


def aliases(name: str) -> set[str]:
    """The effect and those declared exactly equivalent to it (either direction)."""
    out = {name}
    for e in CATALOGUE.values():
        if e.name == name:
            out |= set(e.equivalent_to)
        elif name in e.equivalent_to:
            out.add(e.name)
    return out


def judge(hidden: list[dict], d: dict) -> dict:
    """Found / explained for one seed."""
    names = [h["name"] for h in hidden]
    selected = set(d["selected"])
    first = d["ranking"][0]["effect"] if d["ranking"] else None
    if not names:
        found = not d["selected"]
    elif len(names) == 1:
        ok = aliases(names[0])
        found = first in ok and bool(d["selected"]) and d["selected"][0] in ok
    else:
        found = all(aliases(n) & selected for n in names)
    return {
        "found": bool(found),
        "explained": d["verdict"] == "explained",
        "first": first,
        "selected": d["selected"],
        "verdict": d["verdict"],
        "final_chi2_per_sample": d["final"]["chi2_per_sample"],
        # the first step's margin over its runner-up (none when nothing was added)
        "margin_bic": (d["identifiability"]["steps"] or [{}])[0].get("margin_bic"),
        "runner_up": (d["identifiability"]["steps"] or [{}])[0].get("runner_up"),
        "findings": [
            {k: f.get(k) for k in ("test", "kind", "where", "frequency_Hz", "t0_s", "lag_s") if k in f}
            for f in d["unexplained"]
        ],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--duration-s", type=float, default=None)
    ap.add_argument("--rate-Hz", type=float, default=None)
    ap.add_argument("--out", default="results/benchmarks/diagnosis_seeds.json")
    args = ap.parse_args()
    config = piezobearing.config.load()
    syn = config["synthesis"]
    if args.duration_s is not None:  # as many presses per second as the default record
        syn["n_impulses"] = max(2, int(round(syn["n_impulses"] * args.duration_s / syn["duration_s"])))
        syn["duration_s"] = args.duration_s
    if args.sample_rate_Hz is not None:
        syn["sample_rate_Hz"] = args.sample_rate_Hz
    settings = DiagnosticsSettings.from_config(config["diagnostics"])
    fit_circuit = nominal_circuit(config, config["calibration"]["initial_resistance_ohm"])
    p = PressProtocol.from_config(config["synthesis"])
    out: dict = {
        "record": {
            "duration_s": p.duration_s,
            "sample_rate_Hz": p.sample_rate_Hz,
            "n_impulses": p.n_impulses,
        },
        "seeds": list(range(1, args.seeds + 1)),
        "requirement": "clean: explained >= 95%; one effect: first and explained >= 90%",
        "cases": {},
    }
    t_start = time.perf_counter()
    for case in args.cases.split(","):
        hidden = CASES[case]
        rows = {}
        for seed in out["seeds"]:
            m = synthesize(p, nominal_circuit(config), seed, hidden)
            t, f, v = m.time_s, m.force_N, m.voltage_V
            imps = detect_impulses(f, v, t[1] - t[0], 0.2, 0.8)
            _, d = diagnose_record(ForceRecord(t, f), v, fit_circuit, [], settings, imps)
            rows[str(seed)] = judge(hidden, d)
        n = len(rows)
        ok = [r["found"] and r["explained"] for r in rows.values()]
        out["cases"][case] = {
            "hidden": hidden,
            "explained_rate": sum(r["explained"] for r in rows.values()) / n,
            "found_rate": sum(r["found"] for r in rows.values()) / n,
            "found_and_explained_rate": sum(ok) / n,
            "failed_seeds": {s: r for s, r in rows.items() if not (r["found"] and r["explained"])},
            "per_seed": {
                s: {k: r[k] for k in ("first", "selected", "verdict", "runner_up", "margin_bic")} for s, r in rows.items()
            },
        }
        c = out["cases"][case]
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(
            json.dumps(out, indent=2) + "\n"
        )  # after every case: a partial run keeps its cases
        print(
            f"{case:36s} explained {c['explained_rate']:5.0%}  found {c['found_rate']:5.0%}  "
            f"both {c['found_and_explained_rate']:5.0%}  ({time.perf_counter() - t_start:.0f} s)",
            flush=True,
        )
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
