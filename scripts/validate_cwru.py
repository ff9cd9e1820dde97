"""Run the envelope detector over the shared CWRU fan-end set and write the confusion matrix.

``python scripts/validate_cwru.py [DATA_DIR] [--out results/validation]`` (DATA_DIR default
``../shared/data/cwru_fan_end``: feNN.mat, feNN.yaml, labels.csv) writes ``cwru.json`` (per record the
truth, the call, each family's margin, the band, the shaft speed found; the confusion matrix, rows truth,
columns call) and ``cwru.md`` (the matrix and the per-record table) into the output folder. Two checks of
false alarms on healthy bearings go with it: the healthy record cut into 5 s stretches, and every record's
drive-end channel against the drive-end bearing (an SKF 6205, healthy in the fan-end fault tests).
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.io import write_json
from piezobearing.io.vibration import read_vibration_record
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.stages.recording import detect_recording, read_rig

CALLS = ("outer_race", "inner_race", "rolling_element", "unknown", "none")
STRETCH_S = 5.0


def confusion(rows: list[dict]) -> dict:
    counts = {t: {c: 0 for c in CALLS} for t in CALLS}
    for r in rows:
        counts[r["truth"]][r["call"]] += 1
    right = sum(counts[t][t] for t in CALLS)
    wrong_type = sum(counts[t][c] for t in CALLS for c in CALLS
                     if c not in (t, "none", "unknown") and t not in ("none", "unknown"))
    unknown = sum(counts[t]["unknown"] for t in CALLS if t not in ("none", "unknown"))
    false_alarms = sum(counts["none"][c] for c in CALLS if c != "none")
    missed = sum(counts[t]["none"] for t in CALLS if t != "none")
    return {"rows": "truth", "columns": "call", "classes": list(CALLS), "counts": counts, "right": right,
            "n_records": len(rows), "wrong_type": wrong_type, "unknown": unknown, "missed": missed,
            "false_alarms": false_alarms}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/cwru_fan_end")
    parser.add_argument("--out", default="results/validation")
    args = parser.parse_args()
    data, out = Path(args.data), Path(args.out)
    if not (data / "labels.csv").is_file():
        parser.error(f"{data}: no labels.csv here; give the CWRU fan-end folder (its README, feNN.mat, feNN.yaml, "
                     "labels.csv) as the first argument")
    labels = list(csv.DictReader((data / "labels.csv").open()))
    rows, cpu = [], 0.0
    for lab in labels:
        start = time.process_time()
        result = detect_recording(data / f"{lab['record']}.mat", data / f"{lab['record']}.yaml")
        cpu += time.process_time() - start
        d = result.detection
        rows.append({"record": lab["record"], "source_name": lab["source_name"], "truth": lab["fault_type"],
                     "location": lab["location"], "size_mil": int(lab["size_mil"]),
                     "nominal_rpm": float(lab["shaft_speed_rpm_nominal"]), "call": d.fault_type,
                     "margins_dB": {f: e.margin_dB for f, e in d.families.items()},
                     "type_call": d.details.get("type_call"),
                     "band_Hz": list(d.band_Hz), "shaft_speed_found_rpm": 60.0 * d.shaft_rate_Hz,
                     "shaft_refined": d.details["shaft"]["refined"], "duration_s": result.record.duration_s})
        print(f"{lab['record']} {lab['source_name']:<18} truth {lab['fault_type']:<16} call {d.fault_type}", flush=True)
    matrix = confusion(rows)
    settings = envelope_detector.Settings()
    healthy = [r for r in labels if r["fault_type"] == "none"]
    stretches = []
    for lab in healthy:
        rig = read_rig(data / f"{lab['record']}.yaml")
        full = read_vibration_record(data / f"{lab['record']}.mat", rig.channel, rig.sample_rate_Hz)
        n = int(STRETCH_S * full.sample_rate_Hz)
        kin = rig.bearing.kinematics(rig.shaft_speed_rpm / 60.0).to_dict()
        for k in range(full.samples.size // n):
            d = envelope_detector.detect(full.samples[k * n:(k + 1) * n], full.sample_rate_Hz, kin, settings)
            stretches.append({"record": lab["record"], "start_s": k * STRETCH_S, "call": d.fault_type,
                              "margin_dB": d.margin_dB})
    drive_end = RollingBearing.from_designation("SKF 6205")
    de_rows = []
    for lab in labels:
        rec = read_vibration_record(data / f"{lab['record']}.mat", "_DE_time", 12000.0)
        kin = drive_end.kinematics(float(lab["shaft_speed_rpm_nominal"]) / 60.0).to_dict()
        d = envelope_detector.detect(rec.samples, rec.sample_rate_Hz, kin, settings)
        de_rows.append({"record": lab["record"], "channel": rec.channel, "call": d.fault_type, "margin_dB": d.margin_dB})
    summary = {
        "data": str(data), "detector": "envelope", "settings": {k: getattr(settings, k) for k in settings.__dataclass_fields__},
        "confusion": matrix, "records": rows,
        "healthy_stretches": {"stretch_s": STRETCH_S, "n": len(stretches),
                              "false_alarms": sum(s["call"] != "none" for s in stretches), "stretches": stretches},
        "drive_end_healthy_6205": {"n": len(de_rows), "false_alarms": sum(r["call"] != "none" for r in de_rows),
                                   "records": de_rows},
    }
    write_json(summary, out / "cwru.json")
    (out / "cwru.md").write_text(markdown(summary), encoding="utf-8")
    print(f"right {matrix['right']}/{matrix['n_records']}, wrong type {matrix['wrong_type']}, unknown "
          f"{matrix['unknown']}, missed "
          f"{matrix['missed']}, false alarms {matrix['false_alarms']}; healthy stretches "
          f"{summary['healthy_stretches']['false_alarms']}/{len(stretches)}; drive-end 6205 "
          f"{summary['drive_end_healthy_6205']['false_alarms']}/{len(de_rows)}; detector CPU {cpu:.1f} s")


def markdown(summary: dict) -> str:
    m = summary["confusion"]
    head = "| truth \\ call | " + " | ".join(c.replace("_", " ") for c in CALLS) + " |"
    lines = [head, "|---|" + "---:|" * len(CALLS)]
    for t in (c for c in CALLS if c != "unknown"):
        lines.append(f"| {t.replace('_', ' ')} | " + " | ".join(str(m["counts"][t][c]) for c in CALLS) + " |")
    lines += ["", f"Right: {m['right']} of {m['n_records']}; wrong type: {m['wrong_type']}; unknown type: "
              f"{m['unknown']}; missed: {m['missed']}; "
              f"false alarms: {m['false_alarms']}.", "",
              "| record | CWRU name | truth | call | outer race [dB] | inner race [dB] | rolling element [dB] |",
              "|---|---|---|---|---:|---:|---:|"]
    for r in summary["records"]:
        mg = r["margins_dB"]
        lines.append(f"| {r['record']} | {r['source_name']} | {r['truth']} | {r['call']} | {mg['outer_race']:+.1f} | "
                     f"{mg['inner_race']:+.1f} | {mg['rolling_element']:+.1f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
