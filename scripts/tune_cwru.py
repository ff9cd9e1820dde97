"""Choose the envelope detector's call settings on the CWRU fan-end set, and judge the choice by grouped
cross-validation.

``python scripts/tune_cwru.py [DATA_DIR] [--out results/validation]`` (DATA_DIR default
``../shared/data/cwru_fan_end``) reads every record once per spectrum setting of
:data:`piezobearing.signals.tuning.SPECTRUM_GRID` (single process; the readings are kept in
``OUT/tune_cwru_readings.pkl`` and reused while the data and the grid are unchanged), calls every record under
every decision setting, and writes ``tune_cwru.json`` and ``tune_cwru.md``: the setting chosen on all records
with its in-sample score, and per protocol (leave one fault size out; leave one fault location out) the
setting each fold chose without its held-out group and the score of the held-out calls, per true type.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import pickle
import time
from pathlib import Path

import numpy as np

from piezobearing.io import write_json
from piezobearing.io.vibration import read_vibration_record
from piezobearing.signals import tuning
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.stages.recording import read_rig

#: The grouped cross-validation protocols: a label column of labels.csv per protocol.
PROTOCOLS = {"leave one fault size out": "size_mil", "leave one fault location out": "location"}


def read_all(data: Path, labels: list[dict], spectra: list, cache: Path) -> list[list]:
    """Per spectrum setting, per record, the detector's reading (without spectra), from the cache where its
    key matches."""
    # the key holds the reading's fields: a cache of another version of the reading is read again
    key = hashlib.sha256(repr((sorted((lab["record"], (data / f"{lab['record']}.mat").stat().st_size)
                                       for lab in labels), spectra,
                               sorted(envelope_detector.Reading.__dataclass_fields__))).encode()).hexdigest()
    if cache.is_file():
        stored = pickle.loads(cache.read_bytes())
        if stored["key"] == key:
            return stored["readings"]
    records = []
    for lab in labels:
        rig = read_rig(data / f"{lab['record']}.yaml")
        rec = read_vibration_record(data / f"{lab['record']}.mat", rig.channel, rig.sample_rate_Hz)
        records.append((rec, rig.bearing.kinematics(rig.shaft_speed_rpm / 60.0).to_dict()))
    readings = []
    for i, s in enumerate(spectra):
        start = time.process_time()
        readings.append([envelope_detector.without_spectra(envelope_detector.measure(r.samples, r.sample_rate_Hz, k, s))
                         for r, k in records])
        print(f"spectrum setting {i + 1}/{len(spectra)}: {tuning.settings_dict(s, tuning.SPECTRUM_GRID)} "
              f"({time.process_time() - start:.1f} s CPU)", flush=True)
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_bytes(pickle.dumps({"key": key, "readings": readings}))
    return readings


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/cwru_fan_end")
    parser.add_argument("--out", default="results/validation")
    args = parser.parse_args()
    data, out = Path(args.data), Path(args.out)
    if not (data / "labels.csv").is_file():
        parser.error(f"{data}: no labels.csv here; give the CWRU fan-end folder as the first argument")
    labels = list(csv.DictReader((data / "labels.csv").open()))
    truths = [lab["fault_type"] for lab in labels]
    base = envelope_detector.Settings(min_type_separation_dB=0.0)
    spectra = tuning.spectrum_settings(base)
    decisions = tuning.decision_settings()
    readings = read_all(data, labels, spectra, out / "tune_cwru_readings.pkl")
    table = tuning.call_table(readings, spectra, decisions)
    everyone = list(range(len(labels)))
    chosen = tuning.choose(table, truths, everyone)
    default = 0
    right = [float(table.separations[chosen, r]) for r in everyone
             if tuning.outcome(truths[r], table.calls[chosen, r]) in ("right", "unknown") and truths[r] != "none"]
    summary = {
        "separation": {"supported_dB": table.settings[chosen].min_type_separation_dB,
                       "wrong_type_separations_dB": sorted(tuning.wrong_type_separations(table, truths, everyone)),
                       "wrong_type_calls": [
                           {"record": labels[r]["record"], "truth": truths[r], "call": table.calls[i, r],
                            "separation_dB": float(table.separations[i, r]),
                            "settings": tuning.settings_dict(table.settings[i])}
                           for i, st in enumerate(table.settings) if st.min_type_separation_dB == 0.0
                           for r in everyone if tuning.outcome(truths[r], table.calls[i, r]) == "wrong_type"],
                       "chosen_faulty_separations_dB": sorted(x for x in right if np.isfinite(x))},
        "data": str(data), "n_records": len(labels), "wrong_type_cost": tuning.WRONG_TYPE_COST,
        "grid": {"spectrum": {k: [list(v) if isinstance(v, tuple) else v for v in vs]
                              for k, vs in tuning.SPECTRUM_GRID.items()},
                 "decision": {k: list(v) for k, v in tuning.DECISION_GRID.items()}},
        "in_sample": {"settings": tuning.settings_dict(table.settings[chosen]),
                      "score": tuning.score(truths, list(table.calls[chosen]))},
        "previous_default": {"settings": tuning.settings_dict(table.settings[default]),
                             "score": tuning.score(truths, list(table.calls[default]))},
        "protocols": {},
        "records": [],
    }
    for name, column in PROTOCOLS.items():
        groups = [lab[column] for lab in labels]
        cv = tuning.cross_validate(table, truths, groups)
        summary["protocols"][name] = {
            "groups": column, "score": cv["score"],
            "supported_separation_dB": {g: tuning.supported_separation(
                table, truths, [r for r, h in enumerate(groups) if h != g]) for g in cv["chosen"]},
            "folds": {g: {"n_held_out": groups.count(g), "settings": tuning.settings_dict(table.settings[i]),
                          "held_out_score": tuning.score([t for t, h in zip(truths, groups, strict=True) if h == g],
                                                         [c for c, h in zip(cv["calls"], groups, strict=True) if h == g])}
                      for g, i in cv["chosen"].items()},
            "calls": cv["calls"],
        }
    for r, lab in enumerate(labels):
        summary["records"].append({
            "record": lab["record"], "source_name": lab["source_name"], "truth": truths[r],
            "call_in_sample": table.calls[chosen, r], "call_previous_default": table.calls[default, r],
            "margins_dB": table.margins[chosen][r],
            "separation_dB": None if np.isnan(table.separations[chosen, r]) else float(table.separations[chosen, r]),
            **{f"call_cv_{column}": summary["protocols"][name]["calls"][r] for name, column in PROTOCOLS.items()},
        })
    write_json(summary, out / "tune_cwru.json")
    (out / "tune_cwru.md").write_text(markdown(summary), encoding="utf-8")
    s = summary["in_sample"]["score"]
    print(f"in-sample: {summary['in_sample']['settings']}: right {s['right']}, wrong type {s['wrong_type']}, "
          f"unknown {s['unknown']}, missed {s['missed']}, false alarms {s['false_alarm']}")
    for name, p in summary["protocols"].items():
        s = p["score"]
        print(f"{name}: right {s['right']}, wrong type {s['wrong_type']}, unknown {s['unknown']}, missed "
              f"{s['missed']}, false alarms {s['false_alarm']}")


def _row(name: str, s: dict) -> str:
    per = s["per_type"]
    cells = [f"{per[t]['right']}/{per[t]['n']}" for t in ("outer_race", "inner_race", "rolling_element", "none")]
    return (f"| {name} | {s['right']}/{s['n']} | {s['wrong_type']} | {s['unknown']} | {s['missed']} | "
            f"{s['false_alarm']} | " + " | ".join(cells) + " |")


def markdown(summary: dict) -> str:
    lines = ["| protocol | right | wrong type | unknown | missed | false alarms | outer race | inner race | "
             "rolling element | healthy |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
             _row("previous default, in-sample", summary["previous_default"]["score"]),
             _row("chosen on all records, in-sample", summary["in_sample"]["score"])]
    for name, p in summary["protocols"].items():
        lines.append(_row(f"{name}, held out", p["score"]))
    lines += ["", f"Chosen on all records: `{summary['in_sample']['settings']}`.", ""]
    for name, p in summary["protocols"].items():
        lines += [f"{name}:", ""]
        for g, f in p["folds"].items():
            s = f["held_out_score"]
            lines.append(f"- held out {g} ({f['n_held_out']} records): `{f['settings']}`; held out: right "
                         f"{s['right']}, wrong type {s['wrong_type']}, unknown {s['unknown']}, missed {s['missed']}, "
                         f"false alarms {s['false_alarm']}")
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
