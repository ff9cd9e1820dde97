"""sfepy's first finite-element domain without SymPy: its serendipity bases read only if a serendipity space is made.

At the first ``FEDomain`` sfepy builds its table of polynomial spaces by importing every class of
``sfepy/discrete/fem/poly_spaces.py``. One of them, the serendipity space, holds its basis functions as SymPy
expressions that its class body imports (``sfepy/discrete/fem/_serendipity.py``): SymPy's import and those
expressions cost 0.33 s of CPU in every process that assembles a model, for an element this project never uses
(its meshes are hexahedra and tetrahedra with Lagrange bases). :func:`defer_serendipity_bases` puts a stand-in for
that module in ``sys.modules`` first: its ``all_bfs`` is the same table, read from sfepy's module at its first
look-up (the serendipity space's constructor), so a serendipity space still works as before. Nothing else in sfepy
imports the module (sfepy 2026.3, pinned in pyproject.toml); tests/test_housing.py checks both halves.
"""

from __future__ import annotations

import importlib.util
import sys
import types
from collections.abc import Mapping

MODULE = "sfepy.discrete.fem._serendipity"


class _DeferredBases(Mapping):
    """sfepy's ``all_bfs`` (dimension -> order -> bases), executed from its module at the first look-up."""

    def __init__(self, spec):
        self._spec = spec
        self._table = None

    def _load(self) -> dict:
        if self._table is None:
            module = importlib.util.module_from_spec(self._spec)
            self._spec.loader.exec_module(module)
            sys.modules[MODULE] = module
            self._table = module.all_bfs
        return self._table

    def __getitem__(self, key):
        return self._load()[key]

    def __iter__(self):
        return iter(self._load())

    def __len__(self) -> int:
        return len(self._load())


def defer_serendipity_bases() -> None:
    """Put the stand-in of sfepy's serendipity module in ``sys.modules``, unless that module is already there."""
    if MODULE in sys.modules:
        return
    spec = importlib.util.find_spec(MODULE)
    if spec is None:  # another sfepy: nothing to defer
        return
    stand_in = types.ModuleType(MODULE, "sfepy's serendipity bases, read at their first use (piezobearing)")
    stand_in.all_bfs = _DeferredBases(spec)
    sys.modules[MODULE] = stand_in


JAX_TERMS = "sfepy.terms.terms_jax"


def skip_jax_terms() -> None:
    """Without JAX, put an empty stand-in for sfepy's JAX terms in ``sys.modules`` (unless it is there already).

    sfepy's term table imports every ``sfepy/terms/terms*.py``; its proof-of-concept JAX terms, without JAX,
    print "install jax and jaxlib to use terms_jax.py!" and a WARNING with "No module named 'jax'" on every run,
    about terms this project never uses. The stand-in holds no terms, so the table is the same as sfepy builds
    it without JAX, and nothing is printed. With JAX installed nothing changes.
    """
    if JAX_TERMS in sys.modules or importlib.util.find_spec("jax") is not None:
        return
    sys.modules[JAX_TERMS] = types.ModuleType(JAX_TERMS, "sfepy's JAX terms, left out: JAX is not installed (piezobearing)")


# before any sfepy import of the modules that import this one (housing_fem, sensor.fem)
skip_jax_terms()
