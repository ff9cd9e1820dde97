"""The diagnoses the slow diagnosis tests run (issue 14: CI in 3 min), one version of the package beside another.

The cases are those of tests/test_diagnosis_bearing.py (every hidden effect at 30 dB and the five 10 dB cases
that run in CI, the healthy record, the loose part, on the 0.5 s records at 2550 Hz with the CI mesh's
influence line), tests/test_diagnosis_record_quality.py (the coarse ADC and its blind floor, the wandering and
the kinked drift with and without the drift's new shapes) and tests/test_diagnostics.py (the clean CI record
and each hidden effect), built from the test modules themselves, so the values are the tests' own.

Each side runs in a process of its own with its ``src`` first on ``sys.path`` (``--old REV``: ``git archive``
of that revision's src/tests/config; the new side is this checkout), one BLAS thread, bytecode caches on; each
diagnosis's CPU seconds (``time.process_time``) and its numbers: selection, verdict, ranking, the first-ranked
effect's values and 95% intervals, the final model's values, intervals and NRMSE. The comparison gives the CPU
ratio old / new per group and in all, whether every selection, verdict and ranking order is the same, and how
far each value moved as a share of its 95% interval's half-width (the tests' tolerances are multiples of it).

``--pytest``: also the four test files themselves (``--pytest-files``: others) (tests/test_diagnosis_bearing.py, test_diagnostics.py,
test_diagnosis_record_quality.py, test_cli.py), ``CI=true pytest -p no:xdist`` in one process per side (that
side's tests, its package first on ``sys.path``), their CPU seconds (user + system of pytest and its children)
and the pass line.

Writes results/benchmarks/diagnosis_tests.json. Usage:
``python benchmarks/bench_diagnosis_tests.py --old REV [--groups bearing calibration diagnostics job] [--pytest] [--note TEXT]``.

``job``: the CI workflow's running-bearing jobs (``synthesize_bearing_record`` and ``diagnose_bearing`` on
config/ci.yaml, without the figures), whether their record CSV and diagnosis JSON are byte-identical.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results/benchmarks/diagnosis_tests.json"


# --------------------------------------------------------------------------- one side (a worker process)


def summary(d: dict) -> dict:
    """The numbers of one diagnosis the comparison reads."""
    first = d["ranking"][0] if d["ranking"] else {}
    return {
        "selected": d["selected"],
        "verdict": d["verdict"],
        "ranking": [r["effect"] for r in d["ranking"]],
        "delta_bic": [r["delta_bic"] for r in d["ranking"]],
        "first_params": first.get("params", {}),
        "first_ci95": first.get("ci95", {}),
        "final_params": d["final"]["params"],
        "final_ci95": d["final"]["ci95"],
        "final_nrmse": d["final"]["nrmse"],
        "bytes_sha256": d.get("bytes_sha256"),
        "steps": [[st.get("added"), st.get("effects")] for st in d.get("steps", [])],
        "ranked_params": [r.get("params", {}) for r in d["ranking"]],
        "ranked_ci95": [r.get("ci95", {}) for r in d["ranking"]],
    }


def bearing_cases():
    import test_diagnosis_bearing as tb

    from piezobearing import config as cfg
    from piezobearing.stages.bearing_diagnosis import influence_from_config

    c = copy.deepcopy(cfg.load(cfg.CONFIG_DIR / "ci.yaml"))
    c["bearing_diagnosis"].update(synthetic_duration_s=0.5, synthetic_sample_rate_Hz=2550.0)
    c["diagnostics"]["max_steps"] = 1
    infl = influence_from_config(c)
    for name in tb.HIDDEN:
        for snr in (30.0, 10.0):
            if snr == 10.0 and name not in tb.TEN_DB_ALWAYS:
                continue
            yield f"bearing:{name}-{snr:g}dB", lambda n=name, s=snr: tb.run(
                c, infl, [{"name": n, "params": tb.HIDDEN[n]}], s, tach=(n == "cage_slip"))
    yield "bearing:healthy", lambda: tb.run(c, infl, [], 30.0)
    c2 = copy.deepcopy(c)
    c2["diagnostics"]["max_steps"] = 2
    yield "bearing:loose_part", lambda: tb.run(c2, infl, [], 30.0, extra=tb.loose_part)


def calibration_cases():
    from dataclasses import replace

    import numpy as np
    import test_diagnosis_record_quality as tq

    from piezobearing import config as cfg
    from piezobearing.diagnosis import noise
    from piezobearing.diagnosis.calibration.effects import ForceRecord
    from piezobearing.diagnosis.calibration.effects import baseline_drift as bd
    from piezobearing.diagnosis.calibration.subject import diagnose_record
    from piezobearing.stages.calibration import nominal_circuit
    from piezobearing.synthesis import PressProtocol, synthesize

    ci = cfg.load(cfg.CONFIG_DIR / "ci.yaml")
    c = {**ci, "synthesis": {**ci["synthesis"], "voltage_noise_V": 0.3e-3, "force_noise_N": 0.5e-3}}
    m = synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"])
    q = 20.0 / 4096
    v = np.round(m.voltage_V / q) * q
    args = tq._nominal_args(c, m, v)
    rec = ForceRecord(m.time_s, m.force_N)
    yield "calibration:coarse_adc", lambda: diagnose_record(rec, v, *args)[1]

    def blind():
        stationary = noise.quantisation_step
        try:
            noise.quantisation_step = lambda x, tolerance=0.05: 0.0
            return diagnose_record(rec, v, *args[:2], replace(args[2], max_steps=1), args[3])[1]
        finally:
            noise.quantisation_step = stationary

    yield "calibration:coarse_adc_blind", blind
    m = synthesize(PressProtocol.from_config(ci["synthesis"]), nominal_circuit(ci), ci["seed"])
    t = m.time_s
    v1 = m.voltage_V + 0.020 * np.exp(-0.5 * ((t - 4) / 2.0) ** 2) - 0.012 * np.exp(-0.5 * ((t - 8.5) / 2.0) ** 2)
    s = np.clip(t - 3.3, 0.0, None)
    v2 = m.voltage_V + 0.08 * (np.exp(-s / 8.0) - np.exp(-s / 4.0))
    r = ForceRecord(t, m.force_N)
    for label, vv in (("wandering_drift", v1), ("kinked_drift", v2)):
        a = tq._nominal_args(ci, m, vv)
        yield f"calibration:{label}", lambda vv=vv, a=a: diagnose_record(r, vv, *a)[1]

    def patched(obj, attr, value, vv, a):
        old = getattr(obj, attr)
        setattr(obj, attr, value)
        try:
            return diagnose_record(r, vv, *a)[1]
        finally:
            setattr(obj, attr, old)

    yield "calibration:wandering_drift_cubic", lambda: patched(bd, "KNOTS", (0,), v1, tq._nominal_args(ci, m, v1))
    yield "calibration:kinked_drift_fixed", lambda: patched(
        bd.BaselineDrift, "refinements", lambda self, ctx: [], v2, tq._nominal_args(ci, m, v2))


def diagnostics_cases():
    import test_diagnostics as td

    from piezobearing import config as cfg

    ci = cfg.load(cfg.CONFIG_DIR / "ci.yaml")
    yield "diagnostics:clean", lambda: td.run(ci, [])
    for name, (hidden, _, _) in td.HIDDEN.items():
        yield f"diagnostics:{name}", lambda h=hidden: td.run(ci, h)


def job_cases():
    """The CI workflow's ``synthesize_bearing_record`` and ``diagnose_bearing`` jobs on config/ci.yaml (the
    healthy 0.5 s record; the influence line solved once beforehand, untimed): record CSV and diagnosis JSON
    as the stages write them (no figures), their SHA-256 in the row."""
    import hashlib
    import tempfile

    from piezobearing import config as cfg
    from piezobearing.diagnosis.bearing.subject import synthesise
    from piezobearing.io import write_bearing_record, write_json
    from piezobearing.stages import bearing_diagnosis as bd

    ci = cfg.load(cfg.CONFIG_DIR / "ci.yaml")
    infl = bd.influence_from_config(ci)
    folder = Path(tempfile.mkdtemp())

    def job():
        rec = folder / "synthetic_record.csv"
        write_bearing_record(synthesise(ci, ci["seed"], ci["bearing"]["hidden_effects"], infl), rec)
        out, _ = bd.run(str(rec), infl, ci)
        write_json(out, folder / "diagnosis.json")
        out["bytes_sha256"] = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}
        return out

    yield "job:diagnose_bearing", job


GROUPS = {"bearing": bearing_cases, "calibration": calibration_cases, "diagnostics": diagnostics_cases,
          "job": job_cases}


def worker(groups: list[str]) -> None:
    """Run the cases of ``groups`` with the package on sys.path; one JSON line per diagnosis on stdout."""
    from threadpoolctl import threadpool_limits

    sys.path.insert(0, str(Path(os.environ["BENCH_TESTS_DIR"])))
    import piezobearing

    print(json.dumps({"package": piezobearing.__file__}), flush=True)
    with threadpool_limits(limits=1, user_api="blas"):
        for g in groups:
            for label, fn in GROUPS[g]():
                c0 = time.process_time()
                d = fn()
                cpu = time.process_time() - c0
                print(json.dumps({"case": label, "cpu_seconds": cpu, **summary(d)}), flush=True)


# --------------------------------------------------------------------------- the comparison


def side(root: Path, groups: list[str]) -> dict:
    """One side's cases in a fresh process with ``root``/src first on sys.path."""
    env = {**os.environ, "PYTHONPATH": str(root / "src"), "BENCH_TESTS_DIR": str(root / "tests"),
           "OMP_NUM_THREADS": "1"}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--worker", *groups], env=env, cwd=root,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(out.stderr[-3000:])
    rows = [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]
    assert rows[0]["package"].startswith(str(root)), rows[0]  # the side's own package was imported
    return {r["case"]: r for r in rows[1:]}


