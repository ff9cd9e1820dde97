"""The dynamic healthy model fitted from the quasi-static fit's own values and the grid's two best points, without the
screen's start: the method before :func:`piezobearing.diagnosis.bearing.healthy.dynamic_healthy` added it, kept as the
baseline of ``benchmarks/bench_healthy_screen.py``. The grid's points are ranked by their misfit with the rollers'
offsets at zero and the load share at its least-squares value."""

from __future__ import annotations

import numpy as np

from piezobearing.diagnosis.bearing.healthy import HEALTHY_STARTS, dynamic_model, grid_points
from piezobearing.diagnosis.fit import fit_model


def dynamic_healthy(d, qs):
    """:func:`~piezobearing.diagnosis.bearing.healthy.dynamic_model` of the quasi-static healthy fit ``qs``, fitted
    from ``qs``'s values and from the grid's two best points."""
    rec, v = d.record, np.asarray(d.voltage_V, dtype=float)
    model, base = dynamic_model(qs, rec, v)
    grid = grid_points(model, base, rec, v - v.mean())
    f = fit_model(model, rec, v, d.floor, start=base, starts=[{}, *(pt for _, pt in grid[:HEALTHY_STARTS])],
                  max_nfev=d.settings.max_nfev, ftol=d.settings.ftol)
    f.model.release()
    return f
