"""The envelope detector's call settings chosen on labelled records, and the choice judged on records it was
not made on (grouped cross-validation).

A labelled set (real records with their true fault type, and a group per record: its fault size, or its
location) is read once per setting that changes what the spectrum shows (:data:`SPECTRUM_GRID`, one
:func:`..detectors.envelope.measure` per record and setting); every decision setting
(:data:`DECISION_GRID`) is then a cheap :func:`..detectors.envelope.call_of` of those readings. The type rule's
separation comes first (:func:`supported_separation`: above every wrong-type call the records show under any
setting of the grid); the other settings are then chosen by :func:`objective`: the records called right, less
:data:`WRONG_TYPE_COST` for each record called the wrong fault type or a healthy record called faulty. A call
of ``unknown`` type counts neither way: it gives up a right call where the type was right.

:func:`cross_validate` holds out one group at a time, chooses on the rest, and calls the held-out records with
the settings chosen without them: the score of those calls is what the choice is worth on records it has not
seen. The false-alarm probability is not tuned (it is what the detector states).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from .detectors.envelope import Reading, Settings, call_of
from .detectors.result import FAULT_TYPES, UNKNOWN

#: Settings that change what the spectrum shows (each value read once per record); the first value of each is
#: the detector's default.
SPECTRUM_GRID = {
    "cage_lines": (True, False),
    "frequency_tolerance": (0.01, 0.005, 0.02),
    "mains_Hz": ((50.0, 60.0), ()),
}
#: Settings of the decision alone (cheap on a reading).
DECISION_GRID = {
    "min_lines_above": (2, 1, 3),
    "min_type_separation_dB": (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0),
}
#: What a wrong-type call (or a healthy record called faulty) costs against a right call in :func:`objective`:
#: a repair of the wrong part, or of a sound machine, costs more than a fault found at the next inspection.
WRONG_TYPE_COST = 2.0
#: The outcomes of a call against its truth.
OUTCOMES = ("right", "wrong_type", "unknown", "missed", "false_alarm")


def spectrum_settings(base: Settings, grid: dict = SPECTRUM_GRID) -> list[Settings]:
    """Every combination of the spectrum grid's values over ``base``, the defaults first."""
    keys = list(grid)
    return [replace(base, **dict(zip(keys, values, strict=True))) for values in itertools.product(*grid.values())]


def decision_settings(grid: dict = DECISION_GRID) -> list[dict]:
    """Every combination of the decision grid's values, the defaults first."""
    keys = list(grid)
    return [dict(zip(keys, values, strict=True)) for values in itertools.product(*grid.values())]


@dataclass(frozen=True)
class CallTable:
    """The call of every record under every setting of the grid.

    Attributes
    ----------
    settings : list of Settings
        The grid, in order (the first: the base's spectrum settings and the decision grid's first values).
    calls : ndarray of str
        (n_settings, n_records) calls.
    margins : list of list of dict
        Per setting and record, each family's best margin [dB].
    separations : ndarray
        (n_settings, n_records) the winner's margin over the runner-up's [dB] (nan where no fault is
        detected).
    """

    settings: list[Settings]
    calls: np.ndarray
    margins: list[list[dict]]
    separations: np.ndarray


def call_table(readings: Sequence[Sequence[Reading]], spectra: Sequence[Settings],
               decisions: Sequence[dict]) -> CallTable:
    """:func:`call_of` of every record's reading (``readings[i][r]``: spectrum setting i, record r) under every
    decision setting."""
    settings, calls, margins, seps = [], [], [], []
    for spectrum, per_record in zip(spectra, readings, strict=True):
        for decision in decisions:
            s = replace(spectrum, **decision)
            row, mrow, srow = [], [], []
            for reading in per_record:
                call, m, typed = call_of(reading, s)
                row.append(call)
                mrow.append(m)
                srow.append(typed["separation_dB"] if typed is not None else separation(call, m))
            settings.append(s)
            calls.append(row)
            margins.append(mrow)
            seps.append(srow)
    return CallTable(settings, np.array(calls, dtype=object), margins, np.array(seps, dtype=float))


def separation(call: str, margins: dict) -> float:
    """The called family's margin over the largest other family's [dB]; nan for ``none`` or ``unknown``."""
    if call not in margins:
        return float("nan")
    return margins[call] - max((m for f, m in margins.items() if f != call), default=float("-inf"))


