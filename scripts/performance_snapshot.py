"""Write ``docs/_data/performance.json``, the numbers of the performance page, from benchmark result files.

Reads ``results/benchmarks/<name>.json`` (written by ``benchmarks/bench_<name>.py``; ``command_<name>.json`` by
``benchmarks/bench_command.py`` for whole commands: the paper, the studies, the tests, the install) and the
workflow's per-rule benchmark files ``results/benchmarks/rules/**/*.tsv`` (Snakemake's ``benchmark:``). Each row
of the snapshot holds what was measured, its numbers with their units, the text the page shows, the command that
measures it, the file it was read from and the machine it ran on (the machine running this script: run it where
the benchmarks ran). A row whose file is absent keeps the snapshot's previous row if there is one, and is
otherwise left out: the page lists it under "not measured" with its command, never with a number.

Usage, from the repository root::

    python scripts/performance_snapshot.py                 # every row whose file exists; others kept
    python scripts/performance_snapshot.py --rules-command "snakemake --cores 1 --configfile config/ci.yaml"

``--rules-command`` names the workflow run whose per-rule files are read (without it the per-rule table is kept
as it was).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import platform
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from piezobearing import config as config_loader

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "results" / "benchmarks"
SNAPSHOT = ROOT / "docs" / "_data" / "performance.json"


# --------------------------------------------------------------------------- formatting


def seconds(x: float) -> str:
    """A duration as people read it: 0.9 ms, 67 ms, 8.6 s, 229 s, 4 min 10 s, 2 h 51 min."""
    if x < 1e-3:
        return f"{x * 1e6:.2g} µs"
    if x < 1.0:
        return f"{_sig(x * 1e3)} ms"
    if x < 100.0:
        return f"{_sig(x)} s"
    if x < 600.0:
        return f"{x:.0f} s"
    if x < 3600.0:
        return f"{int(x // 60)} min {x % 60:.0f} s"
    return f"{int(x // 3600)} h {(x % 3600) / 60:.0f} min"


def _sig(x: float) -> str:
    """Three significant digits below 100, whole numbers above (``0.436``, ``27.9``, ``229``)."""
    if x >= 100:
        return f"{x:.0f}"
    return f"{x:.3g}" if x >= 1 else f"{x:.2g}"


def seconds_range(low: float, high: float) -> str:
    """``1.9-11.1 s`` when both ends read in one unit, else ``450 ms-1.2 s``."""
    a, b = seconds(low), seconds(high)
    if a.split()[-1] == b.split()[-1] and len(a.split()) == 2 and len(b.split()) == 2:
        return f"{a.split()[0]}-{b}"
    return f"{a}-{b}"


def ratio(x: float) -> str:
    return f"{x:.3g}x" if x < 10 else f"{x:.0f}x"


def megabytes(x: float) -> str:
    return f"{x / 1000:.2f} GB" if x >= 1000 else f"{x:.0f} MB"


def q(label: str, value: float, unit: str) -> dict:
    """One measured quantity of a row."""
    return {"quantity": label, "value": value, "unit": unit}


# --------------------------------------------------------------------------- rows


@dataclass(frozen=True)
class Row:
    """One row of the page: ``read`` turns the benchmark file's dict into (value text, memory text, quantities)."""

    id: str
    what: str
    file: str
    command: str
    read: Callable[[dict], tuple[str, str, list[dict]] | None]  # None: the file holds no value for this row


def _command_row(d: dict) -> tuple[str, str, list[dict]]:
    if not d.get("exit_ok", False):
        raise ValueError(f"the command failed: {d.get('command')}")
    text = f"{seconds(d['wall_s'])} wall, {seconds(d['cpu_s'])} CPU"
    qs = [q("wall", d["wall_s"], "s"), q("CPU", d["cpu_s"], "s"), q("largest process", d["peak_rss_MB"], "MB")]
    return text, f"{megabytes(d['peak_rss_MB'])} largest process", qs


