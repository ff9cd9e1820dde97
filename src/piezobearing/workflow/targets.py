"""Which jobs a config asks for, beyond the fixed targets: read by the workflow's rules at its start, so light
(no physics imported)."""

from __future__ import annotations


def extra_fault_types(config: dict) -> list[str]:
    """The fault types of ``signals.detector.classification_types`` that need their own record (rule
    fault_type_voltage): all but the faulty case's own type when it has exactly one; none without a defect
    (the size and place of the extra types' defect come from the faulty case's first defect)."""
    defects = config["bearing"]["defects"]
    if not defects:
        return []
    own = {d["type"] for d in defects}
    return [t for t in dict.fromkeys(config["signals"]["detector"]["classification_types"]) if own != {t}]
