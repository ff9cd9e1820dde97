r"""One housing mode between the rollers and the sensor: the sensor force through a single-degree-of-freedom response.

.. math::
    \ddot x + 2 \zeta \omega \dot x + \omega^2 x = \omega^2 F(t), \qquad \omega = 2 \pi f_n

static gain 1, peak gain 1 / (2 zeta) at the mode. A one-mode idealisation of the housing (the whole sensor force
through the mode; the housing's FEM, :mod:`piezobearing.housing.fem`, gives each mode its own share): the LPM's
records with a housing mode inside the DAQ's band (:mod:`piezobearing.diagnosis.bearing.lpm_records`) and the running
bearing's ``housing_mode`` rung (:mod:`piezobearing.diagnosis.bearing.effects.housing_mode`) both pass their summed
sensor force through it.
"""

from __future__ import annotations

import numpy as np


def through_mode(force_N: np.ndarray, step_s: float, mode_Hz: float, damping_ratio: float) -> np.ndarray:
    """``force_N`` on a uniform grid of ``step_s`` through one housing mode, from static equilibrium at the first
    point [N].

    Discretised with the force linear between the grid's points (first-order hold: the mode's poles exact); at
    10.9 us the complex gain is within 0.2 % of the continuous one up to twice a 1.1 kHz mode, within 1.2 % for a
    2.7 kHz mode (``tests/test_diagnosis_bearing_housing_mode.py``).
    """
    # scipy.signal (about 0.3 s of import) only for a model or a record that holds a housing mode
    from scipy.signal import cont2discrete, lfilter, lfilter_zi

    w = 2.0 * np.pi * mode_Hz
    num, den, _ = cont2discrete(([w * w], [1.0, 2.0 * damping_ratio * w, w * w]), step_s, method="foh")
    b, a = np.ravel(num), np.ravel(den)
    y, _ = lfilter(b, a, force_N, zi=lfilter_zi(b, a) * force_N[0])
    return y