def _studies(d: dict) -> tuple[str, str, list[dict]]:
    """Each study's cases (the jobs of rule ``study_case``, start-up included) from ``bench_studies.py``."""
    parts, qs = [], []
    for name, s in d["studies"].items():
        parts.append(f"{name}: {s['cases']} cases, {seconds(s['cases_cpu_s'])} CPU "
                     f"(median case {seconds(s['case_cpu_median_s'])}, largest {seconds(s['case_cpu_max_s'])})")
        qs += [q(f"{name}, cases CPU", s["cases_cpu_s"], "s"), q(f"{name}, median case CPU", s["case_cpu_median_s"], "s")]
    name, largest = max(d["studies"].items(), key=lambda kv: kv[1]["peak_rss_MB"])
    return "; ".join(parts), f"{megabytes(largest['peak_rss_MB'])} largest job ({name})", qs


def _install_row(d: dict) -> tuple[str, str, list[dict]]:
    text, _, qs = _command_row(d)
    return f"{megabytes(d['size_MB'])} on disk ({text})", "–", qs + [q("size", d["size_MB"], "MB")]


def _sensor_fem(d: dict) -> tuple[str, str, list[dict]]:
    m = d["default_mesh"]
    dof = m["n_dof_displacement"] + m["n_dof_potential"]
    text = f"{seconds(m['total_s'])} (modal {seconds(m['modal_s'])}, harmonic {seconds(m['harmonic_s'])}), {dof / 1000:.1f} k DOF"
    return text, f"{d['peak_rss_GB']:.2f} GB (the benchmark's whole process: both stages, both meshes, the direct solves)", [q("modal", m["modal_s"], "s"), q("harmonic", m["harmonic_s"], "s"),
                                               q("peak RSS", d["peak_rss_GB"], "GB"), q("DOF", dof, "1")]


def _sensor_reduction(d: dict) -> tuple[str, str, list[dict]]:
    r = d["reduction"]
    text = (f"{seconds(r['reduced_s_per_frequency'])} against {seconds(r['direct_complex_solve_s_per_frequency'])} "
            f"(coarsest mesh), relative difference {r['max_rel_error']:.1e}")
    return text, "–", [q("reduced", r["reduced_s_per_frequency"], "s"),
                       q("direct", r["direct_complex_solve_s_per_frequency"], "s"), q("difference", r["max_rel_error"], "1")]


def _housing(d: dict) -> tuple[str, str, list[dict]]:
    text = (f"{seconds(d['reduced_s'])} against {seconds(d['direct_s'])} ({ratio(d['speedup'])}), "
            f"RMS difference {d['rms_rel_diff']:.1e}")
    return text, "–", [q("reduced", d["reduced_s"], "s"), q("direct", d["direct_s"], "s"), q("RMS difference", d["rms_rel_diff"], "1")]


def _solver_level(pick: str) -> Callable[[dict], tuple[str, str, list[dict]] | None]:
    """The housing factorisation at the default mesh level (``pick="default"``) or at the finest level measured
    above it (``"finest"``; None when no level above the default was measured)."""

    def read(d: dict) -> tuple[str, str, list[dict]] | None:
        if "housing" not in d:  # bench_solvers.py --only snr,sensor
            return None
        default = float(config_loader.load()["housing"]["mesh_level"])
        levels = {float(k.split("_")[1]): k for k in d["housing"]}
        level = default if pick == "default" else max(levels)
        if level not in levels or (pick == "finest" and level <= default):
            return None
        row = d["housing"][levels[level]]
        p, s = row["pardiso"], row["superlu"]
        text = (f"{seconds(p['factor_s'])} against {seconds(s['factor_s'])} ({ratio(s['factor_s'] / p['factor_s'])}), "
                f"{p['factor_nnz'] / 1e6:.1f} M against {s['factor_nnz'] / 1e6:.1f} M factor entries, "
                f"level {level:g}, {row['n_dofs'] / 1000:.1f} k DOF")
        qs = [q("PARDISO", p["factor_s"], "s"), q("SuperLU", s["factor_s"], "s"), q("DOF", row["n_dofs"], "1")]
        if "factor_cpu_s" in p:  # the process's CPU seconds of each factorisation, load-insensitive
            text += f"; CPU {seconds(p['factor_cpu_s'])} against {seconds(s['factor_cpu_s'])}"
            qs += [q("PARDISO CPU", p["factor_cpu_s"], "s"), q("SuperLU CPU", s["factor_cpu_s"], "s")]
        memory = "–"
        if pick == "finest" and "peak_rss_MB" in row:  # the levels run coarse to fine: the finest holds the peak
            memory = f"{megabytes(row['peak_rss_MB'])} (the benchmark's whole process, both solvers)"
            qs.append(q("peak RSS", row["peak_rss_MB"], "MB"))
        return text, memory, qs

    return read


