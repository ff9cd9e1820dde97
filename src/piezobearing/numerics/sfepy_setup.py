"""sfepy without its JAX terms where JAX is not installed: imported before sfepy by the modules that use it.

sfepy's term table imports every ``sfepy/terms/terms*.py``; its proof-of-concept JAX terms, without JAX, print
"install jax and jaxlib to use terms_jax.py!" and a WARNING with "No module named 'jax'" in every process that
builds a finite-element model, about terms this project never uses. :func:`skip_jax_terms` puts an empty stand-in
for that module in ``sys.modules`` first: the table is the same as sfepy builds it without JAX, and nothing is
printed. With JAX installed nothing changes.
"""

from __future__ import annotations

import importlib.util
import sys
import types

JAX_TERMS = "sfepy.terms.terms_jax"


def skip_jax_terms() -> None:
    """Without JAX, put an empty stand-in for sfepy's JAX terms in ``sys.modules`` (unless it is there already)."""
    if JAX_TERMS in sys.modules or importlib.util.find_spec("jax") is not None:
        return
    sys.modules[JAX_TERMS] = types.ModuleType(JAX_TERMS, "sfepy's JAX terms, left out: JAX is not installed (piezobearing)")


# at import: before sfepy's own import in the modules that import this one (housing.fem, sensor.fem)
skip_jax_terms()
