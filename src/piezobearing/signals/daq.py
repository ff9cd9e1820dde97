"""The data acquisition: anti-alias filter, sampling at the DAQ rate, noise in volts, ADC.

A model voltage v(t) on a fine step (the model's time step) becomes what a
DAQ records:

1. **Anti-alias filter and sampling** (:func:`sample`). A sigma-delta DAQ
   filters digitally before it decimates: flat to 0.45 f_s and (by the
   resampler's own cut at f_s/2) nothing above f_s/2, so nothing aliases.
   Modelled as a zero-phase response, flat to ``passband_fraction`` x f_s,
   a raised-cosine roll-off to 0 at f_s/2, applied in the frequency domain on
   the record (periodic extension, like the envelope's band-pass), then the
   record's Fourier series evaluated on the DAQ clock. A model already on
   the DAQ clock (to 100 ppm) is passed through (its own step averaging is
   its filter).
2. **Noise** (:func:`add_noise`). ``relative``: the paper's white noise at
   an SNR over the record's own power (cancels every sensor gain).
   ``absolute``: input noise of density e_n [V/sqrt(Hz)] (std
   e_n sqrt(f_s/2) over the Nyquist band), mains pick-up at the mains
   frequency and its harmonics, and lines of the motor drive at its electric
   frequency and harmonics, each with a phase drawn from the seed.
3. **ADC** (:func:`quantise`). ``adc_bits`` over [-range_V, range_V]:
   step q = 2 range / 2^bits, mid-tread rounding, samples beyond the range
   clipped to the end codes. The number and fraction of clipped samples are
   returned: a clipped record is reported, never silently passed on.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from .detection import noise_std_for_snr

NOISE_MODELS = ("relative", "absolute")
#: A model step within this relative distance of the DAQ's is taken as the DAQ clock (100 ppm, the order of
#: a crystal's tolerance): the paper's 0.392156 ms is 2550.0026 Hz against its 2550 Hz.
SAME_CLOCK_RTOL = 1e-4


@dataclass(frozen=True)
class NoiseSettings:
    """Noise and ADC of the DAQ.

    Parameters
    ----------
    model : str
        ``relative`` (white noise at ``snr_dB`` over the record's mean square) or ``absolute``.
    snr_dB : float
        SNR of the relative model [dB].
    noise_density_V_per_sqrtHz : float
        Input-referred white noise density of the absolute model [V/sqrt(Hz)].
    adc_bits : int
        ADC resolution of the absolute model [-].
    range_V : float
        Input range +-range_V of the absolute model [V].
    mains_frequency_Hz : float
        Mains frequency [Hz].
    mains_amplitudes_V : tuple of float
        Amplitudes of the mains harmonics 1, 2, ... [V].
    drive_frequency_Hz : float
        Electric frequency of the motor drive [Hz].
    drive_amplitudes_V : tuple of float
        Amplitudes of the drive harmonics 1, 2, ... [V].
    """

    model: str = "relative"
    snr_dB: float = 10.0
    noise_density_V_per_sqrtHz: float = 1.0e-6
    adc_bits: int = 24
    range_V: float = 60.0
    mains_frequency_Hz: float = 50.0
    mains_amplitudes_V: tuple[float, ...] = ()
    drive_frequency_Hz: float = 33.3
    drive_amplitudes_V: tuple[float, ...] = ()

    def __post_init__(self):
        if self.model not in NOISE_MODELS:
            raise ValueError(f"signals.noise.model: unknown model '{self.model}'; use relative or absolute")

    @classmethod
    def from_config(cls, sig: dict) -> "NoiseSettings":
        n = sig["noise"]
        return cls(
            model=n["model"],
            snr_dB=sig["snr_dB"],
            noise_density_V_per_sqrtHz=n["noise_density_V_per_sqrtHz"],
            adc_bits=n["adc_bits"],
            range_V=n["range_V"],
            mains_frequency_Hz=n["mains_frequency_Hz"],
            mains_amplitudes_V=tuple(n["mains_amplitudes_V"]),
            drive_frequency_Hz=n["drive_frequency_Hz"],
            drive_amplitudes_V=tuple(n["drive_amplitudes_V"]),
        )


# --------------------------------------------------------------------------- sampling


def anti_alias_gain(frequency_Hz: np.ndarray, sample_rate_Hz: float, passband_fraction: float = 0.45) -> np.ndarray:
    """Zero-phase gain of the DAQ's anti-alias filter: 1 to f_p = passband_fraction f_s, raised cosine to 0 at f_s/2."""
    f = np.abs(np.asarray(frequency_Hz, dtype=float))
    fp, fn = passband_fraction * sample_rate_Hz, 0.5 * sample_rate_Hz
    g = np.where(f <= fp, 1.0, 0.0)
    tr = (f > fp) & (f < fn)
    g[tr] = 0.5 * (1.0 + np.cos(np.pi * (f[tr] - fp) / (fn - fp)))
    return g


@dataclass(frozen=True)
class Sampled:
    """A record on the DAQ clock.

    Attributes
    ----------
    voltage_V : ndarray
        Samples [V].
    dt_s : float
        Sampling step 1/f_s [s].
    n_dropped : int
        Model samples left off the end so that the record holds a whole number of DAQ steps [-].
    anti_alias : str
        What filtered before sampling.
    """

    voltage_V: np.ndarray
    dt_s: float
    n_dropped: int
    anti_alias: str


def sample(x: np.ndarray, dt_s: float, sample_rate_Hz: float, passband_fraction: float = 0.45) -> Sampled:
    """Filter and sample a model voltage on the DAQ clock t_i = i / f_s.

    Parameters
    ----------
    x : ndarray
        Model voltage on a uniform step [V].
    dt_s : float
        Its step [s]; 1/dt_s must be at least f_s.
    sample_rate_Hz : float
        DAQ sampling rate [Hz].
    passband_fraction : float
        Anti-alias passband edge over f_s [-].
    """
    x = np.asarray(x, dtype=float)
    fs_in = 1.0 / dt_s
    if abs(fs_in - sample_rate_Hz) <= SAME_CLOCK_RTOL * sample_rate_Hz:
        return Sampled(x.copy(), float(dt_s), 0, "none: the model is on the DAQ clock (its step averaging filters)")
    if fs_in < sample_rate_Hz:
        raise ValueError(
            f"model step {dt_s:.6g} s ({fs_in:.6g} Hz) is coarser than the DAQ rate signals.sample_rate_Hz = "
            f"{sample_rate_Hz:.6g} Hz; set bearing.time_step_s <= 1/sample_rate_Hz"
        )
    ratio = Fraction(sample_rate_Hz / fs_in).limit_denominator(100000)  # output samples per input sample
    q = ratio.denominator
    n_in = (x.size // q) * q
    if n_in < q:
        raise ValueError(f"record of {x.size} samples too short for the DAQ rate {sample_rate_Hz:.6g} Hz")
    n_out = n_in * ratio.numerator // q
    X = np.fft.rfft(x[:n_in]) * anti_alias_gain(np.fft.rfftfreq(n_in, dt_s), sample_rate_Hz, passband_fraction)
    m = n_out // 2 + 1
    Y = np.zeros(m, dtype=complex)
    k = min(m, X.size)
    Y[:k] = X[:k]
    if n_out % 2 == 0:
        Y[-1] = Y[-1].real  # the output's Nyquist bin (zero gain there anyway)
    y = np.fft.irfft(Y, n_out) * (n_out / n_in)
    return Sampled(y, float(n_in * dt_s / n_out), int(x.size - n_in),
                   f"flat to {passband_fraction:g} f_s, raised cosine to 0 at f_s/2, zero phase")


# --------------------------------------------------------------------------- noise and ADC


def absolute_noise_std_V(settings: NoiseSettings, sample_rate_Hz: float) -> float:
    """Standard deviation of the input noise over the Nyquist band, e_n sqrt(f_s/2) [V]."""
    return float(settings.noise_density_V_per_sqrtHz * np.sqrt(0.5 * sample_rate_Hz))


def tone_sum(t_s: np.ndarray, lines, rng: np.random.Generator) -> np.ndarray:
    """Harmonic series of lines: sum over ``lines`` of sum_h a_h sin(2 pi h f0 t + phi_h), with ``lines`` pairs
    (f0 [Hz], amplitudes a_1, a_2, ... of its harmonics), the phases uniform from ``rng`` drawn in that order."""
    t = np.asarray(t_s, dtype=float)
    out = np.zeros_like(t)
    for f0, amps in lines:
        for h, a in enumerate(amps, start=1):
            out += a * np.sin(2 * np.pi * h * f0 * t + rng.uniform(0.0, 2 * np.pi))
    return out


def interference_V(t_s: np.ndarray, settings: NoiseSettings, rng: np.random.Generator) -> np.ndarray:
    """Mains and drive lines: sum_h a_h sin(2 pi h f t + phi_h), phases uniform from ``rng`` [V]."""
    return tone_sum(t_s, ((settings.mains_frequency_Hz, settings.mains_amplitudes_V),
                          (settings.drive_frequency_Hz, settings.drive_amplitudes_V)), rng)


def quantise(x: np.ndarray, bits: int, range_V: float) -> tuple[np.ndarray, int]:
    """ADC of ``bits`` over [-range_V, range_V]: mid-tread codes, clipping at the end codes.

    Returns
    -------
    y : ndarray
        Quantised samples [V].
    n_clipped : int
        Samples beyond the range [-].
    """
    q = 2.0 * range_V / 2.0**bits
    lo, hi = -(2 ** (bits - 1)), 2 ** (bits - 1) - 1
    codes = np.round(np.asarray(x, dtype=float) / q)
    n_clipped = int(np.count_nonzero((codes < lo) | (codes > hi)))
    return np.clip(codes, lo, hi) * q, n_clipped


def end_codes_V(settings: NoiseSettings) -> tuple[float, float, float] | None:
    """The ADC's end codes where a clipped sample sits, and half its step: (lo [V], hi [V], q/2 [V]) of
    :func:`quantise` for the absolute model; None for the relative model (no ADC: nothing clips)."""
    if settings.model != "absolute":
        return None
    q = 2.0 * settings.range_V / 2.0**settings.adc_bits
    return -(2 ** (settings.adc_bits - 1)) * q, (2 ** (settings.adc_bits - 1) - 1) * q, 0.5 * q


@dataclass(frozen=True)
class Acquired:
    """A DAQ record and what the DAQ did to it.

    Attributes
    ----------
    voltage_V : ndarray
        The recorded samples [V].
    noise_std_V : float
        Standard deviation of the white input noise [V].
    n_clipped : int
        Samples clipped by the ADC [-].
    clipped_fraction : float
        n_clipped over the record length [-].
    quantisation_step_V : float
        ADC step (0 for the relative model, which has no ADC) [V].
    """

    voltage_V: np.ndarray
    noise_std_V: float
    n_clipped: int
    clipped_fraction: float
    quantisation_step_V: float

    def report(self) -> dict:
        return {"noise_std_V": self.noise_std_V, "n_clipped": self.n_clipped,
                "clipped_fraction": self.clipped_fraction, "clipped": self.n_clipped > 0,
                "quantisation_step_V": self.quantisation_step_V}


def add_noise(x: np.ndarray, dt_s: float, settings: NoiseSettings, rng: np.random.Generator,
              shape: np.ndarray | None = None) -> Acquired:
    """Noise (and for the absolute model, interference and the ADC) on a sampled record.

    ``shape`` may pass a standard normal draw of the record's length to reuse
    one noise shape over several levels (common random numbers).
    """
    x = np.asarray(x, dtype=float)
    z = rng.standard_normal(x.size) if shape is None else np.asarray(shape, dtype=float)
    if settings.model == "relative":
        sigma = noise_std_for_snr(x, settings.snr_dB)
        return Acquired(x + sigma * z, sigma, 0, 0.0, 0.0)
    sigma = absolute_noise_std_V(settings, 1.0 / dt_s)
    analog = x + sigma * z + interference_V(np.arange(x.size) * dt_s, settings, rng)
    y, n_clip = quantise(analog, settings.adc_bits, settings.range_V)
    return Acquired(y, sigma, n_clip, n_clip / x.size, 2.0 * settings.range_V / 2.0**settings.adc_bits)