def _solver_sensor(d: dict) -> tuple[str, str, list[dict]] | None:
    if "sensor" not in d:
        return None
    p, s = d["sensor"]["pardiso"], d["sensor"]["superlu"]
    tp, ts = p["factor_s"] + p["modes_s"], s["factor_s"] + s["modes_s"]
    return f"{seconds(tp)} against {seconds(ts)} ({ratio(ts / tp)})", "–", [q("PARDISO", tp, "s"), q("SuperLU", ts, "s")]


def _snr_sweep(d: dict) -> tuple[str, str, list[dict]] | None:
    if "snr_study" not in d:
        return None
    r = d["snr_study"]["fixed"]
    return (f"{seconds(r['batch_s'])} against {seconds(r['loop_s'])} ({ratio(r['loop_s'] / r['batch_s'])})", "–",
            [q("batch", r["batch_s"], "s"), q("record by record", r["loop_s"], "s")])


def _lpm(d: dict) -> tuple[str, str, list[dict]]:
    text = (f"{seconds(d['compiled_s'])} against {seconds(d['python_s'])} ({ratio(d['ratio_python_over_compiled'])}), "
            f"{d['steps'] / 1000:.0f} k steps, loads equal to {d['max_load_diff_rel_to_peak']:.0e} of the peak")
    return text, "–", [q("compiled", d["compiled_s"], "s"), q("numpy loop", d["python_s"], "s")]


def _surrogate(d: dict) -> tuple[str, str, list[dict]]:
    a, b = d["record_2s_2550Hz_s"], d["record_2s_25600Hz_s"]
    return f"{seconds(a)} at 2550 Hz, {seconds(b)} at 25.6 kHz", "–", [q("2550 Hz", a, "s"), q("25.6 kHz", b, "s")]


def _signals(d: dict) -> tuple[str, str, list[dict]]:
    a, b = d["seconds_per_record_fixed_1s"], d["seconds_per_record_kurtogram_1s"]
    return f"{seconds(a)} / {seconds(b)}", "–", [q("fixed band", a, "s"), q("kurtogram", b, "s")]


def _detect_record(d: dict) -> tuple[str, str, list[dict]]:
    text = f"{seconds(d['envelope_detector_cpu_s'])} CPU for one record of {d['record']}"
    qs = [q("CPU", d["envelope_detector_cpu_s"], "s")]
    if "command_cpu_s" in d:
        cpu = min(d["command_cpu_s"])
        text += f"; `piezobearing detect` on {d['command_record']}: {seconds(cpu)} CPU"
        qs.append(q("command CPU", cpu, "s"))
    return text, "–", qs


def _baseline(d: dict) -> tuple[str, str, list[dict]]:
    a, b = d["2550_Hz"]["baseline_cpu_s_alias_folds_1"], d["25600_Hz"]["baseline_cpu_s_alias_folds_1"]
    return f"{seconds(a)} at 2550 Hz, {seconds(b)} at 25.6 kHz", "–", [q("2550 Hz", a, "s"), q("25.6 kHz", b, "s")]


def _diagnostics(d: dict) -> tuple[str, str, list[dict]]:
    cpu = [c["cpu_seconds"] for c in d["cases"].values()]
    return (f"{seconds_range(min(cpu), max(cpu))} CPU over {len(cpu)} records", "–",
            [q("fastest", min(cpu), "s"), q("slowest", max(cpu), "s")])


