"""Cost of the sensor_comparison study's cases, before and after sharing the housing model; its SLURM resources.

    python benchmarks/bench_sensor_comparison.py [--configfile config/ci.yaml] [--cases 2] [--start 0] [--from-rules]

Runs ``--cases`` cases from the ``--start``-th of the config's ``sensor_comparison`` table, each in a child process (the
study_case rule's function, :func:`piezobearing.stages.studies.run_case`, on the workflow's resistance fit and
sensor FEM response, which must exist: run the workflow on the config first), two ways:

* ``previous``: the case builds its own healthy and faulty housing (mesh, model, modes), projects the roller
  loads on every raceway column (:meth:`HousingModel.column_loads`) and steps the modal recurrence in a
  Python loop (its ``einsum`` form, kept here): what every case did before;
* ``shared``: the housing models computed once per mesh (the rule sensor_comparison_housing, timed apart,
  in a child each), the case reads them, projects each roller's patch on its few columns and steps the
  modes compiled.

Both write the case's summary.json; the record says whether the two are byte-identical. Per case it records
the wall and CPU seconds and the child's peak RSS, and the ratios previous / shared. Writes
results/benchmarks/sensor_comparison.json beside the rule's resources in workflow/rules/studies.smk
(STUDY_MEM_MB, STUDY_RUNTIME_MIN).

``--from-rules``: gathers what Snakemake measured for every case of the study's last run instead (the
benchmark files of the rules study_case and sensor_comparison_housing under results/benchmarks/rules/).
"""

from __future__ import annotations

import argparse
import filecmp
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd

REPO = Path(__file__).resolve().parents[1]

# One case (or one housing model) in this process; prints its wall and CPU seconds and peak RSS [MB] as JSON.
_CHILD = """
import json, resource, sys, time
import numpy as np
from piezobearing import config as cfgmod
from piezobearing.housing import fem
from piezobearing.stages.housing_model import write_housing
from piezobearing.stages.studies import run_case
from piezobearing.config.cases import case_config, check_studies

configfile, index, mode, inputs, out = sys.argv[1], int(sys.argv[2]), sys.argv[3], json.loads(sys.argv[4]), sys.argv[5]
config = cfgmod.load(configfile)
row = check_studies(config)["sensor_comparison"].iloc[index].to_dict()

if mode == "previous":
    def project_every_column(columns, ops, load_N, angle_rad, chunk=2048):
        nt = load_N.shape[0]
        g, f = np.empty(nt), np.empty((nt, ops.omega.size))
        r, half = columns.radius_m, 0.5 * columns.patch_width_m
        for k in range(0, nt, chunk):
            q, psi = load_N[k:k + chunk], angle_rad[k:k + chunk]
            s = psi.ravel() * r
            w = fem.box_weights(columns.psi_rad * r, s - half, s + half, period=2 * np.pi * r).reshape(
                q.shape[0], q.shape[1], -1)
            wy = np.einsum("tj,tjc->tc", q * np.sin(psi), w)
            wz = np.einsum("tj,tjc->tc", -q * np.cos(psi), w)
            g[k:k + chunk] = wy @ ops.static_y + wz @ ops.static_z
            f[k:k + chunk] = wy @ ops.modal_y + wz @ ops.modal_z
        return g, f

    def modal_loop(forces, omega, zeta, h, velocity=False):
        a_mat, b_mat = fem._ramp_recurrence(omega, zeta, h)
        nt, n = forces.shape
        q, qd = np.empty((nt, n)), np.zeros((nt, n))
        x = np.stack([forces[0] / omega**2, np.zeros(n)], axis=1)
        q[0] = x[:, 0]
        for k in range(nt - 1):
            x = np.einsum("nij,nj->ni", a_mat, x) + np.einsum(
                "nij,nj->ni", b_mat, np.stack([forces[k], forces[k + 1]], 1))
            q[k + 1], qd[k + 1] = x[:, 0], x[:, 1]
        return (q, qd) if velocity else q

    fem.project_roller_loads = project_every_column
    fem.modal_response = modal_loop

t0, c0 = time.perf_counter(), time.process_time()
if mode.startswith("housing_"):
    write_housing(case_config(config, row), mode == "housing_faulty", out)
else:
    run_case("sensor_comparison", f"bench{index}", row, config, out, inputs)
print(json.dumps({"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def _resources() -> dict:
    """The study's resources as studies.smk declares them."""
    text = (REPO / "workflow/rules/studies.smk").read_text()
    out = {}
    for key, name in (("mem_mb", "STUDY_MEM_MB"), ("runtime_min", "STUDY_RUNTIME_MIN")):
        block = text[text.index(f"{name} = {{"):]
        block = block[: block.index("\n}")]
        m = re.search(r'"sensor_comparison":\s*([0-9.]+)', block)
        out[key] = float(m.group(1)) if m else None
    return out


