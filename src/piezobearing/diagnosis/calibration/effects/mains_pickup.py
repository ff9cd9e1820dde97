"""``mains_pickup``: interference at the mains frequency and its odd harmonics.

Physics
-------
The PZT source is a few hundred picofarads behind tens of megaohms: a high
impedance node on an unshielded stretch (electrodes, copper tape, leads) or
a ground loop between the two acquisition devices couples the 50 Hz (or
60 Hz) field into the voltage. Saturating transformers and rectifier loads
make the interference rich in odd harmonics (150 Hz, 250 Hz, ...).
Millivolts to tens of millivolts are common in a laboratory.

Model
-----
.. math::  V_{mains}(t) = \\sum_{k \\in \\{1,3,5\\}} a_k \\cos(2\\pi k f_m t) + b_k \\sin(2\\pi k f_m t),

with t from the start of the record. Harmonics at or above 0.49 of the
sampling rate (for the highest mains frequency the fit may reach) are left
out. The mains frequency f_m is fitted: a grid deviates by up to a few
tenths of a hertz, which over a 25 s record turns the phase by several
turns. Start values come from the largest residual peak near 50 or 60 Hz.
Additive: it does not change the response.

Parameters: ``mains_frequency_Hz`` in [49.5, 60.5] Hz; ``mains_h{k}_cos_V``,
``mains_h{k}_sin_V`` in [-1, 1] V.
"""

from __future__ import annotations

import numpy as np

from ....fitting.params import Param
from .base import Effect, ForceRecord, StartContext

HARMONICS = (1, 3, 5)
F_LO, F_HI = 49.5, 60.5
NOMINAL = (50.0, 60.0)
SEARCH_HALF_WIDTH_HZ = 0.5


def harmonics(record: ForceRecord) -> tuple[int, ...]:
    """The odd harmonics below 0.49 of the sampling rate at the highest mains frequency."""
    return tuple(k for k in HARMONICS if k * F_HI < 0.49 * record.sample_rate_Hz)


def basis(t_s: np.ndarray, f_Hz: float, ks: tuple[int, ...]) -> np.ndarray:
    """Columns cos, sin of each harmonic k of f_Hz at times t_s [-]."""
    cols = []
    for k in ks:
        ph = 2 * np.pi * k * f_Hz * t_s
        cols += [np.cos(ph), np.sin(ph)]
    return np.stack(cols, axis=1)


def record_basis(record: ForceRecord, f_Hz: float, ks: tuple[int, ...]) -> np.ndarray:
    """:func:`basis` on the record's clock from its start, kept for the last two frequencies (a fit asks at one
    frequency and its finite-difference step, every evaluation) [-]; read-only."""
    kept = record._cache.setdefault("mains_basis", {})
    b = kept.get((f_Hz, ks))
    if b is None:
        b = basis(record.time_s - record.time_s[0], f_Hz, ks)
        b.flags.writeable = False
        kept[(f_Hz, ks)] = b
        while len(kept) > 2:
            kept.pop(next(iter(kept)))
    return b


class MainsPickup(Effect):
    name = "mains_pickup"
    title = "mains interference (50/60 Hz + odd harmonics)"
    order = 300
    example = {
        "mains_frequency_Hz": 50.03,
        "mains_h1_cos_V": 0.012,
        "mains_h1_sin_V": -0.016,
        "mains_h3_cos_V": 0.003,
        "mains_h3_sin_V": 0.004,
    }
    example_reason = (
        "20 mV at 50 Hz plus 5 mV third harmonic: a high-impedance node (261 pF, 50 MOhm) near mains wiring"
    )
    additive_only = True
    physics = (
        "The PZT is a high-impedance source (hundreds of pF behind tens of MOhm): an unshielded lead or a "
        "ground loop between the two acquisition devices picks up the mains field at 50 or 60 Hz, with odd "
        "harmonics from non-linear loads. It adds to the voltage whatever the force does."
    )

    def params(self, record: ForceRecord) -> list[Param]:
        out = [Param("mains_frequency_Hz", 50.0, F_LO, F_HI, scale=1.0, description="mains frequency [Hz]")]
        for k in harmonics(record):
            for part in ("cos", "sin"):
                out.append(
                    Param(
                        f"mains_h{k}_{part}_V",
                        0.0,
                        -1.0,
                        1.0,
                        scale=1e-3,
                        description=f"{part} amplitude of harmonic {k} [V]",
                    )
                )
        return out

    def additive(self, values, record):
        ks = harmonics(record)
        coef = np.array([values[f"mains_h{k}_{p}_V"] for k in ks for p in ("cos", "sin")])
        return record_basis(record, float(values["mains_frequency_Hz"]), ks) @ coef

    def linear_basis(self, values, record):
        """The harmonics' cos and sin at the mains frequency (the voltage is linear in their amplitudes)."""
        ks = harmonics(record)
        f = float(values["mains_frequency_Hz"])
        names = tuple(f"mains_h{k}_{p}_V" for k in ks for p in ("cos", "sin"))
        return [(names, record_basis(record, f, ks), ("mains", f, ks))]

    def starts(self, ctx: StartContext) -> list[dict[str, float]]:
        """Largest residual peak within 0.5 Hz of 50 or 60 Hz, then linear least squares of the amplitudes."""
        rec = ctx.record
        ks = harmonics(rec)
        r = ctx.residual_V - ctx.residual_V.mean()
        t = rec.time_s - rec.time_s[0]
        nfft = 8 * int(2 ** np.ceil(np.log2(r.size)))
        spec = np.abs(np.fft.rfft(r * np.hanning(r.size), nfft)) ** 2
        f = np.fft.rfftfreq(nfft, rec.dt_s)
        best = None
        for f0 in NOMINAL:
            if f0 >= 0.49 * rec.sample_rate_Hz:
                continue
            sel = np.flatnonzero(np.abs(f - f0) <= SEARCH_HALF_WIDTH_HZ)
            i = sel[np.argmax(spec[sel])]
            if best is None or spec[i] > best[0]:
                best = (spec[i], float(f[i]))
        if best is None:
            return [{}]
        fm = best[1]
        coef, *_ = np.linalg.lstsq(basis(t, fm, ks), r, rcond=None)
        start = {"mains_frequency_Hz": fm}
        names = [f"mains_h{k}_{p}_V" for k in ks for p in ("cos", "sin")]
        start.update({n: float(np.clip(c, -1, 1)) for n, c in zip(names, coef, strict=True)})
        return [start]

    def summary(self, values):
        parts = [f"f = {values['mains_frequency_Hz']:.3f} Hz"]
        for k in HARMONICS:
            if f"mains_h{k}_cos_V" in values:
                a = np.hypot(values[f"mains_h{k}_cos_V"], values[f"mains_h{k}_sin_V"])
                parts.append(f"h{k} amplitude {a * 1e3:.2f} mV")
        return ", ".join(parts)


EFFECT = MainsPickup()
