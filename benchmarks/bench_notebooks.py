"""The figure notebooks' CPU: every notebook executed by papermill as its rule does, in a folder where the CI
workflow finished, fresh (every user's run) and warm (the tests' runs, tests/warm_kernel.py), and the previous
revision's notebooks beside this checkout's, as ratios.

Each notebook of ``notebooks/`` runs as ``papermill NOTEBOOK OUT -k python3 -p figure SCRATCH/NAME.png`` in
``RUN`` (its other parameters keep their defaults, the paths of that run's results), its executed notebook and
figure going to a scratch folder, papermill found on PATH as a job finds it; a set is all of them, one after the
other. ``old``: the notebooks of ``--old REV`` (``git show``), fresh processes; ``cold``: this checkout's
notebooks, fresh processes; ``warm_kernel``: this checkout's notebooks with tests/warm_kernel.py's kernel spec
first on ``JUPYTER_PATH`` (papermill fresh); ``warm``: the same and its papermill stand-in first on PATH, as the
tests' runs (the server started for the set, its start counted). All use this checkout's package. CPU seconds are
user + system of every process (papermill, kernels, stubs, the server), from the children's resource usage; the
sets rotate (old, cold, warm_kernel, warm, old, ...), ``-n`` rounds, and the ratios are taken round by round,
which keeps them meaningful on a shared machine. Checked every round: each figure byte for byte against the run's
own (``RUN/results/figures``); each executed notebook of ``warm_kernel`` and ``warm`` against ``cold`` (cells and
outputs, the displayed images; not the times papermill and the kernel record, nor the random id papermill gives
the injected-parameters cell); the outputs of ``old`` against ``cold``.

The whole of the tests' ``ci_run`` fixture, old against new, is benchmarks/bench_ci_jobs.py's measurement (its
CPU, each job's, and the two sides' figures and number files compared).

Writes ``results/benchmarks/notebooks.json``. Usage: ``python benchmarks/bench_notebooks.py RUN [--old REV]
[-n 3]``, RUN a folder where ``snakemake all --configfile config/ci.yaml`` finished (``tests/conftest.py``'s
``ci_run`` makes one).
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from warm_kernel import WarmKernels  # noqa: E402


def figure_of(notebook: Path) -> str:
    """The default of a notebook's ``figure`` parameter (its rule's figure, relative to the run)."""
    for cell in json.loads(notebook.read_text())["cells"]:
        if "parameters" in cell["metadata"].get("tags", []):
            for line in "".join(cell["source"]).splitlines():
                if line.startswith("figure ="):
                    return line.split("=", 1)[1].strip().strip("\"'")
    raise ValueError(f"{notebook}: no figure parameter")


def executed(path: Path) -> dict:
    """An executed notebook without what differs between any two executions: papermill's times and durations,
    the kernel's message times, the random id papermill gives its injected-parameters cell."""
    nb = json.loads(path.read_text())
    nb["metadata"].pop("papermill", None)
    for cell in nb["cells"]:
        cell["metadata"].pop("papermill", None)
        cell["metadata"].pop("execution", None)
        if "injected-parameters" in cell["metadata"].get("tags", []):
            cell.pop("id", None)
    return nb


