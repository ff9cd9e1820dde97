"""The envelope detector's null distribution with each line's density interpolated on the grid: the method the
closed-form, cached density of :func:`piezobearing.signals.detectors.envelope._line_ratio_density` replaced,
kept as the baseline of ``benchmarks/bench_envelope_null.py``.

Each line's ratio density E_Y[Y f_Z(r Y)] read f_Z at r Y by linear interpolation on the grid (zero beyond its
end), for every line of every family anew.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import fftconvolve

from piezobearing.signals.detectors.envelope import NullDistribution, _gamma_nodes


def null_on_grid(window_bins: tuple[int, ...], floor_shape: float, span: float, n_grid: int) -> NullDistribution:
    """The null distribution on the grid of ``n_grid`` points over [0, ``span``], densities interpolated."""
    x = np.linspace(0.0, span, n_grid)
    h = x[1]
    y, w = _gamma_nodes(round(floor_shape, 3))
    total = None
    for m in window_bins:
        z = m * np.exp(-x) * (-np.expm1(-x)) ** (m - 1)  # density of the largest of m Exp(1)
        g = np.sum(w[:, None] * y[:, None] * np.interp(x[None, :] * y[:, None], x, z, right=0.0), axis=0)
        total = g if total is None else fftconvolve(total, g)[: x.size] * h
    total = np.clip(total, 0.0, None)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (total[1:] + total[:-1]) * h)])
    return NullDistribution(x, np.clip(1.0 - cdf / max(cdf[-1], 1.0), 0.0, 1.0), tuple(window_bins), float(floor_shape))