TEST_FILES = ("tests/test_diagnosis_bearing.py", "tests/test_diagnostics.py", "tests/test_diagnosis_record_quality.py",
              "tests/test_cli.py")


def pytest_cpu(root: Path, files=TEST_FILES) -> dict:
    """CPU seconds of ``CI=true pytest -p no:xdist`` on ``files`` in ``root`` (its src first on sys.path)."""
    import resource

    from bench_ci_tests import per_file  # the --durations lines summed per file, as for the whole suite

    env = {**os.environ, "PYTHONPATH": str(root / "src"), "CI": "true", "OMP_NUM_THREADS": "1"}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:xdist", "-p", "no:cacheprovider",
                          "--durations=0", *files], cwd=root, env=env, capture_output=True, text=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"cpu_seconds": (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime),
            "wall_seconds": time.perf_counter() - t0, "returncode": out.returncode,
            "summary": out.stdout.strip().splitlines()[-1] if out.stdout.strip() else out.stderr[-500:],
            "durations_per_file_s": per_file(out.stdout)}


def moved(old: dict, new: dict, values: str, ci: str) -> float:
    """Largest |new - old| of the values as a share of the old 95% interval's half-width."""
    worst = 0.0
    for k, a in old[values].items():
        b = new[values].get(k)
        iv = old[ci].get(k)
        if b is None or not iv or iv[0] is None or a is None:
            continue
        half = 0.5 * abs(iv[1] - iv[0])
        if half > 0:
            worst = max(worst, abs(b - a) / half)
    return worst