def outputs(nb: dict) -> list:
    """What a notebook showed: the outputs of its code cells, in order."""
    return [o for c in nb["cells"] if c["cell_type"] == "code" for o in c["outputs"]]


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_set(run: Path, notebooks: Path, scratch: Path, warm: str | None) -> dict:
    """Execute every notebook of ``notebooks`` once in ``run``; CPU seconds of the set, whether each figure is the
    run's, byte for byte, and the executed notebooks (:func:`executed`)."""
    bindir = Path(sys.executable).parent
    env_before = dict(os.environ)
    figures, done = {}, {}
    c0 = children_cpu()
    kernels = WarmKernels(notebooks, papermill=warm == "papermill") if warm else None
    # PATH as a job's: the environment's bin folder last (workflow/rules/common.smk), a warm stand-in first
    path = [p for p in os.environ["PATH"].split(os.pathsep) if p and Path(p) != bindir] + [str(bindir)]
    env = {**os.environ, "PATH": os.pathsep.join(path)}
    try:
        for nb in sorted(notebooks.glob("*.ipynb")):
            figure = figure_of(nb)
            figures[nb.stem] = (scratch / Path(figure).name, run / figure)
            subprocess.run(["papermill", str(nb), str(scratch / nb.name), "-k", "python3", "-p", "figure",
                            str(figures[nb.stem][0])], cwd=run, env=env, check=True, capture_output=True)
    finally:
        if kernels is not None:
            kernels.close()
        os.environ.clear()
        os.environ.update(env_before)
    cpu = children_cpu() - c0
    for nb in sorted(notebooks.glob("*.ipynb")):
        done[nb.stem] = executed(scratch / nb.name)
    return {
        "cpu_s": cpu,
        "figures_identical": {k: new.read_bytes() == old.read_bytes() for k, (new, old) in figures.items()},
        "notebooks": done,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, nargs="?")
    ap.add_argument("--old", default=None, help="a revision whose notebooks to run beside this checkout's")
    ap.add_argument("-n", type=int, default=3)
    a = ap.parse_args()
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)  # as the test suite runs (tests/conftest.py)
    out = ROOT / "results/benchmarks/notebooks.json"
    run = a.run.resolve()
    tmp = Path(tempfile.mkdtemp(prefix="bench_notebooks_"))
    kinds = {"cold": (ROOT / "notebooks", None), "warm_kernel": (ROOT / "notebooks", "kernel"),
             "warm": (ROOT / "notebooks", "papermill")}
    if a.old:
        old = tmp / "old_notebooks"
        old.mkdir()
        for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
            old_text = subprocess.run(["git", "show", f"{a.old}:notebooks/{nb.name}"], cwd=ROOT,
                                      capture_output=True, text=True, check=True).stdout
            (old / nb.name).write_text(old_text)
        kinds = {"old": (old, None), **kinds}
    scratch = tmp / "out"  # one for all sets: the figure parameter, which papermill writes into each notebook, is
    scratch.mkdir()  # the same; each set's figures and notebooks are read before the next set runs
    run_set(run, kinds["cold"][0], scratch, None)  # warm-up: bytecode caches, page cache
    rounds = []
    for i in range(a.n):
        r = {kind: run_set(run, nbs, scratch, warm) for kind, (nbs, warm) in kinds.items()}
        rounds.append(r)
        print(f"round {i}: " + ", ".join(f"{k} {v['cpu_s']:.2f} s" for k, v in r.items()), flush=True)

    def med(key):
        return statistics.median(key(r) for r in rounds)

    rec = {
        "what": "every notebook of notebooks/, executed by papermill in a finished CI run's folder (its figure to "
                "a scratch folder); CPU seconds (user + system) of every process of a set of all of them",
        "notebooks": sorted(nb.stem for nb in (ROOT / "notebooks").glob("*.ipynb")),
        "rounds": a.n,
        "old_revision": a.old,
        **{f"{k}_cpu_s": med(lambda r, k=k: r[k]["cpu_s"]) for k in kinds},
        **{f"{k}_cpu_s_each_round": [r[k]["cpu_s"] for r in rounds] for k in kinds},
        "warm_over_cold": med(lambda r: r["warm"]["cpu_s"] / r["cold"]["cpu_s"]),
        "warm_kernel_over_cold": med(lambda r: r["warm_kernel"]["cpu_s"] / r["cold"]["cpu_s"]),
        "warm_over_warm_kernel": med(lambda r: r["warm"]["cpu_s"] / r["warm_kernel"]["cpu_s"]),
        "figures_byte_identical_to_the_run": all(all(s["figures_identical"].values()) for r in rounds
                                                 for s in r.values()),
        "warm_notebooks_identical_to_cold_but_times": all(r[k]["notebooks"] == r["cold"]["notebooks"]
                                                          for r in rounds for k in ("warm", "warm_kernel")),
        "load_average_1_5_15_at_end": os.getloadavg(),
    }
    if a.old:
        rec["cold_over_old"] = med(lambda r: r["cold"]["cpu_s"] / r["old"]["cpu_s"])
        rec["warm_over_old"] = med(lambda r: r["warm"]["cpu_s"] / r["old"]["cpu_s"])
        rec["old_and_cold_outputs_identical"] = {
            k: all(outputs(r["old"]["notebooks"][k]) == outputs(r["cold"]["notebooks"][k]) for r in rounds)
            for k in rec["notebooks"]
        }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print(json.dumps(rec, indent=1))


if __name__ == "__main__":
    main()
