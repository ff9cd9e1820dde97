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
from typing import Callable

from ..io import write_json
from .registry import declared, declared_config, module_code_hash


def remembered(memo: str | Path, run: Callable[[], dict]) -> tuple[dict, bool]:
    """``run()``'s result kept in the JSON file ``memo`` (its name: a digest of all the result depends on).

    Returns (the result, True) after running, (the file's result, False) when ``memo`` holds one. What ``run``
    raises is not remembered; a memo that cannot be read is run again, one that cannot be written only costs
    the next start another run.
    """
    memo = Path(memo)
    try:
        return json.loads(memo.read_text()), False
    except (OSError, ValueError):
        pass  # none yet, or unreadable
    result = run()
    try:
        write_json(result, memo)
    except OSError:
        pass
    return result, True


def check_subject_once(subject_module: str, rule: str, config: dict, cache_dir: str | Path) -> bool:
    """``SUBJECT.check_config`` of module ``subject_module`` on the config keys ``rule`` declares, unless these
    values and this code passed before.

    Returns True when the check ran, False when it was remembered. Raises what the check raises.
    """
    reads = declared(config, rule)
    key = hashlib.sha256(json.dumps(reads, sort_keys=True).encode() + b"\0"
                         + module_code_hash(subject_module).encode()).hexdigest()[:20]

    def check() -> dict:
        importlib.import_module(subject_module).SUBJECT.check_config(declared_config(reads, rule))
        return {"subject": subject_module, "rule": rule, "passed": True}

    return remembered(Path(cache_dir) / f"{subject_module.rsplit('.', 2)[-2]}_{key}.ok", check)[1]
