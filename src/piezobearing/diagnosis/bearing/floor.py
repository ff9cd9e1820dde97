"""The running bearing's noise floor: measured from the record, and again where a fault's lines lift it.

:func:`noise_floor` measures the voltage's white level over the whole record; :func:`floor_prepass` measures it
once more before the engine, on the residual of the best fault fitted alone, where the record's own spectrum is
lifted by a fault's lines (:mod:`.subject` and :mod:`.rung` measure it again on a final residual the same way).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..fit import fit_model
from ..noise import NoiseFloor, robust_diff_std, white_level
from ..selection import add_effect
from ..subject import Problem
from .effects import FAULT_TYPES

#: Final NRMSE below this share of the record's floor: the floor is measured again on the final residual.
REMEASURE_BELOW = 0.8


def noise_floor(v: np.ndarray, dt_s: float, clipped: np.ndarray | None = None) -> NoiseFloor:
    """The voltage's white level over the whole record (one long segment: the bearing's lines are narrow).

    The periodogram of the longest power-of-two stretch, 5-45% of f_s,
    line-free trimmed mean (:func:`piezobearing.diagnosis.noise.white_level`):
    the roller-pass harmonics are lines a few bins wide, left out.
    """
    mask = np.ones(v.size, dtype=bool) if clipped is None else ~clipped
    seg = int(2 ** np.floor(np.log2(max(mask.sum(), 64))))
    var, _ = white_level(v, mask, dt_s, segment=seg)
    return NoiseFloor(
        float(np.sqrt(var)), 0.0, float(mask.sum() * dt_s), 1,
        "whole record: line-free trimmed mean of the periodogram, 5-45% of fs", mask,
    )


def quiet_level(residual_V: np.ndarray, clipped: np.ndarray | None = None) -> float:
    """The white noise level [V] of a residual that is noise plus sparse events, from its quiet samples.

    :func:`~piezobearing.diagnosis.noise.robust_diff_std`: the median absolute deviation of the first
    differences, x 1.4826 / sqrt(2) (the differences take out the slow misfit, the median the sparse
    events). A fault's dips and bursts fill every bin of the spectrum but few samples: at 2550 Hz and
    30 dB this gives 0.28 x the record's spectral floor for the inner-race and the rolling-element
    records of the tests, 0.95 for the healthy one and 0.90-5.3 for every other catalogue effect
    (measured).
    """
    r = np.asarray(residual_V, dtype=float)
    return robust_diff_std(r if clipped is None else r[~clipped])


def floor_prepass(p: Problem, settings, clipped: np.ndarray | None, progress=None, fits: dict | None = None) -> Problem:
    """The noise floor measured once more, before the engine, where a fault's lines have lifted it.

    The baseline is fitted with the record's floor. Where its residual's
    quiet level (:func:`quiet_level`) is below :data:`REMEASURE_BELOW` x that
    floor (the floor is lifted by lines that fill the spectrum but few
    samples), each fault of the catalogue (:data:`~.effects.FAULT_TYPES`) is
    fitted alone on top, as the engine's first ranking does
    (:func:`~piezobearing.diagnosis.selection.add_effect`); where the best
    leaves less than :data:`REMEASURE_BELOW` x the record's floor, the floor
    is measured on that residual the same way as on the record
    (:func:`noise_floor`) and ``p`` is returned with it; otherwise ``p``
    unchanged. A white floor's level does not move the fits, only the
    evidence: the engine's run with this floor is the second run of the old
    two-pass method, found with four fits instead of a whole run. Where ``p`` is returned unchanged, the
    baseline's fit is put in ``fits["baseline"]`` (the engine's own first fit, the same numbers: not fitted twice).
    """
    v, rec = np.asarray(p.voltage_V, dtype=float), p.record
    note = progress or (lambda _msg: None)
    note("floor pre-pass: baseline")
    base = fit_model(p.baseline, rec, v, p.floor, start=p.baseline_start, starts=p.baseline_starts,
                     max_nfev=settings.max_nfev, ftol=settings.ftol)
    base.model.release()
    if fits is not None:
        fits["baseline"] = base  # taken back below if the floor changes
    if quiet_level(base.residual_V, clipped) >= REMEASURE_BELOW * p.floor.voltage_noise_V:
        return p
    best = base
    for name in FAULT_TYPES:
        if name in p.catalogue:
            note(f"floor pre-pass: baseline + {name}")
            f = add_effect(base, p.catalogue[name], rec, v, p.floor, settings)
            f.model.release()
            if f.nrmse < best.nrmse:
                best = f
    if best.nrmse >= REMEASURE_BELOW * best.floor_nrmse:
        return p
    if fits is not None:
        fits.pop("baseline")
    fl = noise_floor(best.residual_V, rec.dt_s, clipped)
    fl = replace(fl, method=f"{fl.method}, of the residual of {best.model.label} fitted before the search "
                 f"(pre-pass): the record's own ({p.floor.voltage_noise_V:.4g} V) was lifted by the fault's lines")
    return replace(p, floor=fl)
