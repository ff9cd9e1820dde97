"""What an effect is: a small, documented change to the forward model.

The forward model (:mod:`piezobearing.diagnosis.calibration.model`) maps the recorded reference
force to the DAQ voltage along one signal chain::

    recorded force --force()--> force on the disk --circuit()--> RC voltage
                   --voltage()--> DAQ voltage --+ additive()--> recorded voltage

An effect overrides the hooks of the links it changes and leaves the others
as the identity. Besides the simulation it states its parameters (with units
in their names, bounds and a typical scale), its frequency response on the
force-noise path (:meth:`Effect.response`, used for the noise floor and the
weighting of the fit; :meth:`Effect.noise_envelope` where that gain changes
along the record) and, optionally, data-driven start values.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
from scipy import fft as sfft

from ....fitting.params import Param
from ... import effect as engine
from ...effect import EffectError, StartContext
from ..record import ForceRecord

__all__ = ["Effect", "EffectError", "Param", "ForceRecord", "StartContext", "denoised_force", "fd_filter"]


def fd_filter(x: np.ndarray, response: Callable[[np.ndarray], np.ndarray], margin: int = 0) -> np.ndarray:
    """x filtered in the frequency domain by ``response(f)`` (f in cycles per sample, 0 to 0.5).

    Non-causal filters (a fractional delay, a zero-phase lead) need the
    signal beyond both ends: the record is padded with its last value held,
    a raised-cosine bridge to its first value, and its first value held, so
    that the circular filter reads the held first value before the record
    starts and the held last value after it ends. ``margin`` is the reach
    of the filter in samples.
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    pad = int(margin) + 64
    total = sfft.next_fast_len(n + 3 * pad, real=True)
    hold = (total - n - pad) // 2
    bridge = x[-1] + (x[0] - x[-1]) * 0.5 * (1 - np.cos(np.pi * np.arange(1, pad + 1) / (pad + 1)))
    y = np.concatenate([x, np.full(hold, x[-1]), bridge, np.full(total - n - pad - hold, x[0])])
    spec = sfft.rfft(y) * response(np.fft.rfftfreq(total))
    return sfft.irfft(spec, total)[:n]


def force_band_Hz(record: "ForceRecord", factor: float = 10.0) -> float:
    """Highest frequency at which the recorded force's spectrum exceeds ``factor`` times its noise level [Hz].

    Welch spectrum with segments of about one second; the noise level is
    the median above a quarter of the sampling rate. Clipped to
    [1 Hz, 0.2 fs]. Above this band the recorded force is noise, so a model
    that must invert a filter of the force channel (``reference_lag``) does so
    only within it.
    """
    if "band" not in record._cache:
        fs = record.sample_rate_Hz
        seg = int(min(record.n, 2 ** np.ceil(np.log2(fs))))
        # Imported here: scipy.signal costs about a second of import, which every calibration job that
        # synthesises records through the catalogue (not diagnosing them) would pay.
        from scipy.signal import welch

        f, p = welch(record.force_N - np.mean(record.force_N), fs, nperseg=seg)
        noise = np.median(p[f > 0.25 * fs])
        above = f[p > factor * noise]
        band = float(above.max()) if above.size else 0.05 * fs
        record._cache["band"] = float(np.clip(band, 1.0, 0.2 * fs))
    return record._cache["band"]


def prefilter_response(f_Hz: np.ndarray, record: "ForceRecord") -> np.ndarray:
    """W(f) = 1 / (1 + (f / f_c)^8), f_c = twice the force band: zero-phase, flat in the band [-]."""
    cut = 2 * force_band_Hz(record)
    return 1.0 / (1.0 + (np.asarray(f_Hz, dtype=float) / cut) ** 8)


def denoised_force(record: "ForceRecord") -> np.ndarray:
    """The recorded force filtered by :func:`prefilter_response` [N].

    Keeps the force's content (its band, see :func:`force_band_Hz`) and
    removes its white noise above twice the band. The diagnosis fits the
    model on this input so that the carried force noise, which a delay or a
    lead would otherwise rotate and amplify at every frequency, cannot be
    fitted; the reported residual uses the recorded force as it is.
    """
    if "denoised" not in record._cache:
        fs = record.sample_rate_Hz
        record._cache["denoised"] = fd_filter(
            record.force_N, lambda k: prefilter_response(k * fs, record), int(2 * fs / force_band_Hz(record))
        )
    return record._cache["denoised"]


class Effect(engine.Effect):
    """Base class of a calibration catalogue effect: the engine's Effect with the signal-chain hooks.

    Class attributes (besides the engine's ``name``, ``title``, ``physics``)
    ----------------
    order : int
        Position in the chain among effects using the same hook (lower first).
    additive_only : bool
        True when the effect only adds a voltage (its parameters do not touch the force path).
    """

    order: int = 0
    additive_only: bool = False

    # ----------------------------------------------------------------- signal chain
    def force(self, force_N: np.ndarray, values: dict, record: ForceRecord) -> np.ndarray:
        """Recorded force -> force acting on the disk (in the voltage channel's time) [N]."""
        return force_N

    def circuit(self, circuit: Any, values: dict) -> Any:
        """Change the :class:`~piezobearing.sensor.calibration.SensorCircuit`."""
        return circuit

    def voltage(self, voltage_V: np.ndarray, values: dict, record: ForceRecord) -> np.ndarray:
        """Voltage across the electrodes -> voltage the DAQ digitises [V]."""
        return voltage_V

    def additive(self, values: dict, record: ForceRecord) -> np.ndarray | None:
        """A voltage added to the recorded voltage, independent of the force [V]."""
        return None

    def linear_basis(self, values: dict, record: ForceRecord) -> list[tuple[tuple[str, ...], np.ndarray, tuple]]:
        """Blocks (names, basis (n, k), key) of parameters :meth:`additive` is linear in: the added voltage's
        derivative by each [V per unit], ``key`` naming the basis's content (hashable). None by default."""
        return []

    def response(self, values: dict, record: ForceRecord) -> np.ndarray | float:
        """Factor this effect puts on the force-to-voltage response at ``record.freq_Hz`` [-].

        The forward model multiplies the circuit's response by it to carry the
        force channel's white noise to the voltage (the noise floor). Additive
        effects leave it at 1. An effect whose gain changes along the record
        returns its rms over the record here and its shape in
        :meth:`noise_envelope`.
        """
        return 1.0

    def noise_envelope(self, values: dict, record: ForceRecord) -> np.ndarray | None:
        """The gain this effect puts on the force noise at each sample of the record, a(t) [-] (None: constant).

        Only its shape counts (the model multiplies the effects' envelopes and
        normalises to rms 1; the level is :meth:`response`'s). The engine then
        lets the residual's std follow it
        (:meth:`~piezobearing.diagnosis.noise.NoiseFloor.scale`), so a correct
        model with a force-dependent or drifting gain is not called
        ``unexplained`` for its louder noise at the peaks.
        """
        return None
