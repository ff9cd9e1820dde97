"""The running bearing's effects: what they add to the chain of :mod:`..chain`.

An effect of this subject declares parameters that the chain reads from the
values (a groove's width and position, the slip, the load, the clearance,
the mounting's share, the rollers' diameters) and, for interference, an
additive voltage. Its starts come from the residual of the current fit
(:class:`~piezobearing.diagnosis.effect.StartContext`; ``ctx.record.rig`` is
the :class:`~..chain.Rig`).
"""

from __future__ import annotations

import numpy as np

from ...effect import Effect as EngineEffect
from ...effect import StartContext
from .. import chain
from ..representations import fitted_kinematics

#: The widest defect the catalogue holds [m]: the upper bound of every defect's width (a groove, a pit). A fit
#: whose width interval reaches it fits no defect of the catalogue (:func:`~..rung.unidentified_reason`).
MAX_DEFECT_WIDTH_M = 3e-3


class Effect(EngineEffect):
    """Base class of a running-bearing effect (hooks: :meth:`additive`; :attr:`holds`, :attr:`rides_on`, :attr:`mimics_defects`)."""

    #: Nuisance parameters the effect takes over: held at their nominal value while it is in the model
    #: (a free nuisance parameter that the effect's own parameter only multiplies would make the two one).
    holds: tuple[str, ...] = ()
    #: Effects this one acts through, which must be in the model before it (a housing mode filters the dynamic
    #: rung's force on its grid: ``shaft_dynamics``); a rig file that configures it without them is refused.
    rides_on: tuple[str, ...] = ()
    #: Whether its signature can be taken for a defect's (a housing's ring after each roller passage is a short dip
    #: a narrow groove mimics): a rung that adds it holds the quasi-static search's first defect to the selection
    #: rule too (:func:`~..rung.dynamic_rung`).
    mimics_defects: bool = False

    def additive(self, values: dict, record) -> np.ndarray | None:
        """A voltage added to the record, independent of the bearing [V]."""
        return None


def scan(ctx: StartContext, trials: list[dict], keep: int = 2) -> list[dict]:
    """The ``keep`` trial values whose model change best explains the residual (linear amplitude fit).

    Each trial dict is added to the current values and simulated; the change
    dV against the current model is fitted to the residual with one amplitude
    a (and a constant); trials are ranked by the residual energy they remove,
    and only those with a > 0 (the trial's sign) are kept.
    """
    rig = ctx.record.rig
    r = ctx.residual_V - ctx.residual_V.mean()
    base = ctx.model_V
    scored = []
    for trial in trials:
        dv = chain.voltage(rig, {**ctx.values, **trial}) - base
        dv = dv - dv.mean()
        e = float(dv @ dv)
        if e <= 0:
            continue
        a = float(r @ dv) / e
        if a > 0:
            scored.append((a * a * e, a, trial))
    scored.sort(key=lambda x: -x[0])
    return [{**t, "_amplitude": a} for _, a, t in scored[:keep]]


def fold_peak(x: np.ndarray, coord: np.ndarray, period: float, n_bins: int) -> float:
    """Where within ``period`` of ``coord`` the residual energy x^2 is largest, folded over the record.

    Short events that repeat at one value of a kinematic coordinate (a
    roller over a groove: the cage phase modulo a pitch) pile up in one bin;
    the bin's centre is returned (a start for the event's phase) [unit of coord].
    """
    b = np.floor(np.mod(coord, period) / period * n_bins).astype(int) % n_bins
    e = np.bincount(b, weights=np.asarray(x) ** 2, minlength=n_bins) / np.maximum(np.bincount(b, minlength=n_bins), 1)
    # smooth over three bins (an event spans a few) before the peak
    e = (np.roll(e, 1) + e + np.roll(e, -1)) / 3
    return (int(np.argmax(e)) + 0.5) * period / n_bins


def cage_phase_of(ctx: StartContext) -> np.ndarray:
    """The current fit's cage phase at every sample [rad]."""
    return fitted_kinematics(ctx.values, ctx.record)["phase_rad"]
