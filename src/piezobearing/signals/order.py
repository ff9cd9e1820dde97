"""Order tracking: envelope analysis in the shaft-angle domain when the speed varies.

At a constant speed a fault line sits at a fixed frequency; on a ramp it
sweeps (a 1000 -> 1200 rpm ramp moves BPFO from 70.8 to 85 Hz) and its
energy spreads over many bins of the envelope spectrum. The fault
frequencies are fixed multiples of the shaft rate (orders: BPFO/f_r = 4.25
for the N 305), so in the shaft-angle domain the lines stay sharp:

1. **Shaft angle** from the tachometer (:func:`pulse_times`,
   :func:`shaft_angle`): the tachometer gives ``pulses_per_rev`` pulses per
   revolution; at the k-th pulse (rising edge, interpolated between samples)
   the angle is 2 pi k / pulses_per_rev, and between pulses it follows a
   cubic spline through them.
2. **Envelope in time** (band-pass and Hilbert envelope as in
   :mod:`.detection`): the band's resonance is excited at the impacts and
   rings at its own frequency, which does not follow the shaft; only the
   envelope does.
3. **Angular resampling** (:func:`angular_resample`): the envelope at
   uniform angle steps 2 pi / samples_per_rev, by cubic interpolation at the
   times where the shaft reaches each angle (inverse of the angle curve).
4. **Order spectrum** of the resampled envelope (:func:`order_envelope_spectrum`):
   uniform in orders (cycles per revolution) with resolution 1/n_revolutions.

To detect a fault on a ramp, resample the record itself (:func:`angular_resample`)
and give it to the envelope detector
(``piezobearing.signals.detectors.detect(values, samples_per_rev, kinematics_in_orders(k), "envelope", settings)``)
with its rate in samples per revolution, the kinematics in orders
(:func:`kinematics_in_orders`) and a fixed band in orders that holds the
resonance over the whole speed range (its frequency over the slowest and the
fastest shaft rate): the band-pass then runs in the angle domain, where the
resonance sweeps; the fault's lines stay sharp.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator

from .envelope import EnvelopeSpectrum, envelope


def tachometer_signal(angle_rad: np.ndarray, pulses_per_rev: int, high_V: float = 5.0, duty: float = 0.5) -> np.ndarray:
    """A TTL tachometer: ``high_V`` while the shaft angle lies in the first ``duty`` of each pulse period [V]."""
    frac = np.mod(np.asarray(angle_rad, dtype=float) * pulses_per_rev / (2 * np.pi), 1.0)
    return np.where(frac < duty, high_V, 0.0)


def pulse_times(tacho_V: np.ndarray, dt_s: float, threshold_V: float | None = None) -> np.ndarray:
    """Times of the rising edges of a tachometer channel, linearly interpolated between samples [s].

    Parameters
    ----------
    tacho_V : ndarray
        Tachometer samples [V].
    dt_s : float
        Sampling step [s].
    threshold_V : float, optional
        Edge level [V]; default halfway between the channel's extremes.
    """
    v = np.asarray(tacho_V, dtype=float)
    thr = 0.5 * (v.min() + v.max()) if threshold_V is None else threshold_V
    i = np.flatnonzero((v[:-1] < thr) & (v[1:] >= thr))
    frac = (thr - v[i]) / (v[i + 1] - v[i])
    return (i + frac) * dt_s


def shaft_angle(pulse_times_s: np.ndarray, pulses_per_rev: int) -> CubicSpline | PchipInterpolator:
    """Shaft angle theta(t) through the pulses: 2 pi k / pulses_per_rev at the k-th pulse [rad].

    A cubic spline (exact for a linear speed ramp); where it would run
    backwards (abrupt speed changes) the monotone PCHIP instead. Valid
    between the first and the last pulse. The pulse times carry the
    tachometer's sampling: a square wave's edge is known to about half a
    sample, an angle error of up to pi f_r dt.
    """

    tp = np.asarray(pulse_times_s, dtype=float)
    if tp.size < 4:
        raise ValueError(f"only {tp.size} tachometer pulses; the record needs at least 4 to track the speed")
    if np.any(np.diff(tp) <= 0):
        raise ValueError("tachometer pulse times must increase")
    th = 2 * np.pi * np.arange(tp.size) / pulses_per_rev
    cs = CubicSpline(tp, th)
    if np.all(cs.derivative()(np.linspace(tp[0], tp[-1], 16 * tp.size)) > 0):
        return cs
    return PchipInterpolator(tp, th)


@dataclass(frozen=True)
class AngleRecord:
    """A signal on uniform shaft-angle steps.

    Attributes
    ----------
    values : ndarray
        The signal at each angle [V].
    angle_rad : ndarray
        Shaft angles, step 2 pi / samples_per_rev [rad].
    samples_per_rev : int
    """

    values: np.ndarray
    angle_rad: np.ndarray
    samples_per_rev: int

    @property
    def n_revolutions(self) -> float:
        return self.values.size / self.samples_per_rev


def angular_resample(x: np.ndarray, dt_s: float, angle: CubicSpline | PchipInterpolator, samples_per_rev: int,
                     t0_s: float = 0.0) -> AngleRecord:
    """Resample x(t) at uniform shaft angles over the whole revolutions the angle curve covers.

    The time of each angle comes from inverting theta(t) (monotone: a dense
    table of theta and linear interpolation of its inverse, then one Newton
    step on the PCHIP); x is interpolated there by a cubic spline.
    """

    x = np.asarray(x, dtype=float)
    t = t0_s + np.arange(x.size) * dt_s
    ta, tb = max(angle.x[0], t[0]), min(angle.x[-1], t[-1])
    th_a, th_b = float(angle(ta)), float(angle(tb))
    n_rev = int(np.floor((th_b - th_a) / (2 * np.pi) + 1e-9))
    if n_rev < 1:
        raise ValueError("the tachometer covers less than one revolution of the record")
    theta = th_a + 2 * np.pi * np.arange(n_rev * samples_per_rev) / samples_per_rev
    tt = np.linspace(ta, tb, 8 * x.size)
    t_of = np.interp(theta, angle(tt), tt)
    t_of = t_of - (angle(t_of) - theta) / angle.derivative()(t_of)  # one Newton step
    values = CubicSpline(t, x)(np.clip(t_of, t[0], t[-1]))
    return AngleRecord(values, theta, samples_per_rev)


def order_envelope_spectrum(x: np.ndarray, dt_s: float, band_Hz: tuple[float, float], angle: CubicSpline | PchipInterpolator,
                            samples_per_rev: int, order: int = 4, window: str = "hann",
                            t0_s: float = 0.0) -> EnvelopeSpectrum:
    """Envelope (band-pass, Hilbert, in time) resampled in angle, and its spectrum in orders.

    The returned spectrum's ``frequency_Hz`` holds orders [cycles/rev] with
    resolution 1 / n_revolutions; amplitudes as in
    :func:`.envelope.envelope_spectrum` with ``window`` [V].
    """
    e = envelope(x, dt_s, band_Hz, order)
    rec = angular_resample(e, dt_s, angle, samples_per_rev, t0_s)
    v = rec.values
    n = v.size
    w = np.hanning(n + 1)[:n] if window == "hann" else np.ones(n)
    amp = 2.0 * np.abs(np.fft.rfft(w * (v - v.mean()))) / w.sum()
    if n % 2 == 0:
        amp[-1] /= 2.0
    return EnvelopeSpectrum(np.fft.rfftfreq(n, 1.0 / samples_per_rev), amp, (float(band_Hz[0]),
                                float(band_Hz[1])), n)


def kinematics_in_orders(kinematics: dict) -> dict:
    """The kinematic frequencies over the shaft rate: orders [cycles/rev] (shaft_Hz becomes 1)."""
    fr = float(kinematics["shaft_Hz"])
    return {k: float(v) / fr for k, v in kinematics.items() if k.endswith("_Hz")}