def _diagnosis_bearing(d: dict) -> tuple[str, str, list[dict]]:
    parts, qs = [], []
    for fs, label in ((2550.0, "2550 Hz"), (25600.0, "25.6 kHz")):
        runs = {r["hidden"]: r for r in d["runs"] if r["sample_rate_Hz"] == fs and "cpu_seconds" in r}
        cells = [seconds(runs[h]["cpu_seconds"]) if h in runs else "failed"
                 for h in ("healthy", "outer_race_defect", "inner_race_defect")]
        parts.append(" / ".join(cells) + f" CPU at {label}")
        qs += [q(f"{h} at {label}", r["cpu_seconds"], "s") for h, r in runs.items()]
    return "; ".join(parts), "–", qs


def _clock_drift(d: dict) -> tuple[str, str, list[dict]]:
    name, p = next(iter(d["parts"].items()))
    text = (f"{seconds(p['current_cpu_s'])} CPU against {seconds(p['previous_cpu_s'])} "
            f"({ratio(p['ratio_previous_over_current'])}), equal to {p['max_abs_difference']:.1e} ({name})")
    return text, "–", [q("current", p["current_cpu_s"], "s"), q("previous", p["previous_cpu_s"], "s")]


def _dynamic_rung(d: dict) -> tuple[str, str, list[dict]] | None:
    """The whole running-bearing diagnosis of 2 s LPM records with ``dynamic_rung`` off, then auto, per case."""
    if "search" not in d:  # bench_shaft_dynamics.py --accuracy only
        return None
    runs = d["search"]
    cases = sorted({k.rsplit(", dynamic_rung ", 1)[0] for k in runs}, key=lambda k: (k.rsplit(" @ ", 1)[1], k))
    parts, qs = [], []
    for case in cases:
        off, auto = runs.get(f"{case}, dynamic_rung off"), runs.get(f"{case}, dynamic_rung auto")
        if off is None or auto is None:
            continue
        name, rate = case.rsplit(" @ ", 1)
        label = name if rate == "2550 Hz" else f"{name} at {float(rate.split()[0]) / 1000:g} kHz"
        rung = "accepted" if auto["rung_accepted"] else ("not accepted" if auto["rung_tried"] else "not tried")
        parts.append(f"{label}: {seconds(off['cpu_s'])} / {seconds(auto['cpu_s'])} ({rung})")
        qs += [q(f"{label}, off", off["cpu_s"], "s"), q(f"{label}, auto", auto["cpu_s"], "s")]
    return "CPU, off / auto: " + "; ".join(parts), "–", qs


def _sensor_design(d: dict) -> tuple[str, str, list[dict]]:
    rows = [r for design in d["designs"].values() for r in design if r["multiplier"] == 1.0]
    secs = [r["seconds"] for r in rows]
    dofs = [r["n_dof"] for r in rows]
    err = max(abs(e) for r in rows for e in r["error_percent_vs_finest"].values())
    text = (f"{seconds_range(min(secs), max(secs))} ({min(dofs) / 1000:.1f}-{max(dofs) / 1000:.1f} k DOF), "
            f"errors ≤ {err:.1f} % against the finest mesh")
    return text, "–", [q("fastest", min(secs), "s"), q("slowest", max(secs), "s"), q("largest error", err, "%")]


def _large_record(d: dict) -> tuple[str, str, list[dict]]:
    """The record check's CPU seconds (a fresh process each, imports included: the wall seconds of an idle
    machine), first start and later starts."""
    a, b = d["check_first_start"], d["check_second_start"]
    text = (f"{seconds(a['cpu_seconds'])} / {seconds(b['cpu_seconds'])} CPU ({d['record_MB']:.0f} MB record, "
            f"{d['rows'] / 1e6:.0f} M rows)")
    return text, f"{megabytes(a['peak_rss_MB'])} / {megabytes(b['peak_rss_MB'])}", [
        q("first start", a["cpu_seconds"], "s"), q("later start", b["cpu_seconds"], "s"),
        q("first start peak RSS", a["peak_rss_MB"], "MB")]


