r"""A housing accelerometer (ICP/IEPE): its transfer function, noise floor and range.

The accelerometer on the housing turns the surface's absolute acceleration a(t) along its axis into a
voltage [V]:

.. math::
    H(f) = S \, \frac{f_n^2}{f_n^2 - f^2 + 2 j \zeta f_n f} \, \frac{j f / f_{hp}}{1 + j f / f_{hp}}

with S the sensitivity [V/(m/s^2)] (the datasheet's mV/g over g_n = 9.80665 m/s^2), f_n the mounted
resonance and zeta its damping (the seismic mass on its crystal stack), f_hp the first-order high-pass of the
built-in amplifier's discharge time constant (f_hp = 1 / (2 pi tau)). The transducer's own noise is added
with the datasheet's spectral noise density [ug/sqrt(Hz)] (interpolated log-log between its frequencies,
constant beyond them), and the output saturates at the measurement range (+-range_g times S).

The defaults in ``config/config.yaml`` (section ``accelerometer``) are PCB Piezotronics model 352C33
(general-purpose ceramic shear ICP accelerometer, 5.8 g): 100 mV/g, +-50 g pk, resonance >= 50 kHz,
discharge time constant >= 1 s, spectral noise 12.5 / 4.0 / 1.4 ug/sqrt(Hz) at 10 / 100 / 1000 Hz
(broadband resolution 150 ug rms over 1 Hz-10 kHz). The resonance's damping is not on datasheets;
0.02 (Q = 25) is typical of a ceramic accelerometer's undamped resonance (assumed).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Standard gravity [m/s^2] (the datasheets' g).
G_N = 9.80665


@dataclass(frozen=True)
class AccelerometerSettings:
    """The transducer (config section ``accelerometer``).

    Parameters
    ----------
    model : str
        Name of the modelled accelerometer (for the record) [-].
    sensitivity_mV_per_g : float
        Voltage sensitivity [mV/g].
    resonance_Hz : float
        Mounted resonance f_n [Hz].
    resonance_damping_ratio : float
        Damping ratio zeta of the mounted resonance [-].
    highpass_Hz : float
        Corner of the amplifier's first-order high-pass [Hz].
    noise_frequencies_Hz : tuple of float
        Frequencies of the datasheet's spectral noise, increasing [Hz].
    noise_density_ug_per_sqrtHz : tuple of float
        Spectral noise density at those frequencies [ug/sqrt(Hz)].
    range_g : float
        Measurement range +-range_g (peak) [g].
    """

    model: str = "PCB 352C33"
    sensitivity_mV_per_g: float = 100.0
    resonance_Hz: float = 50000.0
    resonance_damping_ratio: float = 0.02
    highpass_Hz: float = 0.16
    noise_frequencies_Hz: tuple[float, ...] = (10.0, 100.0, 1000.0)
    noise_density_ug_per_sqrtHz: tuple[float, ...] = (12.5, 4.0, 1.4)
    range_g: float = 50.0

    def __post_init__(self):
        if len(self.noise_frequencies_Hz) != len(self.noise_density_ug_per_sqrtHz) or not self.noise_frequencies_Hz:
            raise ValueError(
                "config accelerometer: noise_frequencies_Hz and noise_density_ug_per_sqrtHz need the same length"
            )
        if np.any(np.diff(self.noise_frequencies_Hz) <= 0):
            raise ValueError("config accelerometer.noise_frequencies_Hz must be increasing")

    @classmethod
    def from_config(cls, section: dict) -> AccelerometerSettings:
        """From the config section ``accelerometer``."""
        keys = ("model sensitivity_mV_per_g resonance_Hz resonance_damping_ratio highpass_Hz range_g").split()
        return cls(
            **{k: section[k] for k in keys},
            noise_frequencies_Hz=tuple(section["noise_frequencies_Hz"]),
            noise_density_ug_per_sqrtHz=tuple(section["noise_density_ug_per_sqrtHz"]),
        )

    @property
    def sensitivity_V_per_m_per_s2(self) -> float:
        """S [V/(m/s^2)]."""
        return self.sensitivity_mV_per_g * 1e-3 / G_N

    @property
    def range_V(self) -> float:
        """The output's saturation, range_g g S [V]."""
        return self.range_g * G_N * self.sensitivity_V_per_m_per_s2

    def transfer(self, frequency_Hz: np.ndarray) -> np.ndarray:
        """H(f) [V/(m/s^2)], complex."""
        f = np.asarray(frequency_Hz, dtype=float)
        fn, z = self.resonance_Hz, self.resonance_damping_ratio
        mech = fn * fn / (fn * fn - f * f + 2j * z * fn * f)
        hp = (1j * f / self.highpass_Hz) / (1.0 + 1j * f / self.highpass_Hz)
        return self.sensitivity_V_per_m_per_s2 * mech * hp

    def noise_density_m_per_s2_per_sqrtHz(self, frequency_Hz: np.ndarray) -> np.ndarray:
        """The transducer's noise density, log-log between the datasheet's points, flat beyond [m/s^2/sqrt(Hz)]."""
        f = np.maximum(np.asarray(frequency_Hz, dtype=float), self.noise_frequencies_Hz[0])
        logd = np.interp(np.log(f), np.log(self.noise_frequencies_Hz), np.log(self.noise_density_ug_per_sqrtHz))
        return np.exp(logd) * 1e-6 * G_N


def transduce(acceleration_m_per_s2: np.ndarray, dt_s: float, settings: AccelerometerSettings) -> np.ndarray:
    """The accelerometer's noiseless output voltage [V]: H(f) applied on the record's Fourier series.

    The record is taken as periodic (as the DAQ's anti-alias filter does, :func:`piezobearing.signals.daq.sample`):
    the high-pass's start-up transient is not modelled (its time constant, 1 s, is that of a sensor that has
    been running for a long time).
    """
    a = np.asarray(acceleration_m_per_s2, dtype=float)
    freq = np.fft.rfftfreq(a.size, dt_s)
    return np.fft.irfft(np.fft.rfft(a) * settings.transfer(freq), a.size)


def transducer_noise_V(n: int, dt_s: float, settings: AccelerometerSettings, rng: np.random.Generator) -> np.ndarray:
    """The transducer's own noise on n samples of step dt [V]: Gaussian with the datasheet's density times |S|.

    Drawn in the frequency domain (complex Gaussian bins): one-sided density e(f) gives the mean square
    sum_k e(f_k)^2 df over the bins up to the Nyquist frequency.
    """
    freq = np.fft.rfftfreq(n, dt_s)
    df = 1.0 / (n * dt_s)
    e = settings.noise_density_m_per_s2_per_sqrtHz(freq) * settings.sensitivity_V_per_m_per_s2
    c = (rng.standard_normal(freq.size) + 1j * rng.standard_normal(freq.size)) / np.sqrt(2.0)
    spec = 0.5 * n * np.sqrt(2.0 * df) * e * c
    spec[0] = 0.0
    if n % 2 == 0:
        spec[-1] = spec[-1].real
    return np.fft.irfft(spec, n)


def saturate(v: np.ndarray, settings: AccelerometerSettings) -> tuple[np.ndarray, int]:
    """The output clipped at +-range_V; returns the voltage [V] and the number of clipped samples [-]."""
    lim = settings.range_V
    v = np.asarray(v, dtype=float)
    return np.clip(v, -lim, lim), int(np.count_nonzero(np.abs(v) > lim))