def moved_ranked(old: dict, new: dict) -> float:
    """Largest |new - old| of any ranked candidate's value (same effect in both rankings) as a share of the old
    95% interval's half-width (0 where a side has no such rows)."""
    worst = 0.0
    rows = zip(new.get("ranked_params", []), new.get("ranked_ci95", []), strict=False)
    new_of = dict(zip(new["ranking"], rows, strict=False))
    for e, p, ci in zip(old["ranking"], old.get("ranked_params", []), old.get("ranked_ci95", []), strict=False):
        if e in new_of:
            worst = max(worst, moved({"v": p, "c": ci}, {"v": new_of[e][0], "c": new_of[e][1]}, "v", "c"))
    return worst


def compare(old: dict, new: dict) -> dict:
    out = {"cases": {}, "groups": {}}
    for case, o in old.items():
        n = new.get(case)
        if n is None:
            continue
        ob = dict(zip(o["ranking"], o["delta_bic"], strict=True))
        nb = dict(zip(n["ranking"], n["delta_bic"], strict=True))
        out["cases"][case] = {
            "old_cpu_seconds": o["cpu_seconds"],
            "new_cpu_seconds": n["cpu_seconds"],
            "ratio": o["cpu_seconds"] / n["cpu_seconds"],
            "same_selection": o["selected"] == n["selected"],
            "same_verdict": o["verdict"] == n["verdict"],
            "same_ranking": o["ranking"] == n["ranking"],
            "same_steps": o.get("steps") == n.get("steps"),
            "first_values_moved_half_widths": moved(o, n, "first_params", "first_ci95"),
            "ranked_values_moved_half_widths": moved_ranked(o, n),
            "final_values_moved_half_widths": moved(o, n, "final_params", "final_ci95"),
            "max_delta_bic_change": max((abs(a - nb[e]) for e, a in ob.items() if e in nb), default=0.0),
            "max_delta_bic_change_relative": max(
                (abs(a - nb[e]) / max(abs(a), 1.0) for e, a in ob.items() if e in nb), default=0.0),
            "final_nrmse_old_new": [o["final_nrmse"], n["final_nrmse"]],
            "same_bytes": ({k: o["bytes_sha256"][k] == n["bytes_sha256"].get(k) for k in o["bytes_sha256"]}
                           if o.get("bytes_sha256") else None),
            "selected": n["selected"],
            "verdict": n["verdict"],
        }
    for g in GROUPS:
        rows = [r for c, r in out["cases"].items() if c.startswith(g + ":")]
        if rows:
            old_s, new_s = sum(r["old_cpu_seconds"] for r in rows), sum(r["new_cpu_seconds"] for r in rows)
            out["groups"][g] = {"old_cpu_seconds": old_s, "new_cpu_seconds": new_s, "ratio": old_s / new_s}
    rows = list(out["cases"].values())
    old_s, new_s = sum(r["old_cpu_seconds"] for r in rows), sum(r["new_cpu_seconds"] for r in rows)
    # the blind floor (coarse_adc_blind: a tenth of the ADC's) weighs the residual 1e14 times: its values and
    # intervals are the search's false discoveries, far from any physical value; compare the others
    rows_kept = [r for c, r in out["cases"].items() if not c.endswith("_blind")]
    out["max_values_moved_half_widths_but_blind"] = max(
        (max(r["first_values_moved_half_widths"], r["final_values_moved_half_widths"]) for r in rows_kept), default=0.0)
    out["total"] = {
        "old_cpu_seconds": old_s,
        "new_cpu_seconds": new_s,
        "ratio": old_s / new_s,
        "all_same_selection_and_verdict": all(r["same_selection"] and r["same_verdict"] for r in rows),
        "all_same_ranking": all(r["same_ranking"] for r in rows),
        "all_same_steps": all(r["same_steps"] for r in rows),
        "max_ranked_values_moved_half_widths_but_blind": max(
            (r["ranked_values_moved_half_widths"] for c, r in out["cases"].items() if not c.endswith("_blind")),
            default=0.0),
        "max_values_moved_half_widths": max(
            (max(r["first_values_moved_half_widths"], r["final_values_moved_half_widths"]) for r in rows), default=0.0
        ),
    }
    return out


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(sys.argv[2:])
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="the revision before the change (git rev)")
    ap.add_argument("--groups", nargs="+", default=list(GROUPS), choices=list(GROUPS))
    ap.add_argument("--note", default="")
    ap.add_argument("--pytest", action="store_true", help="also the four test files' CPU, old and new")
    ap.add_argument("--pytest-files", nargs="+", default=list(TEST_FILES), help="--pytest: these test files instead")
    args = ap.parse_args()
    sha = subprocess.run(["git", "rev-parse", args.old], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.strip()
    new_sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    dirty = bool(subprocess.run(["git", "status", "--porcelain", "src"], cwd=ROOT, capture_output=True,
                                text=True).stdout.strip())
    with tempfile.TemporaryDirectory() as tmp:
        old_root = Path(tmp)
        arch = subprocess.run(["git", "archive", sha, "src", "tests", "config", "pyproject.toml"], cwd=ROOT,
                              capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(old_root)], input=arch, check=True)
        old = side(old_root, args.groups)
        new = side(ROOT, args.groups)
        tests = ({"old": pytest_cpu(old_root, args.pytest_files), "new": pytest_cpu(ROOT, args.pytest_files),
                  "files": args.pytest_files} if args.pytest else None)
    res = compare(old, new)
    if tests:
        tests["ratio_cpu"] = tests["old"]["cpu_seconds"] / tests["new"]["cpu_seconds"]
        res["test_files"] = tests
    res.update({"old_revision": sha, "new_revision": new_sha + (" + uncommitted src" if dirty else ""),
                "note": args.note, "cpu_count": os.cpu_count(), "load_average_1min": os.getloadavg()[0],
                "blas_threads": 1})
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(res, indent=2) + "\n")
    print(json.dumps({"groups": res["groups"], "total": res["total"], "test_files": res.get("test_files")}, indent=2))


if __name__ == "__main__":
    main()
