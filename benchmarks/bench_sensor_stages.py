"""The sensor FEM stages (mesh, modal, convergence, harmonic), the previous code beside this checkout's.

``sensor_modal`` writes the harmonic analysis's Ritz model and its mesh's convergence row from the SS system it
factorises anyway, so ``sensor_harmonic`` and ``sensor_convergence`` do not assemble and factorise the modal
mesh again; the previous code did. Both sides run the four stages in a fresh process each (``--old-src``: the
previous package's ``src``), at the same time, under GNU time (CPU seconds and peak RSS of the process), and
their result files are compared byte by byte (``bench_workflow.compare_results``).

Writes ``results/benchmarks/sensor_stages_<config>.json``. Usage::

    python benchmarks/bench_sensor_stages.py --old-src /path/to/old/src --config ci     # or default
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_workflow import compare_results, parse_time_log  # noqa: E402

CONFIG = Path(__file__).resolve().parents[1] / "config"  # the checkout's configs (ci.yaml)

ROOT = Path(__file__).resolve().parents[1]


def worker(out: Path, config_name: str) -> None:
    """The four stages with whichever package is importable, into ``out/results/sensor``."""
    from piezobearing import config
    from piezobearing.stages import sensor_fem as sensor_fem_stages

    d = out / "results/sensor"
    d.mkdir(parents=True, exist_ok=True)
    c = config.load() if config_name == "default" else config.load(CONFIG / f"{config_name}.yaml")
    p = sensor_fem_stages.SensorFemParams.from_config(c)
    meshes = [f"stack_L{k}.vtk" for k in range(1, len(p.multipliers) + 1)]
    os.chdir(d)  # relative paths: the files name no folder, so the two sides' files compare byte by byte
    sensor_fem_stages.sensor_mesh(meshes, "mesh.json", c)
    (d / "resistance.json").write_text(json.dumps({"resistance_ohm": 50.3e6}))
    (d / "lowfreq.json").write_text(json.dumps({"linear_from_Hz": 30.0}))
    mesh = meshes[p.mesh_level - 1]
    if "out_ritz_npz" in inspect.signature(sensor_fem_stages.sensor_modal).parameters:  # this checkout
        sensor_fem_stages.sensor_modal(mesh, "modal.json", "mode.npz", "ritz.npz", "row.json", c)
        sensor_fem_stages.sensor_convergence(meshes, "row.json", "convergence.csv", c)
        sensor_fem_stages.sensor_harmonic("ritz.npz", "modal.json", "resistance.json", "lowfreq.json", "harmonic.csv",
                                          "band.json", c)
        for f in ("ritz.npz", "row.json"):  # what only the new code writes: not a result to compare
            Path(f).rename(f + ".new")
    else:
        sensor_fem_stages.sensor_convergence(meshes, "convergence.csv", c)
        sensor_fem_stages.sensor_modal(mesh, "modal.json", "mode.npz", c)
        sensor_fem_stages.sensor_harmonic(mesh, "modal.json", "resistance.json", "lowfreq.json", "harmonic.csv",
                                          "band.json", c)


def _side(src: Path | None, out: Path, config_name: str) -> Path:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    if src is not None:
        env["PYTHONPATH"] = str(src)
    log = out.with_suffix(".log")
    cmd = ["/usr/bin/time", "-v", sys.executable, __file__, "--worker", str(out), "--config", config_name]
    with log.open("w") as f:
        code = subprocess.run(cmd, env=env, stdout=f, stderr=subprocess.STDOUT).returncode
        f.write(f"\nrc={code}\n")
    return log


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old-src", type=Path)
    ap.add_argument("--config", default="ci", help="ci or default")
    ap.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        worker(a.worker, a.config)
        return
    tmp = Path(tempfile.mkdtemp(prefix="bench_sensor_stages_"))
    dirs = (tmp / "old", tmp / "new")
    with ThreadPoolExecutor(2) as pool:
        logs = list(pool.map(lambda k: _side((a.old_src, ROOT / "src")[k], dirs[k], a.config), (0, 1)))
    t_old, t_new = (parse_time_log(p.read_text()) for p in logs)
    rec = {
        "what": f"sensor_mesh, sensor_modal, sensor_convergence, sensor_harmonic on config '{a.config}', "
        "one fresh process a side, both at the same time",
        "old": {"src": str(a.old_src), **t_old},
        "new": {"src": "this checkout", **t_new},
        "new_over_old": {k: t_new[k] / t_old[k] for k in ("wall_s", "cpu_s", "peak_rss_MB")},
        "load_average_1_5_15_at_end": os.getloadavg(),
        "results": compare_results(*dirs),
    }
    out = ROOT / "results/benchmarks" / f"sensor_stages_{a.config}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps({k: rec[k] for k in ("old", "new", "new_over_old")}, indent=1), rec["results"]["counts"])


if __name__ == "__main__":
    main()
