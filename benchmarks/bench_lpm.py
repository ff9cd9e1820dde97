"""Time of the bearing's lumped-parameter model: the numpy reference loop against the compiled kernel.

Writes results/benchmarks/lpm.json:
- one LPM run of 1 s of bearing time (the default config's faulty case, 92k steps) with
  ``method="python"`` and ``method="compiled"`` (warm: the kernel already compiled), their ratio,
  and the largest difference of the roller loads relative to the peak load;
- the compiled kernel's cost in a fresh process: import + compile + run with an empty numba
  cache (cold) and with the cache of the cold run (warm, what every later process pays);
- the ``bearing_lpm`` stage (both cases, 1.05 s each, CSV/NPZ/JSON written) with each method.

Run from the repository root: ``python benchmarks/bench_lpm.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from piezobearing.bearing import lpm
from piezobearing.config import load as load_config
from piezobearing.stages import bearing as stage

ROOT = Path(__file__).resolve().parents[1]

FRESH = """
import time
t0 = time.perf_counter()
import numpy as np
from piezobearing.bearing import lpm
from piezobearing.config import load as load_config
b = load_config()['bearing']
p = lpm.LPMParameters.from_config(b, True)
h = b['time_step_s'] / b['substeps']
lpm.simulate_lpm(p, 0.0, int(round(1.0 / h)), h, method='compiled')
print(time.perf_counter() - t0)
"""


def one_run(bearing: dict, method: str) -> tuple[float, lpm.LPMResult]:
    p = lpm.LPMParameters.from_config(bearing, True)
    h = bearing["time_step_s"] / bearing["substeps"]
    t0 = time.perf_counter()
    res = lpm.simulate_lpm(p, 0.0, int(round(1.0 / h)), h, method=method)
    return time.perf_counter() - t0, res


def fresh_process(cache_dir: str) -> float:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}
    out = subprocess.run(
        [sys.executable, "-c", FRESH], cwd=ROOT, env=env, capture_output=True, text=True, check=True
    )
    return float(out.stdout.strip().splitlines()[-1])


def stage_seconds(config: dict, method: str, outdir: Path) -> float:
    t0 = time.perf_counter()
    stage.bearing_lpm(
        outdir / "kinematics.json",
        {c: outdir / f"contact_{c}.npz" for c in stage.CASES},
        {c: outdir / f"contact_forces_{c}.csv" for c in stage.CASES},
        outdir / "lpm.json",
        config,
        method=method,
    )
    return time.perf_counter() - t0


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n")[0]).parse_args()  # no options: --help only
    config = load_config()
    b = config["bearing"]
    out: dict = {"cpu_count": os.cpu_count(), "bearing_time_s": 1.0}
    with tempfile.TemporaryDirectory() as cache:
        out["compiled_fresh_process_cold_s"] = fresh_process(cache)
        out["compiled_fresh_process_warm_s"] = fresh_process(cache)
    one_run(b, "compiled")  # compile (or load) in this process
    t_new, r_new = min((one_run(b, "compiled") for _ in range(3)), key=lambda x: x[0])
    t_old, r_old = one_run(b, "python")
    out["steps"] = len(r_new.time_s) - 1
    out["python_s"] = t_old
    out["compiled_s"] = t_new
    out["ratio_python_over_compiled"] = t_old / t_new
    out["max_load_diff_rel_to_peak"] = float(np.abs(r_new.load_N - r_old.load_N).max() / r_old.load_N.max())
    out["max_displacement_diff_m"] = float(
        max(np.abs(r_new.shaft_m - r_old.shaft_m).max(), np.abs(r_new.pedestal_m - r_old.pedestal_m).max())
    )
    out["newton_iterations_python_compiled"] = [r_old.newton_iterations, r_new.newton_iterations]
    with tempfile.TemporaryDirectory() as d:
        out["stage_bearing_lpm_python_s"] = stage_seconds(config, "python", Path(d))
        out["stage_bearing_lpm_compiled_s"] = stage_seconds(config, "compiled", Path(d))
    out["stage_ratio"] = out["stage_bearing_lpm_python_s"] / out["stage_bearing_lpm_compiled_s"]
    path = ROOT / "results" / "benchmarks" / "lpm.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
