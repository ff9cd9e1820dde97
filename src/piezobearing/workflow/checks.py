"""The workflow's parse-time check of a diagnosis subject's config, done once per config and code.

A bad effect name in ``model.effects``, ``synthesis.hidden_effects``, ``bearing_diagnosis.effects`` or
``bearing.hidden_effects`` stops Snakemake before any job, with the subject's one-line
:class:`~piezobearing.diagnosis.effect.EffectError`. The check needs the subject's models, whose imports (scipy's
signal and stats, numba) cost about 1.5 s of CPU, at every start and every dry run. A config that passed is
remembered in the user's cache folder (``checked/<subject>_<digest>.ok`` in
:func:`~piezobearing.workflow.registry.user_cache_dir`), keyed by the SHA-256 of the config keys the
subject's rule declares (:func:`~piezobearing.workflow.registry.declared`; the check sees only those, strictly) and
of the subject's code (:func:`~piezobearing.workflow.registry.module_code_hash`): a start whose diagnosis settings
did not change costs a hash. Failures are not remembered.
"""

from __future__ import annotations

import hashlib
import importlib
import json
from pathlib import Path

from .registry import declared, declared_config, module_code_hash


def check_subject_once(subject_module: str, rule: str, config: dict, cache_dir: str | Path) -> bool:
    """``SUBJECT.check_config`` of module ``subject_module`` on the config keys ``rule`` declares, unless these
    values and this code passed before.

    Returns True when the check ran, False when it was remembered. Raises what the check raises.
    """
    reads = declared(config, rule)
    key = hashlib.sha256(json.dumps(reads, sort_keys=True).encode() + b"\0"
                         + module_code_hash(subject_module).encode()).hexdigest()[:20]
    memo = Path(cache_dir) / f"{subject_module.rsplit('.', 2)[-2]}_{key}.ok"
    if memo.is_file():
        return False
    importlib.import_module(subject_module).SUBJECT.check_config(declared_config(reads, rule))
    try:
        memo.parent.mkdir(parents=True, exist_ok=True)
        memo.write_text(f"{subject_module}: the config passed its check\n")
    except OSError:
        pass  # a read-only cache folder only costs the next start another check
    return True
