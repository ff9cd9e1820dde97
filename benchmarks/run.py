"""Run the benchmarks: each times a method against its previous or plain version and writes its JSON.

Usage, from the repository root with the package's environment active::

    python benchmarks/run.py                  # every method benchmark, one after the other
    python benchmarks/run.py lpm housing      # only these
    python benchmarks/run.py lpm -- --ci      # arguments after -- go to each named benchmark
    python benchmarks/run.py --list           # names and what each measures

A benchmark NAME is the script ``benchmarks/bench_NAME.py`` run in a process of its own from the repository
root; it writes ``results/benchmarks/NAME.json`` (see benchmarks/README.md for the exceptions and each
script's own options: ``python benchmarks/bench_NAME.py --help``). The whole-workflow measurements
(``workflow``, ``rules``) run the whole paper once or twice and are run only when named.
"""

from __future__ import annotations

import argparse
import ast
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
#: Benchmarks that run the whole workflow: only when named.
WHOLE_WORKFLOW = ("workflow", "rules")


def benchmarks() -> dict[str, Path]:
    """Every ``bench_NAME.py`` of this folder by NAME, sorted."""
    return {p.stem.removeprefix("bench_"): p for p in sorted(HERE.glob("bench_*.py"))}


def summary(path: Path) -> str:
    """The first line of a benchmark's module docstring."""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return doc.strip().splitlines()[0] if doc.strip() else ""


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    extra: list[str] = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1 :]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="benchmarks to run (default: all but the whole-workflow ones)")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and what each measures")
    args = ap.parse_args(argv)
    found = benchmarks()
    if args.list:
        for name, path in found.items():
            tag = " (whole workflow: only when named)" if name in WHOLE_WORKFLOW else ""
            print(f"{name:20s} {summary(path)}{tag}")
        return 0
    unknown = [n for n in args.names if n not in found]
    if unknown:
        print(f"run.py: no benchmark {', '.join(unknown)}; choose from {', '.join(found)}", file=sys.stderr)
        return 2
    names = args.names or [n for n in found if n not in WHOLE_WORKFLOW]
    failed = []
    for name in names:
        print(f"== {name}: python {found[name].relative_to(ROOT)} {' '.join(extra)}", flush=True)
        t0 = time.perf_counter()
        code = subprocess.run([sys.executable, str(found[name]), *extra], cwd=ROOT).returncode
        print(f"== {name}: exit {code} after {time.perf_counter() - t0:.0f} s", flush=True)
        if code != 0:
            failed.append(name)
    if failed:
        print(f"run.py: failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