def _child(configfile: str, index: int, mode: str, inputs: dict, out: str) -> dict:
    res = subprocess.run([sys.executable, "-c", _CHILD, configfile, str(index), mode, json.dumps(inputs), out],
                         cwd=REPO, capture_output=True, text=True, check=True)
    record = json.loads(res.stdout.strip().splitlines()[-1])
    print(mode, index, record, file=sys.stderr)
    return record


def _from_rules(results: Path, config: dict) -> dict:
    """What Snakemake measured for the config's cases and housing models: seconds, CPU seconds and max RSS of each
    job (benchmark files of other configs' cases in the same folder are left out)."""
    from snakemake.utils import Paramspace

    from piezobearing.config.cases import case_config, check_studies
    from piezobearing.workflow.registry import reads_digest

    table = check_studies(config)["sensor_comparison"]
    cases = list(Paramspace(table, filename_params="*", single_wildcard="case").instance_patterns)
    meshes = [f"{mesh}_{reads_digest(case_config(config, row), 'sensor_comparison_housing')}"
              for row in table.to_dict("records") for mesh in ("healthy", "faulty")]
    out = {}
    for key, folder, names in (("cases", "study_case_sensor_comparison", cases),
                               ("housings", "sensor_comparison_housing", sorted(set(meshes)))):
        out[key] = []
        for name in names:
            tsv = results / "benchmarks/rules" / folder / f"{name}.tsv"
            if not tsv.exists():
                continue
            row = pd.read_csv(tsv, sep="\t").iloc[0]
            out[key].append({"name": name, "wall_s": float(row["s"]), "cpu_s": float(row["cpu_time"]),
                             "peak_rss_mb": float(row["max_rss"])})
    if not out["cases"]:
        raise SystemExit("no cases measured: run the study first (snakemake ... study_all) or drop --from-rules")
    for key in ("cases", "housings"):
        for q in ("wall_s", "cpu_s", "peak_rss_mb"):
            values = [c[q] for c in out[key]]
            out[f"{key}_{q}_max"] = max(values) if values else None
            out[f"{key}_{q}_total"] = sum(values) if values and q != "peak_rss_mb" else None
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--configfile", default="config/ci.yaml")
    ap.add_argument("--cases", type=int, default=2)
    ap.add_argument("--start", type=int, default=0, help="index of the first case in the table")
    ap.add_argument("--out", default="results/benchmarks/sensor_comparison.json")
    ap.add_argument("--from-rules", action="store_true", help="gather the rules' benchmark files")
    args = ap.parse_args()
    sys.path.insert(0, str(REPO / "src"))
    from piezobearing import config as cfgmod
    from piezobearing.config import results_folder
    from piezobearing.config.cases import case_config, check_studies
    from piezobearing.workflow.registry import reads_digest

    config = cfgmod.load(args.configfile)
    results = REPO / results_folder(config)
    record = {"configfile": args.configfile, "n_seeds": config["sensor_comparison"]["n_seeds"],
              "declared": _resources()}
    if args.from_rules:
        record.update(source="the rules' benchmark files", **_from_rules(results, config))
    else:
        inputs = {"resistance": str(results / "calibration/resistance.json")}
        if config["signals"]["sensor_fem_correction"]:
            inputs["harmonic"] = str(results / "sensor/harmonic.csv")
        table = check_studies(config)["sensor_comparison"]
        cases, housings = [], {}
        with tempfile.TemporaryDirectory() as tmp:
            for i in range(args.start, min(args.start + args.cases, len(table))):
                digest = reads_digest(case_config(config, table.iloc[i].to_dict()), "sensor_comparison_housing")
                files = {}
                for mesh in ("healthy", "faulty"):
                    path = f"{tmp}/{mesh}_{digest}.npz"
                    if path not in housings:
                        housings[path] = _child(args.configfile, i, f"housing_{mesh}", {}, path)
                    files[f"housing_{mesh}"] = path
                prev = _child(args.configfile, i, "previous", inputs, f"{tmp}/previous{i}/summary.json")
                new = _child(args.configfile, i, "shared", {**inputs, **files}, f"{tmp}/shared{i}/summary.json")
                same = filecmp.cmp(f"{tmp}/previous{i}/summary.json", f"{tmp}/shared{i}/summary.json", shallow=False)
                cases.append({"overrides": table.iloc[i].to_dict(), "previous": prev, "shared": new,
                              "summary_byte_identical": same,
                              "cpu_ratio_previous_over_shared": prev["cpu_s"] / new["cpu_s"],
                              "wall_ratio_previous_over_shared": prev["wall_s"] / new["wall_s"]})
        housing_cpu = sum(h["cpu_s"] for h in housings.values())
        record.update(
            source="each case and housing model in a child process",
            cases=cases,
            housings=list(housings.values()),
            # the measured cases as a study: every case building its housings, against the housings once
            study_cpu_s_previous=sum(c["previous"]["cpu_s"] for c in cases),
            study_cpu_s_shared=housing_cpu + sum(c["shared"]["cpu_s"] for c in cases),
        )
        record["study_cpu_ratio_previous_over_shared"] = record["study_cpu_s_previous"] / record["study_cpu_s_shared"]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
