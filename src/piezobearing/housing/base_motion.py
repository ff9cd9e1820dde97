"""The surroundings: the machine frame's vibration entering the housing through its foot (base motion).

The frame under the housing's foot moves with an acceleration a_b(t) = (a_y, a_z) in the bearing's plane
(y horizontal, z up; the half model's mirror plane x = 0 carries no axial base motion). Per axis it is

* a broadband random part: a Gaussian process with the one-sided power spectral density S(f)
  [(m/s^2)^2/Hz], given at breakpoints and interpolated log-log between them (zero outside them), drawn as
  a random-phase Fourier series on the simulation's fine time grid (complex Gaussian coefficients: the
  realisation's expected mean square is the integral of S);
* tonal lines: the mains-driven vibration at the mains frequency and its harmonics (motors, transformers),
  and a neighbouring gear mesh at its mesh frequency and harmonics, each a sine of the given peak
  amplitude [m/s^2] with a phase drawn from the seed.

``level`` scales the whole disturbance (0: the frame at rest). Each axis draws its own random numbers, and
``axis_weights_yz`` scales each axis's amplitude. The same realisation drives the LPM (shaft and pedestal)
and the housing FEM, so both sensors see the same surroundings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..signals.daq import tone_sum

#: Stream index of the base-motion draws in ``numpy.random.default_rng([seed, STREAM, replicate])``.
STREAM = 29


@dataclass(frozen=True)
class BaseMotionSettings:
    """The base motion's spectrum and lines (config section ``base_motion``).

    Parameters
    ----------
    level : float
        Factor on every amplitude (PSD by its square) [-]; 0 is no base motion.
    psd_frequencies_Hz : tuple of float
        Breakpoints of the broadband PSD, increasing [Hz].
    psd_m2_per_s4_per_Hz : tuple of float
        One-sided PSD of the acceleration at the breakpoints [(m/s^2)^2/Hz].
    mains_frequency_Hz : float
        Mains frequency [Hz].
    mains_amplitudes_m_per_s2 : tuple of float
        Peak amplitudes of the mains harmonics 1, 2, ... [m/s^2].
    gear_mesh_frequency_Hz : float
        Mesh frequency of the neighbouring gear [Hz].
    gear_mesh_amplitudes_m_per_s2 : tuple of float
        Peak amplitudes of the gear mesh harmonics 1, 2, ... [m/s^2].
    axis_weights_yz : tuple of float
        Amplitude factors of the y and z axes [-].
    """

    level: float = 0.0
    psd_frequencies_Hz: tuple[float, ...] = (10.0, 10000.0)
    psd_m2_per_s4_per_Hz: tuple[float, ...] = (1.0e-4, 1.0e-4)
    mains_frequency_Hz: float = 50.0
    mains_amplitudes_m_per_s2: tuple[float, ...] = ()
    gear_mesh_frequency_Hz: float = 400.0
    gear_mesh_amplitudes_m_per_s2: tuple[float, ...] = ()
    axis_weights_yz: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self):
        f, s = np.asarray(self.psd_frequencies_Hz), np.asarray(self.psd_m2_per_s4_per_Hz)
        if f.size != s.size or f.size < 2:
            raise ValueError(
                "config base_motion: psd_frequencies_Hz and psd_m2_per_s4_per_Hz need the same length, at least 2"
            )
        if np.any(np.diff(f) <= 0) or f[0] <= 0:
            raise ValueError("config base_motion.psd_frequencies_Hz must be positive and increasing")
        if np.any(s <= 0):
            raise ValueError("config base_motion.psd_m2_per_s4_per_Hz must be positive (log-log interpolation)")

    @classmethod
    def from_config(cls, section: dict) -> BaseMotionSettings:
        """From the config section ``base_motion``."""
        return cls(
            level=section["level"],
            psd_frequencies_Hz=tuple(section["psd_frequencies_Hz"]),
            psd_m2_per_s4_per_Hz=tuple(section["psd_m2_per_s4_per_Hz"]),
            mains_frequency_Hz=section["mains_frequency_Hz"],
            mains_amplitudes_m_per_s2=tuple(section["mains_amplitudes_m_per_s2"]),
            gear_mesh_frequency_Hz=section["gear_mesh_frequency_Hz"],
            gear_mesh_amplitudes_m_per_s2=tuple(section["gear_mesh_amplitudes_m_per_s2"]),
            axis_weights_yz=tuple(section["axis_weights_yz"]),
        )

    @property
    def active(self) -> bool:
        """True when the frame moves (level > 0 and some spectrum or line)."""
        return self.level > 0.0

    def psd(self, frequency_Hz: np.ndarray) -> np.ndarray:
        """The broadband one-sided PSD at ``frequency_Hz`` at level 1 [(m/s^2)^2/Hz]; 0 outside the breakpoints."""
        f = np.asarray(frequency_Hz, dtype=float)
        fk = np.asarray(self.psd_frequencies_Hz)
        sk = np.asarray(self.psd_m2_per_s4_per_Hz)
        inside = (f >= fk[0]) & (f <= fk[-1])
        out = np.zeros_like(f)
        out[inside] = np.exp(np.interp(np.log(f[inside]), np.log(fk), np.log(sk)))
        return out

    def expected_rms_m_per_s2(self) -> float:
        """Expected RMS of one axis of weight 1 at ``level``: sqrt(integral of S + sum of a^2 / 2) [m/s^2]."""
        f = np.geomspace(self.psd_frequencies_Hz[0], self.psd_frequencies_Hz[-1], 4001)
        s = self.psd(f)
        broadband = float(np.sum(0.5 * (s[1:] + s[:-1]) * np.diff(f)))
        tones = sum(a * a / 2 for a in self.mains_amplitudes_m_per_s2 + self.gear_mesh_amplitudes_m_per_s2)
        return float(self.level * np.sqrt(broadband + tones))


def broadband(n: int, dt_s: float, settings: BaseMotionSettings, rng: np.random.Generator) -> np.ndarray:
    """One axis's random part on n samples of step dt at level 1 [m/s^2]: a random-phase Fourier series.

    x_i = sum_k sqrt(2 S(f_k) df) Re(c_k exp(2 pi j k i / n)), c_k complex Gaussian with E|c_k|^2 = 1 and
    df = 1 / (n dt): the expected mean square is sum_k S(f_k) df.
    """
    freq = np.fft.rfftfreq(n, dt_s)
    df = 1.0 / (n * dt_s)
    c = (rng.standard_normal(freq.size) + 1j * rng.standard_normal(freq.size)) / np.sqrt(2.0)
    spec = 0.5 * n * np.sqrt(2.0 * settings.psd(freq) * df) * c
    spec[0] = 0.0
    if n % 2 == 0:
        spec[-1] = 0.0
    return np.fft.irfft(spec, n)


def tones(t_s: np.ndarray, settings: BaseMotionSettings, rng: np.random.Generator) -> np.ndarray:
    """One axis's tonal lines at level 1: sum_h a_h sin(2 pi h f t + phi_h), phases uniform from ``rng`` [m/s^2]."""
    return tone_sum(t_s, ((settings.mains_frequency_Hz, settings.mains_amplitudes_m_per_s2),
                          (settings.gear_mesh_frequency_Hz, settings.gear_mesh_amplitudes_m_per_s2)), rng)


