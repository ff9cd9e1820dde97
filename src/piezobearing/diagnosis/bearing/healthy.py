"""The dynamic healthy model: a healthy bearing with the shaft's dynamics, fitted from a grid of operating points.

Where the quasi-static best healthy model still leaves a fault family's lines with energy above the floor, the lines
rule judges them against a healthy bearing with the shaft's dynamics (:func:`dynamic_healthy`, called by
:func:`~.answer.best_healthy`): at a light load in a wide clearance the shaft rings on its few loaded rollers at every
passage, which the quasi-static chain does not hold, and its residual then holds the roller passage's own lines at
k x BPFO, which are a healthy bearing's. The joint dynamic search (:mod:`.joint`) fits its dynamic healthy model
(the quasi-static final model without its defects) the same way (:func:`fit_from_grid`).

The dynamic chain's misfit has local minima over (clearance, load): which rollers carry, and when, depends on the
clearance, the load and each roller's offset. A grid point's misfit with the offsets at zero and the load share at its
least-squares value ranks the points by the record's amplitude more than by its shape (the share makes up for the
load), so the grid's best points need not lie in the record's basin. The model is fitted from the quasi-static fit's
own values and the grid's :data:`HEALTHY_STARTS` best points, and from one more start: the :data:`HEALTHY_SCREEN`
points after those are each fitted for :data:`SCREEN_NFEV` steps (the screen: a few Gauss-Newton steps fit the
offsets and often show the basin), and the best end starts a full fit. A screen alone does not replace the grid's best
points: a start far from its basin (90 um against a record's 73) may end a few steps worse than a start in another
basin and end best after the full fit (feasibility draw 22 of validation/bearing_feasibility.py).
"""

from __future__ import annotations

import numpy as np

from ...fitting.least_squares import InfeasibleError
from ..effect import StartContext
from ..fit import fit_model
from .effects import CATALOGUE

#: The grid the dynamic healthy model starts from (:func:`grid_points`): radial clearances [m] and loads as ratios of
#: the rig file's [-]. Spans the range of a running rig's clearance (0-60 um, and a worn 90 um) and a load within
#: x/÷ 2 of the file's: where the shaft rests on one or two rollers (a light load in a wide clearance) the dynamic
#: chain's misfit has local minima a fit from the rig file's values does not leave.
HEALTHY_GRID = ((0.0, 15e-6, 30e-6, 45e-6, 60e-6, 90e-6), (0.5, 0.7, 1.0, 1.4, 2.0))
#: How many of the grid's best points the dynamic healthy model is fitted from besides the quasi-static fit's own
#: values: each fit runs the dynamic chain some 20 times per step (every free parameter's difference, the rollers'
#: offsets among them). With one, 2 of 7 healthy draws far off were left at 11-12 % NRMSE against a 1 % floor and
#: named faulty (validation/bearing_fault_lines.py).
HEALTHY_STARTS = 2
#: How many of the grid's points after its :data:`HEALTHY_STARTS` best are screened (:func:`screen`). Healthy draw 3
#: of validation/bearing_fault_lines.py (256 N in 48 um at 25.6 kHz): the point in the record's basin (45 um at half
#: the rig file's load) is the grid's sixth; after four steps its chi2 is 204 where the five before it stay above
#: 1.4e4, and the full fits from the two best points end in a local minimum at 11.6 % NRMSE (a floor of 4.86 %).
HEALTHY_SCREEN = 8
#: The residual evaluations of each screening fit (one Jacobian each besides): four steps, 3 s of CPU a point on a
#: 1 s record at 25.6 kHz.
SCREEN_NFEV = 4


def share_misfit(vc: np.ndarray, m: np.ndarray) -> tuple[float, float]:
    """The misfit of ``m`` to the centred record ``vc`` with its scale (the load share) at its least-squares value,
    and that share (clipped to the load share's bounds)."""
    mc = m - m.mean()
    share = float(np.clip(vc @ mc / max(mc @ mc, 1e-300), 0.05, 5.0))
    return float(np.sum((vc - share * mc) ** 2)), share


