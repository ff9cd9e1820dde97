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

To detect a fault on a ramp, :func:`detect_tracked` resamples the record itself
(:func:`order_track`) and gives it to the envelope detector with its rate in
samples per revolution and the kinematics in orders (:func:`kinematics_in_orders`);
the shaft angle comes from a tachometer's pulses (:func:`shaft_angle`) or from a
speed channel (:func:`speed_angle`). The detector's bands (the kurtogram's and the
whole band) then lie in the angle domain, where a resonance fixed in Hz sweeps
over the orders as the speed changes; the fault's lines stay sharp.
``piezobearing detect`` does this where a record has a tachometer or a speed
channel (``--tachometer``, ``--speed-channel``, or a column ``speed_rpm``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator

from .detectors import envelope as envelope_detector
from .detectors.result import Detection
from .envelope import EnvelopeSpectrum, analytic_band_signal, envelope, prewhiten
from .fault_bands import ShaftRate


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


def speed_angle(speed_rpm: np.ndarray, dt_s: float, step_s: float = 0.01) -> CubicSpline:
    """Shaft angle theta(t) from a speed channel [rpm] sampled with the record: its integral (trapezoids),
    a cubic spline through it every ``step_s`` (a speed sensor's own bandwidth is far below the DAQ's rate)."""
    v = np.asarray(speed_rpm, dtype=float) * (2 * np.pi / 60.0)
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt_s)])
    stride = max(1, int(round(step_s / dt_s)))
    idx = np.arange(0, v.size, stride)
    if idx[-1] != v.size - 1:
        idx = np.append(idx, v.size - 1)
    return CubicSpline(idx * dt_s, theta[idx])


@dataclass(frozen=True)
class OrderTrack:
    """A record resampled at uniform shaft angles, with what its speed was.

    Attributes
    ----------
    record : AngleRecord
        The record on uniform angle steps (its rate: ``samples_per_rev`` samples per revolution).
    mean_shaft_Hz, min_shaft_Hz, max_shaft_Hz : float
        The shaft rate over the revolutions resampled [Hz].
    seconds : float
        The time those revolutions took [s].
    """

    record: AngleRecord
    mean_shaft_Hz: float
    min_shaft_Hz: float
    max_shaft_Hz: float
    seconds: float

    def to_dict(self) -> dict:
        return {"samples_per_rev": self.record.samples_per_rev, "n_revolutions": self.record.n_revolutions,
                "mean_speed_rpm": 60.0 * self.mean_shaft_Hz, "min_speed_rpm": 60.0 * self.min_shaft_Hz,
                "max_speed_rpm": 60.0 * self.max_shaft_Hz, "seconds": self.seconds}


def order_track(x: np.ndarray, dt_s: float, angle: CubicSpline | PchipInterpolator) -> OrderTrack:
    """``x`` resampled at uniform shaft angles (:func:`angular_resample`), as many samples per revolution as the
    record has per revolution at its slowest: no content of the record aliases, at any speed."""
    t0, t1 = float(angle.x[0]), min(float(angle.x[-1]), (np.asarray(x).size - 1) * dt_s)
    t = np.linspace(t0, t1, 4096)
    rate = angle.derivative()(t) / (2 * np.pi)
    if not np.all(rate > 0):
        raise ValueError("the shaft angle does not increase over the record: the speed is zero or negative somewhere")
    slowest, fastest = float(rate.min()), float(rate.max())
    samples_per_rev = int(np.ceil(1.0 / (dt_s * slowest)))
    rec = angular_resample(x, dt_s, angle, samples_per_rev)
    seconds = float(np.interp(rec.angle_rad[-1], angle(t), t) - np.interp(rec.angle_rad[0], angle(t), t))
    return OrderTrack(rec, rec.n_revolutions / seconds, slowest, fastest, seconds)


def detect_tracked(x: np.ndarray, dt_s: float, angle: CubicSpline | PchipInterpolator, kinematics: dict,
                   settings: envelope_detector.Settings) -> tuple[Detection, OrderTrack]:
    """The envelope detector on a record whose speed changes, in orders (the module docstring's steps).

    The bands are chosen in time, where a structural resonance stays put (pre-whitening and the fast
    kurtogram as :func:`..detectors.envelope.measure` does, bands at least as wide as the highest line at the
    fastest speed); each band's squared envelope, computed in time, is resampled at uniform shaft angles
    (:func:`order_track`'s samples per revolution) and its spectrum taken in orders, where the lines sit at
    the bearing's orders (:func:`kinematics_in_orders`: the tachometer gives the shaft's rate exactly, so the
    windows hold slip and ``frequency_tolerance`` only). The floor's half-width in orders is
    ``floor_halfwidth_Hz`` over the mean shaft rate; the supply's harmonics, not synchronous with the shaft,
    are not left out. The false-alarm calibration takes the time the revolutions took: the bins per line window
    and floor are those of a record of that length at the mean speed.

    Returns the detection, its frequencies in orders (``details["order_tracking"]``: the speed's range, the
    samples per revolution; ``frequency_unit`` ``order``), and the track."""
    x = np.asarray(x, dtype=float)
    track = order_track(x, dt_s, angle)
    spr = track.record.samples_per_rev
    f = track.mean_shaft_Hz
    in_orders = replace(settings, floor_halfwidth_Hz=settings.floor_halfwidth_Hz / f, mains_Hz=())
    shaft = ShaftRate(1.0, 1.0, False, (), 0.0)
    kin = kinematics_in_orders(kinematics)
    lines = {fam: envelope_detector.family_lines(kin, fam, in_orders, settings.frequency_tolerance)
             for fam in settings.families}
    top = max(ln.high_Hz for fam in lines.values() for ln in fam)
    w = prewhiten(x) if settings.prewhiten else x - x.mean()
    bands, kurtogram = envelope_detector.candidate_bands(w, dt_s, top * track.max_shaft_Hz, settings)
    measured = []
    for band in bands:
        z = analytic_band_signal(w, dt_s, band)
        e = angular_resample(z.real**2 + z.imag**2, dt_s, angle, spr).values
        n = e.size
        window = np.hanning(n + 1)[:n]
        amplitude = 2.0 * np.abs(np.fft.rfft(window * (e - e.mean()))) / window.sum()
        spectrum = EnvelopeSpectrum(np.fft.rfftfreq(n, 1.0 / spr), amplitude, band, n)
        measured.append(envelope_detector.band_ratios(spectrum, lines, [shaft], in_orders))
    reading = envelope_detector.Reading(shaft, None, tuple(measured), kurtogram, lines, top, track.seconds)
    d = envelope_detector.decide(reading, in_orders)
    details = {**d.details, "order_tracking": {**track.to_dict(), "frequency_unit": "order"}}
    return replace(d, details=details), track