def outcome(truth: str, call: str) -> str:
    """One of :data:`OUTCOMES`: a call against its truth (``unknown`` on a faulty record is neither right nor
    wrong; on a healthy record it is a false alarm as any fault call is)."""
    if truth == "none":
        return "right" if call == "none" else "false_alarm"
    if call == "none":
        return "missed"
    if call == UNKNOWN:
        return "unknown"
    return "right" if call == truth else "wrong_type"


def score(truths: Sequence[str], calls: Sequence[str]) -> dict:
    """Counts of every outcome, overall and per true type, and the :func:`objective`."""
    counts = {o: 0 for o in OUTCOMES}
    per_type = {t: {o: 0 for o in OUTCOMES} | {"n": 0} for t in (*FAULT_TYPES, "none")}
    for t, c in zip(truths, calls, strict=True):
        o = outcome(t, c)
        counts[o] += 1
        per_type[t][o] += 1
        per_type[t]["n"] += 1
    return {"n": len(truths), **counts, "objective": objective(counts), "per_type": per_type}


def objective(counts: dict) -> float:
    """Right calls less :data:`WRONG_TYPE_COST` per wrong-type call and per false alarm."""
    return counts["right"] - WRONG_TYPE_COST * (counts["wrong_type"] + counts["false_alarm"])


def wrong_type_separations(table: CallTable, truths: Sequence[str], records: Sequence[int]) -> list[float]:
    """The winner's separation from the runner-up [dB] of every wrong-type call the ``records`` get under any
    setting of the grid with the type rule at 0 dB (the call is the winner)."""
    return [float(table.separations[i, r]) for i, s in enumerate(table.settings) if s.min_type_separation_dB == 0.0
            for r in records if outcome(truths[r], table.calls[i, r]) == "wrong_type"]


def supported_separation(table: CallTable, truths: Sequence[str], records: Sequence[int],
                         values: Sequence[float] = DECISION_GRID["min_type_separation_dB"]) -> float:
    """The smallest separation of ``values`` [dB] above every wrong-type call's separation the ``records`` show
    under any setting of the grid (:func:`wrong_type_separations`; 0 where they show none).

    A wrong-type call anywhere in the grid shows how near two families come on these records when the winner
    is the wrong one; the chosen setting's own calls cannot show it, as it is chosen for having few."""
    top = max(wrong_type_separations(table, truths, records), default=-np.inf)
    above = [v for v in sorted(values) if v > top]
    if not above:
        raise ValueError(f"a wrong-type call stands {top:.2f} dB above its runner-up, beyond the grid's largest "
                         f"separation {max(values):g} dB; extend DECISION_GRID['min_type_separation_dB']")
    return float(above[0])


def choose(table: CallTable, truths: Sequence[str], records: Sequence[int]) -> int:
    """The setting chosen on ``records`` (indices): the type rule's separation they support
    (:func:`supported_separation`), and of the settings with it, the one of largest :func:`objective`; of
    equals, the fewest ``unknown`` calls, then the first in the grid's order (the defaults first)."""
    separation = supported_separation(table, truths, records)
    t = [truths[r] for r in records]
    best, best_key = None, None
    for i, setting in enumerate(table.settings):
        if setting.min_type_separation_dB != separation:
            continue
        s = score(t, [table.calls[i, r] for r in records])
        key = (s["objective"], -s["unknown"])
        if best_key is None or key > best_key:
            best, best_key = i, key
    return best


def cross_validate(table: CallTable, truths: Sequence[str], groups: Sequence[str]) -> dict:
    """Leave one group out: per group the setting chosen on the other records and the held-out calls it makes.

    Returns
    -------
    dict
        ``calls`` (per record, the call of the setting chosen without its group), ``chosen`` (per group the
        index of its setting), ``score`` (:func:`score` of the held-out calls).
    """
    calls = [""] * len(truths)
    chosen = {}
    for g in dict.fromkeys(groups):
        train = [r for r, h in enumerate(groups) if h != g]
        i = choose(table, truths, train)
        chosen[g] = i
        for r, h in enumerate(groups):
            if h == g:
                calls[r] = table.calls[i, r]
    return {"calls": calls, "chosen": chosen, "score": score(truths, calls)}


def settings_dict(s: Settings, keys: Sequence[str] = (*SPECTRUM_GRID, *DECISION_GRID)) -> dict:
    """The tuned fields of a setting, JSON-ready."""
    return {k: (list(getattr(s, k)) if isinstance(getattr(s, k), tuple) else getattr(s, k)) for k in keys}
