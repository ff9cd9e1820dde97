"""CPU seconds of the signals and bearing unit tests (issue 14: CI in 3 min), one revision beside another, and
whether the code they exercise still gives the same numbers.

Each revision is exported (``git archive``) to a temporary folder and its tests run there with its own package
(``PYTHONPATH``), in one pytest process per run (as an xdist worker runs them: imports once), ``CI=true``, with
bytecode caches on; a first run of each side writes the bytecode and the numba cache, then ``-n`` runs in turn
(old, new, old, new ...). A small plugin records each test's CPU seconds (``time.process_time`` around its
setup, call and teardown); the process's own CPU (user + system, from the parent's rusage) is reported too.
Medians over the runs.

The results compared, each side's code on the same inputs (``PROBE``): the baseline detector's detections
(unclipped at 10 dB and at a DAQ's 3.6e-4 V, clipped, with a gain tolerance) and the slip-searched outer-race
test's statistics, compared as JSON (byte-identical expected); and the LPM trapezoid rule's Radau reference at
each side's tolerance (``tests/test_bearing.py``: rtol 1e-9 before, 1e-7 after): its largest load difference
and each side's error ratio; and the fault-type classification over noise seeds (``classification.classify_seeds``,
the workflow's ``fault_classification``: a healthy and an outer-race stand-in record at 2550 Hz, 50 seeds each,
the paper config's baseline detector): its CPU seconds and rows (``--probe-only`` reruns this part alone).

Writes ``results/benchmarks/unit_tests.json``. Usage:
``python benchmarks/bench_unit_tests.py --old REV [--new HEAD] [-n 2]``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results/benchmarks/unit_tests.json"
FILES = ("tests/test_signals_baseline.py", "tests/test_signals_clipped.py", "tests/test_bearing.py",
         "tests/test_sensor_fem.py", "tests/test_signals_detector_stages.py", "tests/test_signals_passage.py",
         "tests/test_signals.py", "tests/test_bearing_faults.py", "tests/test_bearing_stages.py")

PLUGIN = '''
import json, os, time, pytest
_cpu = {}
@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    t = time.process_time()
    yield
    _cpu[item.nodeid] = time.process_time() - t
def pytest_sessionfinish(session):
    with open(os.environ["UNIT_CPU_OUT"], "w") as f:
        json.dump(_cpu, f)
'''

PROBE = '''
import json, sys
sys.path.insert(0, "tests")
import numpy as np
from scipy.integrate import solve_ivp
from test_signals_baseline import FS, KIN, healthy, impacts
from test_signals_clipped import adc, SIGMA
from test_bearing import _params
from piezobearing import config as cfg
from piezobearing.bearing import lpm as brg
from piezobearing.signals import baseline as B, clipped as CL
from piezobearing.signals.fault_bands import slipped_frequencies
rtol, atol = float(sys.argv[2]), float(sys.argv[3])
det = {}
n, dt = 2550, 1 / FS
st = B.BaselineSettings(); h = healthy(n); base = B.Baseline.from_record(h, dt, KIN, st)
rng = np.random.default_rng(17)
det["clipped"] = [CL.detect(adc(h, SIGMA, rng), dt, KIN, base, st).per_type for _ in range(12)]
rng = np.random.default_rng(5)
for true in ("none", "outer_race", "inner_race", "rolling_element"):
    v = h + (impacts(true, n) if true != "none" else 0.0)
    det["detect_" + true] = [B.detect(v + s * rng.standard_normal(n), dt, KIN, base, st).per_type
                             for s in (np.sqrt(np.mean(v**2) / 10), 3.6e-4)]
det["gain"] = B.detect(1.1 * h + 1e-2 * rng.standard_normal(n), dt, KIN, base,
                       B.BaselineSettings(gain_tolerance=0.1)).per_type
base2 = B.Baseline.from_record(healthy(640), dt, KIN, st)
window = (KIN["bpfo_Hz"] * 0.97, KIN["bpfo_Hz"])
f_true = slipped_frequencies(KIN, 0.015)["bpfo_Hz"]
rng = np.random.default_rng(12)
det["slip_search"] = [B.harmonic_test(healthy(640) + s * rng.standard_normal(640), dt, f_true, base2, s, 0.0, window)
                      for s in (2.0,) * 10 + (30.0,) * 10]
bcfg = cfg.load()["bearing"]
p = _params(bcfg, faulty=True, start_angle_rad=-0.012)
hh, nn = bcfg["time_step_s"] / bcfg["substeps"], 240
fun, jac = brg.lpm_rhs(p)
res, res2 = brg.simulate_lpm(p, 0.0, nn, hh), brg.simulate_lpm(p, 0.0, 2 * nn, hh / 2)
y0 = np.r_[res.shaft_m[0], res.pedestal_m[0], np.zeros(4)]
sol = solve_ivp(fun, (0, nn * hh), y0, method="Radau", jac=jac, rtol=rtol, atol=atol, t_eval=res.time_s, max_step=hh)
e = sol.y[:2] - sol.y[2:4]
q = brg.contact_law(brg.roller_deflections(e.T, res.psi_rad, p.gap_m, p.drops(p.motion(res.time_s))), p.k_contact)[0]
e0, e1 = float(np.abs(res.load_N - q).max()), float(np.abs(res2.load_N[::2] - q).max())
import time
from piezobearing.signals import classification as SC, daq
sig = cfg.load()["signals"]
records = {"healthy": ("none", healthy(2550), dt), "outer": ("outer_race", healthy(2550) + impacts("outer_race", 2550), dt)}
analyse = SC.analyser(sig, KIN, (healthy(2550), dt))
c0 = time.process_time()
cm, rows = SC.classify_seeds(records, KIN, analyse, daq.NoiseSettings(), lambda c, j: np.random.default_rng([3, len(c), j]), 50)
cls_cpu = time.process_time() - c0
with open(sys.argv[1], "w") as f:
    json.dump({"detections": json.dumps(det, default=float), "radau_load_N": q.tolist(), "radau_nfev": int(sol.nfev),
               "error_h_over_peak": e0 / float(q.max()), "error_ratio_h_over_h2": e0 / e1,
               "classification_cpu_s": cls_cpu, "classification_rows": json.dumps(rows, default=float)}, f)
'''


def export_revision(rev: str, dest: Path) -> tuple[Path, str]:
    """Revision ``rev`` as a plain folder ``dest`` (with an empty ``data/``); and its commit."""
    sha = subprocess.run(["git", "rev-parse", rev], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    dest.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", sha], cwd=ROOT, capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    (dest / "data").mkdir(exist_ok=True)
    return dest, sha


def _env(folder: Path, plugin_dir: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return {**env, "PYTHONPATH": f"{folder / 'src'}{os.pathsep}{plugin_dir}", "CI": "true", "OMP_NUM_THREADS": "1"}


def run_tests(folder: Path, plugin_dir: Path) -> dict:
    """One pytest process over :data:`FILES` in ``folder``: per-test CPU seconds, the process's CPU, the summary."""
    out = plugin_dir / f"cpu_{folder.name}.json"
    env = {**_env(folder, plugin_dir), "UNIT_CPU_OUT": str(out)}
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "unit_cpu", "-p", "no:cacheprovider", *FILES],
                       cwd=folder, env=env, capture_output=True, text=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = p.stdout.strip().splitlines()[-1] if p.stdout.strip() else p.stderr[-500:]
    if p.returncode != 0:
        raise RuntimeError(f"tests failed in {folder}: {summary}\n{p.stdout[-3000:]}")
    return {"per_test": json.loads(out.read_text()), "process_cpu_s": r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime,
            "summary": summary}