def _calibrated_seed(d: dict) -> tuple[str, str, list[dict]]:
    """The comparison's calibrated test: median CPU per seed at rest / under base motion, and per case."""
    parts, counts, qs, cases = [], [], [], []
    for key, label in (("at_rest", "at rest"), ("base_motion", "under base motion")):
        c = d["conditions"].get(key)
        if not c or "healthy" not in c:
            continue
        seeds = [s for s in (c.get("healthy"), c.get("faulty")) if s]
        median = c["healthy"]["median_cpu_s"]
        parts.append((seconds(median), label))
        counts.append(str(sum(s["seeds"] for s in seeds)))
        qs.append(q(f"healthy seed, {label}", median, "s"))
        if c.get("faulty"):
            qs.append(q(f"faulty seed, {label}", c["faulty"]["median_cpu_s"], "s"))
        if c.get("case_cpu_s") is not None:
            cases.append(c["case_cpu_s"])
            qs.append(q(f"case, {label}", c["case_cpu_s"], "s"))
    nh, nf = d["case_seeds"]
    text = (" / ".join(p for p, _ in parts) + " CPU per healthy seed " + " / ".join(lb for _, lb in parts)
            + f" (median; {' / '.join(counts)} seeds)")
    if cases:
        text += f"; a case of {nh} + {nf} seeds {seconds(max(cases))} CPU"
    memory = f"{megabytes(d['peak_rss_MB'])} largest process" if "peak_rss_MB" in d else "–"
    return text, memory, qs


def _comparison_kernels(d: dict) -> tuple[str, str, list[dict]]:
    """The sensor comparison's heights and projection, compiled against numpy, per realisation."""
    h, p = d["heights"], d["projection"]
    text = (f"heights {seconds(h['compiled_cpu_s'])} against {seconds(h['numpy_cpu_s'])} "
            f"({ratio(h['numpy_over_compiled'])}, {h['points'] / 1e6:.2f} M points); projection "
            f"{seconds(p['compiled_cpu_s'])} against {seconds(p['numpy_cpu_s'])} ({ratio(p['numpy_over_compiled'])}, "
            f"{p['samples'] / 1000:.1f} k samples); equal to "
            f"{max(h['relative_difference'], p['relative_difference_sensor'], p['relative_difference_modal']):.0e}")
    return text, "–", [q("heights, compiled", h["compiled_cpu_s"], "s"), q("heights, numpy", h["numpy_cpu_s"], "s"),
                       q("projection, compiled", p["compiled_cpu_s"], "s"),
                       q("projection, numpy", p["numpy_cpu_s"], "s")]


def _startup(d: dict) -> tuple[str, str, list[dict]]:
    """Start-up against a previous revision: ``piezobearing detect`` on one record, the package imports of
    every workflow script (what each job of its rule pays before its work) and a dry run of the CI config,
    CPU seconds."""
    det = d["commands"]["piezobearing detect (10 s at 12 kHz)"]
    jobs = d["job_imports_cpu_s"]
    text = (f"`piezobearing detect` on {d['record']}.mat: {seconds(det['new']['cpu_s'])} CPU against "
            f"{seconds(det['old']['cpu_s'])} ({ratio(det['ratio_cpu'])}); the package imports of the "
            f"{len(d['job_imports'])} workflow scripts, summed: {seconds(jobs['new'])} CPU against "
            f"{seconds(jobs['old'])} ({ratio(jobs['old'] / jobs['new'])})")
    quantities = [q("detect, CPU", det["new"]["cpu_s"], "s"), q("detect, CPU before", det["old"]["cpu_s"], "s"),
                  q("job imports, CPU", jobs["new"], "s"), q("job imports, CPU before", jobs["old"], "s")]
    dry = d["commands"].get("snakemake -n (CI config, nothing built)")
    if dry is not None:
        text += (f"; `snakemake -n --configfile config/ci.yaml`, nothing built: {seconds(dry['new']['cpu_s'])} CPU "
                 f"against {seconds(dry['old']['cpu_s'])} ({ratio(dry['ratio_cpu'])})")
        quantities += [q("dry run, CPU", dry["new"]["cpu_s"], "s"), q("dry run, CPU before", dry["old"]["cpu_s"], "s")]
    return text, "–", quantities


