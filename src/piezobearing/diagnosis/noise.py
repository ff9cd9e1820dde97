"""The noise floor: what a correct model leaves, measured from the record itself.

A record has the output channel (the sensor voltage, noise level s_v) and,
when the subject has one, a measured input channel (a reference force, level
s_f). A correct model driven by the measured input leaves r = n_v - G n_f:
white noise through the model's response G from input to output, with the
spectrum S(f) = s_v^2 + s_f^2 |G(f)|^2, the floor of that model
(:meth:`NoiseFloor.spectrum`). Both levels are measured where the input
rests (:func:`quiet_mask`), as a line-free trimmed mean of the periodogram
between 5% and 45% of the sampling rate (:func:`white_level`), so that drift,
decaying tails and mains lines do not inflate them.

A channel recorded by a coarse ADC sits on one code where it rests: its
quiet stretches then show less noise than the converter adds where the
signal moves (the quantisation error, uniform over one step q, variance
q^2/12). Each level is therefore at least its channel's q^2/12, with q
the step found in the channel's distinct levels (:func:`quantisation_step`).

Where the model's gain from input to output changes along the record (a
force-dependent sensitivity, a drifting gain), the carried input noise is
louder where the gain is higher: the model says so with its noise envelope
a(t), and the residual's std follows it (:meth:`NoiseFloor.scale`, h(t)).
The fit divides the residual by h before weighting it by S(f) and adds
sum ln h^2 to chi2 (the log-determinant of the noise covariance, so -2 ln L
stays comparable between models with and without an envelope).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .record import Record
from .settings import DiagnosticsSettings


@dataclass(frozen=True)
class NoiseFloor:
    """White-noise levels of the output and input channels.

    Attributes
    ----------
    voltage_noise_V : float
        Std of the output (voltage) channel's own noise [V].
    input_noise : float
        Std of the measured input channel's noise [unit of the input; 0 without an input].
    quiet_s : float
        Total length of the quiet stretches used [s].
    n_stretches : int
        Number of quiet stretches [-].
    method : str
        How the levels were measured.
    quiet_mask : ndarray of bool
        Samples the levels were measured on.
    input_noise_key : str
        Key of ``input_noise`` in :meth:`report`, with the input's unit (``force_noise_N``).
    voltage_step_V, input_step : float
        The converters' steps (LSB) found in the record's distinct levels
        (:func:`quantisation_step`; 0: no grid) [V], [unit of the input]. A level is
        never below its channel's quantisation noise LSB^2/12.
    """

    voltage_noise_V: float
    input_noise: float
    quiet_s: float
    n_stretches: int
    method: str
    quiet_mask: np.ndarray = field(repr=False, default=None)
    input_noise_key: str = "input_noise"
    voltage_step_V: float = 0.0
    input_step: float = 0.0

    def spectrum(self, response: np.ndarray) -> np.ndarray:
        """S(f) = s_v^2 + s_f^2 |G(f)|^2: variance per sample of the residual noise at each bin [V^2]."""
        s = self.voltage_noise_V**2 + self.input_noise**2 * np.abs(response) ** 2
        return np.maximum(s, 1e-30)  # noise-free (synthetic) records: finite weights

    def rms_V(self, response: np.ndarray, n: int) -> float:
        """rms of the residual noise of a model with response G on n samples [V] (Parseval)."""
        s = np.broadcast_to(self.spectrum(response), (n // 2 + 1,))
        w = np.full(s.size, 2.0)
        w[0] = 1.0
        if n % 2 == 0:
            w[-1] = 1.0
        return float(np.sqrt(np.sum(w * s) / n))

    def scale(self, response: np.ndarray, envelope: np.ndarray | None, n: int) -> np.ndarray | None:
        """h(t): the residual noise's std at each sample over its rms on the record [-] (None: stationary).

        A model whose gain from input to output changes along the record
        (the d33 nonlinearity: 1 + 2 beta F(t); a drifting sensitivity)
        carries the input noise with the envelope a(t) (rms 1 over the
        record; :meth:`Model.noise_envelope <piezobearing.diagnosis.model.Model>`), so the residual
        variance at t is s_v^2 + a(t)^2 s_c^2, s_c^2 the carried variance of the stationary floor
        (Parseval of s_f^2 |G|^2). h^2 is that over its mean s_v^2 + s_c^2, so mean(h^2) = 1.
        """
        if envelope is None:
            return None
        own = self.voltage_noise_V**2
        carried = max(self.rms_V(response, n) ** 2 - own, 0.0)
        a2 = np.square(np.asarray(envelope, dtype=float))
        a2 = a2 / max(float(np.mean(a2)), 1e-30)
        return np.sqrt((own + carried * a2) / max(own + carried, 1e-30))

    def report(self) -> dict:
        return {
            "voltage_noise_V": self.voltage_noise_V,
            self.input_noise_key: self.input_noise,
            "quiet_s": self.quiet_s,
            "n_stretches": self.n_stretches,
            "method": self.method,
            "voltage_step_V": self.voltage_step_V,
            self.input_noise_key.replace("_noise", "_step"): self.input_step,
        }


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of the runs of True in a boolean array."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True))


def dilate(mask: np.ndarray, before: int, after: int) -> np.ndarray:
    """The mask with each run of True widened by ``before`` and ``after`` samples."""
    out = mask.copy()
    for a, b in runs(mask):
        out[max(a - before, 0) : min(b + after, mask.size)] = True
    return out


def robust_diff_std(x: np.ndarray) -> float:
    """Std of white noise on a smooth signal from the MAD of its first differences."""
    d = np.diff(x)
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2))


#: How long before an excursion of the input a stretch stops counting as quiet [s] (the fit's low-passed
#: input spreads an excursion about this far back).
QUIET_BEFORE_S = 0.05


def quiet_mask(input_: np.ndarray, dt_s: float, settle_s: float, min_length_s: float = 0.2) -> np.ndarray:
    """Samples where the input rests: away from every excursion by ``settle_s`` after and 50 ms before.

    An excursion (a press of a calibration) is where the input, smoothed over
    20 ms, departs from its resting level (the 10th percentile) by more than
    1% of its range or 6 noise standard deviations of the smoothed input.
    Only stretches of at least ``min_length_s`` are kept.
    """
    f = np.asarray(input_, dtype=float)
    w = max(int(round(0.02 / dt_s)), 1)
    fs = np.convolve(f, np.ones(w) / w, mode="same")
    sigma = robust_diff_std(f) / np.sqrt(w)
    rest = np.percentile(fs, 10)
    active = np.abs(fs - rest) > max(0.01 * np.ptp(fs), 6 * sigma)
    active = dilate(active, int(round(QUIET_BEFORE_S / dt_s)), int(round(settle_s / dt_s)))
    quiet = ~active
    keep = np.zeros_like(quiet)
    for a, b in runs(quiet):
        if (b - a) * dt_s >= min_length_s:
            keep[a:b] = True
    return keep


def white_level(
    x: np.ndarray,
    mask: np.ndarray,
    dt_s: float,
    segment: int = 256,
    line_factor: float = 20.0,
    trim: float = 6.0,
) -> tuple[float, int]:
    """Variance of the white part of x in the masked stretches [unit^2], and the number of ordinates used.

    Each stretch is cut into segments (at most ``segment`` samples, at least
    64), detrended and Hann-windowed; only periodogram ordinates between 5%
    and 45% of the sampling rate are used, so slow trends and decaying
    tails do not count. For white noise each ordinate is sigma^2 times an
    exponential variable. A first level from the median (over ln 2) marks
    spectral lines (ordinates above ``line_factor`` times it, with 4 bins
    either side, e.g. mains); the level is then the mean of the remaining
    ordinates below ``trim`` times the first level, corrected for that
    truncation (E[X | X < c] = (1 - (1 + c) e^-c) / (1 - e^-c) for a unit
    exponential).
    """
    spectra = []
    for a, b in runs(mask):
        for s0 in range(a, b - 63, segment):
            seg = x[s0 : min(s0 + segment, b)]
            if seg.size < 64:
                continue
            t = np.arange(seg.size)
            seg = seg - np.polyval(np.polyfit(t, seg, 1), t)
            win = np.hanning(seg.size)
            p = np.abs(np.fft.rfft(seg * win)) ** 2 / np.sum(win**2)
            fr = np.fft.rfftfreq(seg.size)
            spectra.append(p[(fr >= 0.05) & (fr <= 0.45)])
    if not spectra:
        return float("nan"), 0
    level0 = float(np.median(np.concatenate(spectra)) / np.log(2))
    if level0 <= 0.0:  # mostly flat (a coarse ADC resting on one code): the plain mean, no line or trim rule
        allp = np.concatenate(spectra)
        return float(np.mean(allp)), int(allp.size)
    kept = []
    for p in spectra:
        line = dilate(p > line_factor * level0, 4, 4)
        kept.append(p[~line & (p < trim * level0)])
    k = np.concatenate(kept)
    c = trim
    return float(np.mean(k) * (1 - np.exp(-c)) / (1 - (1 + c) * np.exp(-c))), int(k.size)


def estimate_noise_floor(
    record: Record,
    voltage_V: np.ndarray,
    settings: DiagnosticsSettings,
    settle_s: float = 0.0,
) -> NoiseFloor:
    """Measure s_v and s_f where the record's input rests (settling ``quiet_settle_s`` + ``settle_s``).

    Falls back on the whole record when the quiet stretches hold fewer than
    1000 samples: s_f from the input's high band, s_v from the voltage's high
    band, which then includes the carried input noise (recorded in ``method``).
    Samples the record marks as filled (``Record.left_out``) are never used.
    The record must have an input; a subject without one measures its floor
    with :func:`white_level` on stretches of its own choosing.
    """
    dt = record.dt_s
    key = (
        f"{record.input_name}_noise_{record.input_unit}"
        if record.input_unit
        else f"{record.input_name}_noise"
    )
    qv, qf = quantisation_step(voltage_V), quantisation_step(record.input)
    mask = quiet_mask(record.input, dt, settings.quiet_settle_s + settle_s)
    if record.left_out is not None:  # filled samples hold no noise: measure on measured samples only
        mask &= ~record.left_out
    if mask.sum() >= 1000:
        vf, _ = white_level(record.input, mask, dt)
        vv, _ = white_level(voltage_V, mask, dt)
        return NoiseFloor(
            float(np.sqrt(max(vv, qv**2 / 12))),
            float(np.sqrt(max(vf, qf**2 / 12))),
            float(mask.sum() * dt),
            len(runs(mask)),
            "quiet stretches: line-free trimmed mean of the periodogram, 5-45% of fs"
            + _quantisation_note(vv, qv, vf, qf, record.input_unit),
            mask,
            key,
            qv,
            qf,
        )
    whole = np.ones(record.n, dtype=bool) if record.left_out is None else ~record.left_out
    vf, _ = white_level(record.input, whole, dt)
    vv, _ = white_level(voltage_V, whole, dt)
    return NoiseFloor(
        float(np.sqrt(max(vv, qv**2 / 12))),
        float(np.sqrt(max(vf, qf**2 / 12))),
        0.0,
        0,
        f"whole record (no quiet stretches): voltage level includes carried {record.input_name} noise"
        + _quantisation_note(vv, qv, vf, qf, record.input_unit),
        mask,
        key,
        qv,
        qf,
    )


def quantisation_step(x: np.ndarray | None, tolerance: float = 0.05) -> float:
    """The converter's step (LSB) of a recorded channel, from its distinct levels [unit]; 0.0 if none.

    A channel recorded by an ADC takes values on a grid of codes: every
    spacing between its distinct sorted values is a whole multiple of the
    step (the smallest spacing), within ``tolerance`` of a step (a CSV's
    rounding). A channel of floating-point values (a synthetic record, a
    DAQ's scaled and filtered output) has no such grid: 0.0. At least 3
    distinct levels are needed.
    """
    if x is None:
        return 0.0
    u = np.unique(np.asarray(x, dtype=float))
    if u.size < 3:
        return 0.0
    d = np.diff(u)
    q = float(d.min())
    if q <= 0 or q < 1e-9 * float(np.ptp(u)):  # below a CSV's 10 significant digits: not a converter's grid
        return 0.0
    k = d / q
    return q if float(np.max(np.abs(k - np.round(k)))) <= tolerance else 0.0


def _quantisation_note(vv: float, qv: float, vf: float, qf: float, input_unit: str) -> str:
    """The method's words on the quantisation floors that raised a measured level (empty if none did)."""
    notes = []
    if qv and qv**2 / 12 > vv:
        notes.append(f"voltage raised to its ADC floor LSB/sqrt(12), LSB {qv:.4g} V")
    if qf and qf**2 / 12 > vf:
        notes.append(f"input raised to its ADC floor LSB/sqrt(12), LSB {qf:.4g} {input_unit}")
    return "; " + "; ".join(notes) if notes else ""