def probe(folder: Path, plugin_dir: Path, rtol: float, atol: float) -> dict:
    out = plugin_dir / f"probe_{folder.name}.json"
    (plugin_dir / "probe.py").write_text(PROBE)
    subprocess.run([sys.executable, str(plugin_dir / "probe.py"), str(out), repr(rtol), repr(atol)], cwd=folder,
                   env=_env(folder, plugin_dir), check=True)
    return json.loads(out.read_text())


def compare(p_old: dict, p_new: dict) -> dict:
    """The two sides' probe results compared."""
    q_old, q_new = p_old["radau_load_N"], p_new["radau_load_N"]
    out = {
        "detections_byte_identical": p_old["detections"] == p_new["detections"],
        "radau_reference_max_load_difference_N": float(np.abs(np.subtract(q_old, q_new)).max()),
        "radau_reference_peak_load_N": float(np.max(q_old)),
        "radau_rhs_evaluations": {"old": p_old["radau_nfev"], "new": p_new["radau_nfev"]},
        "trapezoid_error_over_peak": {"old": p_old["error_h_over_peak"], "new": p_new["error_h_over_peak"]},
        "trapezoid_error_ratio_h_over_h2": {"old": p_old["error_ratio_h_over_h2"],
                                            "new": p_new["error_ratio_h_over_h2"]},
    }
    if "classification_cpu_s" in p_old and "classification_cpu_s" in p_new:
        out["classify_seeds_2_cases_x_50_seeds_2550Hz"] = {
            "old_cpu_s": p_old["classification_cpu_s"], "new_cpu_s": p_new["classification_cpu_s"],
            "new_over_old": p_new["classification_cpu_s"] / p_old["classification_cpu_s"],
            "rows_byte_identical": p_old["classification_rows"] == p_new["classification_rows"]}
    return out


