"""The code hash's import graph remembered from one workflow start to the next (registry.use_imports_cache)."""

from __future__ import annotations

import json
import subprocess
import sys

from piezobearing.workflow import registry

ENTRY = "workflow/scripts/diagnose.py"

CODE = """
import json, sys
from piezobearing.workflow import registry
registry.use_imports_cache(sys.argv[1])
parsed = []
imports = registry._imports
registry._imports = lambda source, module, is_package: parsed.append(module) or imports(source, module, is_package)
print(json.dumps([registry.code_hash({entry!r}), len(registry.package_modules({entry!r})), parsed]))
"""


def _start(cache) -> tuple[list, list]:
    """(code hash and module count of ENTRY, the modules parsed: None for the entry script) in a new process."""
    out = subprocess.run([sys.executable, "-c", CODE.format(entry=ENTRY), str(cache)], capture_output=True,
                         text=True, check=True)
    *result, parsed = json.loads(out.stdout.strip().splitlines()[-1])
    return result, parsed


def test_a_second_start_parses_nothing_and_hashes_the_same(tmp_path):
    """The first start parses every module and writes the cache at exit; the second reads every module's imports
    from it (it parses only the entry script) and gives the hash of a start without a cache."""
    cache = tmp_path / "imports.json"
    first, parsed = _start(cache)
    assert cache.is_file() and len(parsed) == first[1] + 1
    entries = json.loads(cache.read_text())
    assert len(entries) == first[1] and all(k.split()[1].startswith("piezobearing") for k in entries)
    second, parsed = _start(cache)
    assert second == first and parsed == [None]
    assert first == [registry.code_hash(ENTRY), len(registry.package_modules(ENTRY))]


def test_an_edited_module_is_parsed_again(tmp_path):
    """An entry keyed by another module text is not used: a module whose bytes changed is parsed afresh."""
    cache = tmp_path / "imports.json"
    first, _ = _start(cache)
    entries = json.loads(cache.read_text())
    # the cached imports of every module replaced by stale ones under keys its current bytes do not have
    cache.write_text(json.dumps({f"{'0' * 64} {k.split()[1]}": [] for k in entries}))
    again, parsed = _start(cache)
    assert again == first and len(parsed) == first[1] + 1


def test_the_cache_folder_follows_the_environment(monkeypatch, tmp_path):
    """$PIEZOBEARING_CACHE_DIR first, then $XDG_CACHE_HOME/piezobearing, then ~/.cache/piezobearing."""
    monkeypatch.setenv("PIEZOBEARING_CACHE_DIR", str(tmp_path / "mine"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert registry.user_cache_dir() == tmp_path / "mine"
    monkeypatch.delenv("PIEZOBEARING_CACHE_DIR")
    assert registry.user_cache_dir() == tmp_path / "xdg" / "piezobearing"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert registry.user_cache_dir() == tmp_path / "home" / ".cache" / "piezobearing"