def grid_points(model, base: dict, rec, vc: np.ndarray) -> list[tuple[float, dict]]:
    """Every point of :data:`HEALTHY_GRID` (clearance, load ratio of the rig file's) with its misfit of ``model`` at
    ``base`` (load share at its least-squares value), best first; points without an equilibrium left out."""
    out = []
    for c in HEALTHY_GRID[0]:
        for r in HEALTHY_GRID[1]:
            pt = {"radial_clearance_m": c, "radial_load_N": r * rec.rig.radial_load_N, "load_share_ratio": 1.0}
            try:
                m = model.simulate({**base, **pt}, rec)
            except InfeasibleError:
                continue
            e, share = share_misfit(vc, m)
            out.append((e, {**pt, "load_share_ratio": share}))
    out.sort(key=lambda x: x[0])
    return out


def screened(grid: list[tuple[float, dict]]) -> list[dict]:
    """The points of ``grid`` (:func:`grid_points`, best first) the screen fits: the :data:`HEALTHY_SCREEN` after its
    :data:`HEALTHY_STARTS` best."""
    return [pt for _, pt in grid[HEALTHY_STARTS:HEALTHY_STARTS + HEALTHY_SCREEN]]


def screen(model, rec, v: np.ndarray, floor, base: dict, points: list[dict]) -> list[tuple[float, dict]]:
    """Each of ``points`` fitted for :data:`SCREEN_NFEV` steps from ``base``: (chi2, the fit's values), best first;
    points without a solution of the model left out."""
    out = []
    for pt in points:
        try:
            f = fit_model(model, rec, v, floor, start={**base, **pt}, max_nfev=SCREEN_NFEV)
        except InfeasibleError:
            continue
        f.model.release()
        out.append((f.chi2, f.values))
    out.sort(key=lambda x: x[0])
    return out


def healthy_start_values(model, qs, rec, v: np.ndarray) -> tuple[dict, dict]:
    """The start of a dynamic healthy ``model`` (:func:`dynamic_model`, :func:`~.joint.healthy_model`) from the
    quasi-static fit ``qs``: its values where the model has them, the shaft's mass and damping at the rig file's
    (``shaft_dynamics``' start, not the effect's neutral mass 0); returns (the start, the shaft's values)."""
    own = CATALOGUE["shaft_dynamics"].starts(StartContext(rec, v, qs.model_V, qs.values))[0]
    defaults = model.defaults(rec)
    return {**defaults, **{k: x for k, x in qs.values.items() if k in defaults}, **own}, own


def dynamic_model(qs, rec, v: np.ndarray) -> tuple:
    """The quasi-static healthy fit ``qs``'s model with the shaft's dynamics, the load, the clearance, the load share
    and the rollers' scatter (those it lacks added), and its start (:func:`healthy_start_values`)."""
    present = {e.name for e in qs.model.effects}
    model = qs.model
    for name in ("radial_load", "clearance", "load_share", "roller_scatter", "shaft_dynamics"):
        if name not in present:
            model = model.with_effect(CATALOGUE[name])
    return model, healthy_start_values(model, qs, rec, v)[0]


def fit_from_grid(model, rec, v: np.ndarray, floor, base: dict, grid: list[tuple[float, dict]], settings):
    """``model`` fitted from ``base`` (the quasi-static fit's values), from the ``grid``'s (:func:`grid_points`)
    :data:`HEALTHY_STARTS` best points and from the best end of the screen (:func:`screen`) of the
    :data:`HEALTHY_SCREEN` points after them; the best fit is kept."""
    ends = screen(model, rec, v, floor, base, screened(grid))
    starts = [{}, *(pt for _, pt in grid[:HEALTHY_STARTS]), *(vals for _, vals in ends[:1])]
    f = fit_model(model, rec, v, floor, start=base, starts=starts, max_nfev=settings.max_nfev, ftol=settings.ftol)
    f.model.release()
    return f


def dynamic_healthy(d, qs):
    """:func:`dynamic_model` of the quasi-static healthy fit ``qs``, fitted from the grid (:func:`fit_from_grid`;
    the speed, slip and offsets at ``qs``'s)."""
    rec, v = d.record, np.asarray(d.voltage_V, dtype=float)
    model, base = dynamic_model(qs, rec, v)
    return fit_from_grid(model, rec, v, d.floor, base, grid_points(model, base, rec, v - v.mean()), d.settings)