def per_file(per_test: dict) -> dict:
    out: dict = {}
    for node, s in per_test.items():
        out[node.split("::")[0]] = out.get(node.split("::")[0], 0.0) + s
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--old", required=True)
    ap.add_argument("--new", default="HEAD")
    ap.add_argument("-n", type=int, default=2)
    ap.add_argument("--probe-only", action="store_true", help="rerun the results' comparison, keep the timings")
    a = ap.parse_args()
    if a.probe_only:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            (tmp / "plugin").mkdir()
            (old, _), (new, _) = export_revision(a.old, tmp / "old"), export_revision(a.new, tmp / "new")
            p_old, p_new = probe(old, tmp / "plugin", 1e-9, 1e-15), probe(new, tmp / "plugin", 1e-7, 1e-13)
        result = json.loads(OUT.read_text())
        result["results"] = compare(p_old, p_new)
        OUT.write_text(json.dumps(result, indent=2) + "\n")
        print(json.dumps(result["results"], indent=2))
        return
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        plugin_dir = tmp / "plugin"
        plugin_dir.mkdir()
        (plugin_dir / "unit_cpu.py").write_text(PLUGIN)
        (old, old_sha), (new, new_sha) = export_revision(a.old, tmp / "old"), export_revision(a.new, tmp / "new")
        runs: dict = {"old": [], "new": []}
        for folder in (old, new):  # bytecode, numba cache
            run_tests(folder, plugin_dir)
        for _ in range(a.n):
            for side, folder in (("old", old), ("new", new)):
                runs[side].append(run_tests(folder, plugin_dir))
                print(side, runs[side][-1]["summary"], f"{runs[side][-1]['process_cpu_s']:.1f} s", flush=True)
        p_old, p_new = probe(old, plugin_dir, 1e-9, 1e-15), probe(new, plugin_dir, 1e-7, 1e-13)
    sides = {}
    for side, rs in runs.items():
        tests = {k: statistics.median(r["per_test"][k] for r in rs) for k in rs[0]["per_test"]}
        sides[side] = {"tests_cpu_s": sum(tests.values()),
                       "process_cpu_s": statistics.median(r["process_cpu_s"] for r in rs),
                       "per_file_cpu_s": per_file(tests), "per_test_cpu_s": tests, "summary": rs[-1]["summary"]}
    result = {
        "old_revision": old_sha, "new_revision": new_sha, "files": list(FILES), "runs_each": a.n,
        "old": sides["old"], "new": sides["new"],
        "tests_new_over_old": sides["new"]["tests_cpu_s"] / sides["old"]["tests_cpu_s"],
        "process_new_over_old": sides["new"]["process_cpu_s"] / sides["old"]["process_cpu_s"],
        "per_file_new_over_old": {f: sides["new"]["per_file_cpu_s"][f] / sides["old"]["per_file_cpu_s"][f]
                                  for f in sides["old"]["per_file_cpu_s"] if f in sides["new"]["per_file_cpu_s"]},
        "results": compare(p_old, p_new),
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k not in ("old", "new")}, indent=2))


if __name__ == "__main__":
    main()