ROWS = [
    Row("paper", "the whole paper workflow in a fresh clone (all figures, the scorecard, both diagnoses)",
        "command_paper.json", "`python benchmarks/bench_command.py paper -- snakemake --cores 2`", _command_row),
    Row("ci", "the CI workflow, `config/ci.yaml` (every rule on the reduced case)", "command_ci.json",
        "`python benchmarks/bench_command.py ci -- snakemake --cores 1 --configfile config/ci.yaml`", _command_row),
    Row("study_all", "every parameter study on the paper config, `study_all`, after the paper",
        "command_study_all.json", "`python benchmarks/bench_command.py study_all -- snakemake --cores 2 study_all`",
        _command_row),
    Row("studies", "each parameter study on the paper config: its cases' jobs (rule `study_case`) in a `study_all` run",
        "studies.json", "`python benchmarks/bench_studies.py` (after the `study_all` row's command)", _studies),
    Row("study_sensor_design", "the sensor_design study on the paper config (its 25 designs), after the paper",
        "command_study_sensor_design.json",
        "`python benchmarks/bench_command.py study_sensor_design -- snakemake --cores 2 study_sensor_design`",
        _command_row),
    Row("tests", "the test suite", "command_tests.json", "`python benchmarks/bench_command.py tests -- pytest -n 2`",
        _command_row),
    Row("install", "the install: a new venv with `pip install .`, its wheels at hand (pip's cache or a local "
        "mirror; a first download adds its own time)", "command_install.json",
        "`python benchmarks/bench_command.py install --size /tmp/pb-venv -- sh -c "
        "'python3.11 -m venv /tmp/pb-venv && /tmp/pb-venv/bin/pip install .'`", _install_row),
    Row("sensor_fem", "sensor FEM, modal + harmonic, default mesh (quadratic)", "sensor_fem.json",
        "`python benchmarks/bench_sensor_fem.py`", _sensor_fem),
    Row("sensor_reduction", "sensor FEM reduced model against a direct complex solve, per frequency", "sensor_fem.json",
        "`python benchmarks/bench_sensor_fem.py`", _sensor_reduction),
    Row("housing", "housing transient, 1 s: reduced (modes + static correction) against direct (generalized-α)",
        "housing.json", "`python benchmarks/bench_housing.py`", _housing),
    Row("solvers_default", "sparse factorisation, housing K at the default mesh level: MKL PARDISO against SuperLU",
        "solvers.json", "`python benchmarks/bench_solvers.py`", _solver_level("default")),
    Row("solvers_finest", "sparse factorisation, housing K at the finest level of `housing.convergence_levels`",
        "solvers.json", "`python benchmarks/bench_solvers.py`",
        _solver_level("finest")),
    Row("solvers_sensor", "sensor saddle matrix, default mesh, factorisation and modes: PARDISO against SuperLU",
        "solvers.json", "`python benchmarks/bench_solvers.py`", _solver_sensor),
    Row("lpm", "bearing LPM, 1 s of bearing time: numba kernel against the numpy loop", "lpm.json",
        "`python benchmarks/bench_lpm.py`", _lpm),
    Row("surrogate", "quasi-static surrogate, 2 s record (table built once)", "surrogate.json",
        "`python benchmarks/bench_surrogate.py`", _surrogate),
    Row("signals", "envelope analysis of 1 s at 2550 Hz: fixed band / kurtogram", "signals.json",
        "`python benchmarks/bench_signals.py`", _signals),
    Row("snr_sweep", "SNR sweep of one record, fixed band: batch against record by record", "solvers.json",
        "`python benchmarks/bench_solvers.py`", _snr_sweep),
    Row("cwru_validate", "the envelope detector's validation on the 46 CWRU fan-end records of 10-20 s (the whole script: "
        "reading, detection, the confusion matrix)", "command_cwru_validate.json",
        "`python benchmarks/bench_command.py cwru_validate -- python scripts/validate_cwru.py ../shared/data/cwru_fan_end "
        "--out results/validation` (see [CWRU](validation/cwru.md))", _command_row),
    Row("detect_folder", "`piezobearing detect` over the 46-record fan-end folder, each record's report and figure, the "
        "table and the trend", "command_detect_folder.json",
        "`python benchmarks/bench_command.py detect_folder -- piezobearing detect ../shared/data/cwru_fan_end "
        "--glob '*.mat' --out results/detect/fan_end`", _command_row),
    Row("tune_cwru", "the call settings' grid on the 46 CWRU records and the grouped cross-validation",
        "command_tune_cwru.json", "`python benchmarks/bench_command.py tune_cwru -- python scripts/tune_cwru.py "
        "../shared/data/cwru_fan_end --out results/validation`", _command_row),
    Row("startup", "start-up of `piezobearing detect` (a 10 s, 12 kHz record: reading, detection, detection.json, "
        "report.md and detection.png), of the workflow's jobs and of a dry run, against the revision before the "
        "scorecard's jobs dropped the sensor FEM and the config files were read with libyaml (`--old`)",
        "startup.json",
        "`python benchmarks/bench_startup.py --old 7303243 --data ../shared/data/cwru_fan_end --runs 7`", _startup),
    Row("detect_record", "envelope detector (`piezobearing detect`) on a 12 kHz record", "detect_record.json",
        "`python benchmarks/bench_detect_record.py`", _detect_record),
    Row("baseline", "baseline detector, 1 s record, CPU on one BLAS thread", "detector.json",
        "`python benchmarks/bench_detector.py`", _baseline),
    Row("diagnostics", "calibration diagnosis of a 25 s, 1 kHz record, whole catalogue", "diagnostics.json",
        "`python benchmarks/bench_diagnostics.py`", _diagnostics),
    Row("diagnosis_bearing", "running-bearing diagnosis, 2 s record, whole catalogue: healthy / 0.6 mm outer race / "
        "0.8 mm inner race", "diagnosis_bearing.json", "`python benchmarks/bench_diagnosis_bearing.py`",
        _diagnosis_bearing),
    Row("dynamic_rung", "running-bearing diagnosis, 2 s LPM records at 2550 Hz (one at 25.6 kHz), whole search with "
        "`bearing_diagnosis.dynamic_rung` `off` / `auto` (the default)", "shaft_dynamics.json",
        "`python benchmarks/bench_shaft_dynamics.py --search`", _dynamic_rung),
    Row("clock_drift", "`clock_drift` effect's windowed-sinc reading of a 25001-sample record: a series for I0 and "
        "one sine a sample, against numpy's `i0` and `sinc` for every tap",
        "clock_drift.json", "`python benchmarks/bench_clock_drift.py`", _clock_drift),
    Row("calibrated_seed", "the sensor comparison's calibrated test, one seed on the paper config (a rig realisation: "
        "the LPM with the healthy bearing's floor, the housing, both sensors and the envelope detector)",
        "calibrated_seed.json", "`python benchmarks/bench_calibrated_seed.py --seeds 5`",
        _calibrated_seed),
    Row("comparison_kernels", "sensor comparison, one realisation of the rig: the surfaces' heights on the LPM's "
        "fine grid and the roller loads' projection on the housing, compiled against numpy (CPU, warm)",
        "comparison_kernels.json", "`python benchmarks/bench_comparison_kernels.py`", _comparison_kernels),
    Row("sensor_design", "sensor-design study mesh, one design at multiplier 1.0", "sensor_design.json",
        "`python benchmarks/bench_sensor_design.py`", _sensor_design),
    Row("large_record", "the workflow's check of a large calibration record, run at every start (`snakemake -n` "
        "too): first start / later starts (the result cached by the record's content hash)", "large_record.json",
        "`python benchmarks/bench_large_record.py`", _large_record),
]


