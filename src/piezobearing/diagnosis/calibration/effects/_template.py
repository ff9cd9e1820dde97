"""``fixture_mode``: the TEMPLATE of a calibration effect (copy it to add one; CONTRIBUTING.md, "Adding an effect").

This module is a complete, working effect that is deliberately left out of
the catalogue (``_MODULES`` in ``effects/__init__.py`` does not list it), so
that it documents the contract by example; ``tests/test_effect_contract.py``
holds it to the same contract as every catalogue effect. To add your own:
copy this file to ``effects/<identifier>.py``, rewrite the docstring (the
mechanism, the model, plausible sizes), the class and ``EFFECT``, list the
module in ``_MODULES``, and run ``piezobearing hide-and-find <identifier>``.

Physics
-------
The reference force sensor sits on a fixture that has a mode of its own
(a mass on the sensor's and the fixture's stiffness): the force it records
is the force on the PZT filtered by the mode's transmissibility
H(f) = 1 / (1 - (f/f_n)^2 + 2 j zeta f/f_n). A hand-held rod on a soft pad
gives f_n of tens of Hz with a few percent damping; the presses (rising
over 0.4 s) excite it at their onset.

Model
-----
The circuit must be driven by the force on the PZT, i.e. the recorded force
through 1/H = 1 + j w 2 zeta tau - (w tau)^2 (tau = 1/(2 pi f_n)), a lead
that grows with frequency: it is applied within the force's band only
(the window W(f) of ``reference_lag``), zero-phase, in the frequency domain.
With tau = 0 the effect is neutral. The noise path carries the same factor
(``response``): the recorded force's noise reaches the voltage through it.

Parameters: ``fixture_tau_s`` = 1/(2 pi f_n) in [0, 0.05] s (f_n above
3.2 Hz), ``fixture_damping_ratio`` in [0.001, 1].
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord, StartContext, fd_filter, force_band_Hz
from .reference_lag import ORDER


def inverse_mode(f_Hz: np.ndarray, tau_s: float, zeta: float, band_Hz: float) -> np.ndarray:
    """Band-limited inverse transmissibility 1 + (j w 2 zeta tau - (w tau)^2) W(f) [-]."""
    w = 2 * np.pi * np.asarray(f_Hz, dtype=float)
    return 1.0 + (2j * zeta * w * tau_s - (w * tau_s) ** 2) / (1.0 + (np.asarray(f_Hz) / band_Hz) ** ORDER)


class FixtureMode(Effect):
    # the identifier (config lists, hide-and-find), a title for tables, the position among the effects
    # using the same hook (lower first: this one reads the recorded force, as reference_lag, order 10)
    name = "fixture_mode"
    title = "reference sensor on a resonant fixture"
    order = 15
    # a plausible size, chosen for the physics before any diagnosis, and why (the tests, the error-rate
    # study and hide-and-find hide it)
    example = {"fixture_tau_s": 1.0 / (2 * np.pi * 35.0), "fixture_damping_ratio": 0.03}
    example_reason = "a rod on a soft pad: a 35 Hz mode with 3% damping (tau = 4.5 ms)"
    # the paragraph the report shows
    physics = (
        "The reference force sensor sits on a fixture with a mode of its own: it records the force on the "
        "PZT through H = 1 / (1 - (f/f_n)^2 + 2 j zeta f/f_n). The model drives the circuit with the recorded "
        "force through 1/H within the force's band. A rod on a soft pad gives tens of Hz, a few % damping."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        # names end in a unit suffix of fitting/units.py; the declared value (first number) is neutral
        return [
            Param("fixture_tau_s", 0.0, 0.0, 0.05, scale=1e-3, description="1/(2 pi f_n) of the fixture mode [s]"),
            Param("fixture_damping_ratio", 0.05, 1e-3, 1.0, log=True, description="damping ratio of the mode [-]"),
        ]

    # signal path: the force hook receives the recorded force with PAD samples before the record
    # (f.size == record.n + PAD) and returns as many; a zero-phase filter needs no time alignment
    def force(self, force_N, values, record):
        tau, zeta = values["fixture_tau_s"], values["fixture_damping_ratio"]
        if tau == 0.0:
            return force_N
        fs, band = record.sample_rate_Hz, force_band_Hz(record)
        return fd_filter(force_N, lambda k: inverse_mode(k * fs, tau, zeta, band), int(4 * fs / band))

    # noise path: the factor on the force-to-voltage response at record.freq_Hz (0 .. Nyquist), the same
    # filter the force hook applies, so that the floor carries the recorded force's noise through it
    def response(self, values, record):
        return inverse_mode(
            record.freq_Hz, values["fixture_tau_s"], values["fixture_damping_ratio"], force_band_Hz(record)
        )

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        """Off, and the mode at the largest peak of the residual's spectrum between 5 Hz and the force's band
        (at most two or three starts: every start is a fit)."""
        r = ctx.residual_V - ctx.residual_V.mean()
        f = np.fft.rfftfreq(r.size, ctx.record.dt_s)
        p = np.abs(np.fft.rfft(r * np.hanning(r.size))) ** 2
        sel = (f >= 5.0) & (f <= max(force_band_Hz(ctx.record), 10.0))
        if not sel.any():
            return [{}]
        fp = float(f[sel][np.argmax(p[sel])])
        return [{}, {"fixture_tau_s": float(np.clip(1 / (2 * np.pi * fp), 0.0, 0.05)), "fixture_damping_ratio": 0.05}]

    def summary(self, values):
        tau = values["fixture_tau_s"]
        fn = 1 / (2 * np.pi * tau) if tau > 0 else float("inf")
        return f"f_n = {fn:.2f} Hz, damping {values['fixture_damping_ratio'] * 100:.2g}%"


EFFECT = FixtureMode()
