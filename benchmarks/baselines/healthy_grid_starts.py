"""The dynamic healthy model fitted from the grid's two best points (and the quasi-static fit's own values) without a
screen: the method :func:`piezobearing.diagnosis.bearing.healthy.dynamic_healthy` replaced, kept as the baseline of
``benchmarks/bench_healthy_screen.py``. The grid's points are ranked by their misfit with the rollers' offsets at
zero and the load share at its least-squares value, and the full fits start from the two best."""

from __future__ import annotations

import numpy as np

from piezobearing.diagnosis.bearing.effects import CATALOGUE
from piezobearing.diagnosis.bearing.healthy import HEALTHY_STARTS, grid_points
from piezobearing.diagnosis.effect import StartContext
from piezobearing.diagnosis.fit import fit_model


def dynamic_healthy(d, qs):
    """The quasi-static healthy fit ``qs`` with the shaft's dynamics, the load, the clearance, the load share and the
    rollers' scatter (those it lacks added), fitted from ``qs``'s values and from the grid's two best points."""
    present = {e.name for e in qs.model.effects}
    model = qs.model
    for name in ("radial_load", "clearance", "load_share", "roller_scatter", "shaft_dynamics"):
        if name not in present:
            model = model.with_effect(CATALOGUE[name])
    rec, v = d.record, np.asarray(d.voltage_V, dtype=float)
    own = CATALOGUE["shaft_dynamics"].starts(StartContext(rec, v, qs.model_V, qs.values))[0]
    base = {**model.defaults(rec), **qs.values, **own}
    grid = grid_points(model, base, rec, v - v.mean())
    f = fit_model(model, rec, v, d.floor, start=base, starts=[{}, *(pt for _, pt in grid[:HEALTHY_STARTS])],
                  max_nfev=d.settings.max_nfev, ftol=d.settings.ftol)
    f.model.release()
    return f