# --------------------------------------------------------------------------- machine and rules


def machine() -> dict:
    """The machine this script runs on: CPU model, cores, memory, OS and Python."""
    cpuinfo = Path("/proc/cpuinfo")
    model = next((line.split(":", 1)[1].strip() for line in cpuinfo.read_text().splitlines()
                  if line.startswith("model name")), platform.processor()) if cpuinfo.exists() else platform.processor()
    mem = next((int(line.split()[1]) for line in Path("/proc/meminfo").read_text().splitlines()
                if line.startswith("MemTotal:")), 0) if Path("/proc/meminfo").exists() else 0
    m = {"cpu": model, "cores": os.cpu_count(), "memory_GiB": round(mem / 2**20, 1),
         "system": f"{platform.system()} {platform.machine()}", "python": platform.python_version()}
    m["id"] = hashlib.sha256(json.dumps(m, sort_keys=True).encode()).hexdigest()[:8]
    return m


def rule_rows(folder: Path) -> list[dict]:
    """Per rule (a rule with wildcards: its jobs together) the jobs' wall seconds, CPU seconds and peak RSS."""
    jobs: dict[str, list[dict]] = {}
    for tsv in sorted(folder.rglob("*.tsv")):
        rel = tsv.relative_to(folder)
        rule = rel.parts[0] if len(rel.parts) > 1 else tsv.stem
        with tsv.open() as f:
            jobs.setdefault(rule, []).extend(csv.DictReader(f, delimiter="\t"))
    out = []
    for rule, rows in sorted(jobs.items()):
        wall = [float(r["s"]) for r in rows]
        cpu = [float(r["cpu_time"]) for r in rows]
        rss = [float(r["max_rss"]) for r in rows]
        out.append({"rule": rule, "jobs": len(rows), "wall_s": round(sum(wall), 2), "cpu_s": round(sum(cpu), 2),
                    "peak_rss_MB": round(max(rss), 1)})
    return out