def realisation(settings: BaseMotionSettings, seed: int, replicate: int = 0):
    """The base acceleration as a function of a uniform time grid: ``f(t) -> (n, 2)`` [m/s^2] (y, z).

    The draws come from ``default_rng([seed, STREAM, replicate, axis])``: a replicate is one realisation of
    the surroundings; the function gives the same numbers for the same grid. Pass it to
    :func:`piezobearing.housing.transient.run_lpm` (``base_motion``).
    """

    def acceleration(t_s: np.ndarray) -> np.ndarray:
        t = np.asarray(t_s, dtype=float)
        out = np.zeros((t.size, 2))
        if not settings.active:
            return out
        dt = float(t[1] - t[0])
        for axis in range(2):
            rng = np.random.default_rng([seed, STREAM, replicate, axis])
            x = broadband(t.size, dt, settings, rng) + tones(t, settings, rng)
            out[:, axis] = settings.level * settings.axis_weights_yz[axis] * x
        return out

    return acceleration


def rms_m_per_s2(acceleration_m_per_s2: np.ndarray) -> float:
    """RMS of the base acceleration's magnitude, sqrt(mean(a_y^2 + a_z^2)) [m/s^2]."""
    a = np.asarray(acceleration_m_per_s2, dtype=float)
    return float(np.sqrt(np.mean(np.sum(a * a, axis=1))))
