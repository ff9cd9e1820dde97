"""The package's structure, read with ``ast`` (no module is imported): its layers hold (the import-linter contract
in ``pyproject.toml``), no import cycle in ``src``, the diagnosis engine imports no subject (nor any physics,
stage or plotting module; the fit machinery below it is shared), and the
diagnosis package keeps its modules under ~600 lines and its functions under ~80 (or says why
with a ``# long:`` comment in the function).

Every ``import`` counts, also those inside functions: a lazy import only hides a cycle
(``effects/ac_coupling.py`` and ``model.py`` once imported each other that way).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PACKAGE = "piezobearing"


def _modules() -> dict[str, Path]:
    out = {}
    for p in sorted((SRC / PACKAGE).rglob("*.py")):
        parts = list(p.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """Modules of the package that ``name`` imports (``from X import y``: X.y if it is a module, else X)."""
    is_pkg = path.name == "__init__.py"
    here = name.split(".") if is_pkg else name.split(".")[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[: len(here) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod for a in node.names]
        else:
            continue
        for t in targets:
            # `import a.b.c` binds a, but runs a.b.c: count the deepest module of the package
            while t and t not in modules and "." in t:
                t = t.rsplit(".", 1)[0]
            if t in modules and t != name:
                out.add(t)
    return out


def import_graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as a list of modules (first == last), or None (iterative depth-first search)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    for root in sorted(graph):
        if root in state:
            continue
        path, stack = [root], [iter(sorted(graph[root]))]
        state[root] = 1
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                state[path.pop()] = 2
                stack.pop()
            elif state.get(nxt) == 1:
                return path[path.index(nxt) :] + [nxt]
            elif nxt not in state:
                state[nxt] = 1
                path.append(nxt)
                stack.append(iter(sorted(graph.get(nxt, ()))))
    return None


def test_the_graph_reads_the_package():
    g = import_graph()
    assert "piezobearing.diagnosis.calibration.model" in g
    assert "piezobearing.sensor.calibration" in g["piezobearing.diagnosis.calibration.model"]


def test_the_cycle_finder_finds_a_lazy_import_cycle():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(g) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_cycle_in_src():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


DIAGNOSIS = f"{PACKAGE}.diagnosis"
#: The fit machinery under the engine (parameters, units, least squares, profiles): shared with the calibration.
FITTING = f"{PACKAGE}.fitting"


def _subject_packages(modules: dict[str, Path]) -> set[str]:
    """Subpackages of diagnosis/ that are subjects (they hold a ``subject`` module)."""
    return {
        m.rsplit(".", 1)[0] for m in modules if m.startswith(DIAGNOSIS + ".") and m.endswith(".subject")
    } - {DIAGNOSIS}


def test_the_engine_imports_no_subject_and_no_physics():
    modules = _modules()
    subjects = _subject_packages(modules)
    assert f"{DIAGNOSIS}.calibration" in subjects
    g = import_graph()

    def in_subject(m: str) -> bool:
        return any(m == s or m.startswith(s + ".") for s in subjects)

    engine = [m for m in g if (m == DIAGNOSIS or m.startswith(DIAGNOSIS + ".")) and not in_subject(m)]
    assert f"{DIAGNOSIS}.engine" in engine and f"{DIAGNOSIS}.report.sections" in engine
    for m in engine:
        bad = sorted(t for t in g[m] if in_subject(t) or not t.startswith((DIAGNOSIS, FITTING)))
        assert not bad, (
            f"engine module {m} imports {bad}: the engine must not know its subjects or the physics"
        )


def _functions(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node


def test_diagnosis_modules_and_functions_stay_short():
    for name, path in _modules().items():
        if not name.startswith(DIAGNOSIS):
            continue
        text = path.read_text()
        lines = text.splitlines()
        assert len(lines) <= 600 or "long module:" in text, (
            f"{path}: {len(lines)} lines (split it, or say why)"
        )
        for fn in _functions(ast.parse(text)):
            body = lines[fn.lineno - 1 : fn.end_lineno]
            if len(body) > 80:
                assert any("# long:" in b for b in body), f"{path}:{fn.lineno} {fn.name}: {len(body)} lines"


def test_the_layers_hold():
    """``lint-imports`` checks the contract of ``pyproject.toml`` (every import, those inside functions too)."""
    out = subprocess.run([Path(sys.executable).with_name("lint-imports"), "--no-cache"], cwd=ROOT,
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-2000:]
    assert "1 kept, 0 broken" in out.stdout