# --------------------------------------------------------------------------- snapshot


def build(previous: dict, rules_command: str | None) -> dict:
    here = machine()
    machines = dict(previous.get("machines", {}))
    old_rows = {r["id"]: r for r in previous.get("rows", [])}
    rows = []
    for spec in ROWS:
        path = BENCH / spec.file
        value = spec.read(json.loads(path.read_text())) if path.exists() else None
        if value is not None:
            text, memory, quantities = value
            rows.append({"id": spec.id, "what": spec.what, "value": text, "memory": memory, "quantities": quantities,
                         "command": spec.command, "source": f"results/benchmarks/{spec.file}", "machine": here["id"]})
            machines[here["id"]] = here
        elif spec.id in old_rows:
            rows.append(old_rows[spec.id])
    snapshot = {"generated_by": "python scripts/performance_snapshot.py", "machines": {}, "rows": rows,
                "not_measured": [{"id": s.id, "what": s.what, "command": s.command}
                                 for s in ROWS if s.id not in {r["id"] for r in rows}],
                "rules": previous.get("rules")}
    if rules_command:
        folder = BENCH / "rules"
        if not folder.is_dir():
            raise SystemExit(f"--rules-command given but {folder} does not exist: run the workflow first")
        snapshot["rules"] = {"command": rules_command, "machine": here["id"], "rows": rule_rows(folder)}
        machines[here["id"]] = here
    used = {r["machine"] for r in rows} | ({snapshot["rules"]["machine"]} if snapshot["rules"] else set())
    snapshot["machines"] = {k: v for k, v in machines.items() if k in used}
    return snapshot


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rules-command", help="the workflow command whose results/benchmarks/rules/ files to read")
    ap.add_argument("--out", type=Path, default=SNAPSHOT)
    a = ap.parse_args(argv)
    previous = json.loads(a.out.read_text()) if a.out.exists() else {}
    snapshot = build(previous, a.rules_command)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(snapshot, indent=1, ensure_ascii=False) + "\n")
    print(f"{len(snapshot['rows'])} rows measured, {len(snapshot['not_measured'])} not measured -> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
