"""Envelope analysis of a vibration or sensor record: band-pass, envelope, (squared) envelope spectrum,
cepstrum pre-whitening, and the band choice by spectral kurtosis (kurtogram, fast kurtogram).

The field's chain for a rolling-bearing record ``x`` (uniform step ``dt`` [s]; Randall & Antoni, "Rolling
element bearing diagnostics - a tutorial", MSSP 25 (2011) 485-520):

1. **Pre-whitening** (:func:`prewhiten`): the record's spectrum set to unit magnitude, its phase kept: the
   real cepstrum zeroed at every quefrency but zero (Borghesani, Pennacchi, Randall, Sawalhi, Ricci,
   "Application of cepstrum pre-whitening for the diagnosis of bearing faults under variable speed
   conditions", MSSP 36 (2013) 370-384). Discrete lines (shaft harmonics, gear meshes, the roller passage)
   and resonances are flattened; impulses stay impulses.
2. **Band** (:func:`fast_kurtogram`): spectral kurtosis SK = <|z|^4> / <|z|^2>^2 - 2 of the complex band
   signal z over Antoni's 1/3-binary tree of bands (J. Antoni, "Fast computation of the kurtogram for the
   detection of transient faults", MSSP 21 (2007) 108-124). SK is 0 for Gaussian noise, -1 for a
   sinusoid, large for an impulse train: the band where the defect's impulses stand out most.
3. **Envelope** (:func:`analytic_band_signal`): z, the analytic signal of x band-passed by the zero-phase
   gain |H|^2 of a Butterworth band-pass (as ``sosfiltfilt``), applied in the frequency domain to the
   record's periodic extension (no edge transient).
4. **Spectrum** (:func:`envelope_spectrum`): the single-sided amplitude spectrum of the envelope |z| or of
   the squared envelope |z|^2 (the squared envelope spectrum, SES: the envelope's spectrum without the
   square root's distortion of the modulation), rectangular (exact fault periods) or Hann window (lines
   between bins, as with slip).

The paper's kurtogram (:func:`kurtogram`) filters the whole record's spectrum for each band of a
half-overlapping filter bank; :func:`fast_kurtogram` takes each band of the tree from the record's one FFT
and transforms back at the band's own rate, so a level costs about one FFT of the record.

The transforms are scipy.fft's: numpy.fft runs the same pocketfft algorithm (with the pinned numpy and scipy
the values agree to the last bit, odd, even and prime lengths alike) but plans every call afresh, and a
record's length is seldom a fast one (a 10 s CWRU record has 121,168 = 16 x 7573 samples, a prime factor that
takes Bluestein's algorithm, whose set-up then costs as much as the transform); scipy.fft keeps the plans of
the lengths it has seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft

#: Envelope-spectrum windows and the variance inflation of a mean of their bins' powers,
#: 1 + 2 sum_k |rho_k|^2 (Hann: adjacent bins rho = -2/3, next 1/6).
WINDOWS = {"rectangular": 1.0, "hann": 1.0 + 2.0 * (4.0 / 9.0 + 1.0 / 36.0)}


# --------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class EnvelopeSettings:
    """How the band of the envelope is chosen.

    Parameters
    ----------
    band_rule : str
        ``"kurtogram"`` (largest spectral kurtosis of the filter bank) or
        ``"fixed"`` (``band_Hz``).
    band_Hz : tuple of float
        The band [low, high] for ``band_rule = "fixed"`` [Hz].
    min_bandwidth_Hz : float
        Narrowest band of the kurtogram's filter bank [Hz].
    filter_order : int
        Order of the Butterworth band-pass (applied forward and backward) [-].
    """

    band_rule: str = "kurtogram"
    band_Hz: tuple[float, float] = (500.0, 1200.0)
    min_bandwidth_Hz: float = 300.0
    filter_order: int = 4

    @classmethod
    def from_config(cls, sig: dict) -> "EnvelopeSettings":
        return cls(
            band_rule=sig["band_rule"],
            band_Hz=tuple(sig["band_Hz"]),
            min_bandwidth_Hz=sig["kurtogram_min_bandwidth_Hz"],
            filter_order=sig["filter_order"],
        )


# --------------------------------------------------------------------------- pre-whitening


def prewhiten(x: np.ndarray) -> np.ndarray:
    """Cepstrum pre-whitening: the record with its spectrum's magnitude set to one, its phase kept [-].

    x_w = IDFT(X / |X|), X = DFT(x - mean x) (bins of zero magnitude stay zero). Equivalent to zeroing the
    real cepstrum at every quefrency but zero (Borghesani et al. 2013). The result is dimensionless; its
    mean square is (N - 1)/N for a record with no zero bin.
    """
    x = np.asarray(x, dtype=float)
    spectrum = scipy.fft.rfft(x - x.mean())
    magnitude = np.abs(spectrum)
    unit = np.divide(spectrum, magnitude, out=np.zeros_like(spectrum), where=magnitude > 0)
    return scipy.fft.irfft(unit, x.size)


# --------------------------------------------------------------------------- band-pass and envelope


def band_gain(frequency_Hz: np.ndarray, sample_rate_Hz: float, band_Hz: tuple[float, float], order: int) -> np.ndarray:
    """Zero-phase gain |H(f)|^2 of a digital Butterworth band-pass (a high-pass if the band reaches Nyquist) [-].

    The filter is scipy's ``butter(order, band, btype, fs, output="sos")``: the analog Butterworth prototype,
    transformed to a band-pass (high-pass) and mapped by the bilinear transform with pre-warped edges. Its
    squared magnitude has a closed form in the warped frequency W = tan(pi f / fs), with W1, W2 the warped
    edges: 1 / (1 + ((W^2 - W1 W2) / ((W2 - W1) W))^(2 order)) for the band-pass, 1 / (1 + (W1 / W)^(2 order))
    for the high-pass (0 at f = 0). It is evaluated so, not through the filter's sections
    (``sosfreqz``): the values are the same to about 1e-14 of the peak gain (tests/test_signals.py
    compares both), and the detection needs no ``scipy.signal``, whose import costs about a second.
    """
    nyq = sample_rate_Hz / 2
    lo, hi = float(band_Hz[0]), float(band_Hz[1])
    if not 0 < lo < hi <= nyq * (1 + 1e-9):
        raise ValueError(f"band {band_Hz} Hz must satisfy 0 < low < high <= Nyquist = {nyq:.6g} Hz")
    w = np.tan(np.pi * np.asarray(frequency_Hz, dtype=float) / sample_rate_Hz)
    w1 = np.tan(np.pi * lo / sample_rate_Hz)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        if hi >= nyq * (1 - 1e-6):
            ratio = w1 / w
        else:
            w2 = np.tan(np.pi * hi / sample_rate_Hz)
            ratio = (w * w - w1 * w2) / ((w2 - w1) * w)
        gain = 1.0 / (1.0 + ratio ** (2 * order))
    return np.where(w == 0.0, 0.0, gain)


def analytic_band_signal(
    x: np.ndarray, dt_s: float, band_Hz: tuple[float, float], order: int = 4, spectrum: np.ndarray | None = None
) -> np.ndarray:
    """Analytic signal z of x band-passed by :func:`band_gain` (periodic extension of the record).

    ``spectrum`` may pass ``scipy.fft.rfft(x)`` to save the transform when many
    bands are tried on one record.
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    X = scipy.fft.rfft(x) if spectrum is None else spectrum
    f = np.fft.rfftfreq(n, dt_s)
    Y = X * band_gain(f, 1.0 / dt_s, band_Hz, order)
    Z = np.zeros(n, dtype=complex)
    Z[: Y.size] = Y
    Z[1 : (n + 1) // 2] *= 2.0  # positive frequencies doubled; DC and (even n) Nyquist kept once
    return scipy.fft.ifft(Z)


def envelope(x: np.ndarray, dt_s: float, band_Hz: tuple[float, float], order: int = 4) -> np.ndarray:
    """Hilbert envelope |z| of x in the band [V]."""
    return np.abs(analytic_band_signal(x, dt_s, band_Hz, order))


def band_power_V2(x: np.ndarray, dt_s: float, band_Hz: tuple[float, float], order: int = 4) -> float:
    """Mean square of x band-passed as before the envelope, mean(|z|^2)/2 [V^2]."""
    return float(np.mean(np.abs(analytic_band_signal(x, dt_s, band_Hz, order)) ** 2) / 2.0)


# --------------------------------------------------------------------------- envelope spectra


@dataclass(frozen=True)
class EnvelopeSpectrum:
    """Single-sided amplitude spectrum of the envelope (or of the squared envelope).

    Attributes
    ----------
    frequency_Hz : ndarray
        Frequencies, spacing 1 / (N dt) [Hz].
    amplitude_V : ndarray
        Amplitude of the envelope's (mean-removed) sinusoidal components [V] ([V^2] for the squared
        envelope; [-] after pre-whitening).
    band_Hz : tuple of float
        The band-pass before the envelope [Hz].
    n_samples : int
        Samples of the analysed record [-].
    """

    frequency_Hz: np.ndarray
    amplitude_V: np.ndarray
    band_Hz: tuple[float, float]
    n_samples: int

    @property
    def resolution_Hz(self) -> float:
        return float(self.frequency_Hz[1] - self.frequency_Hz[0])


def envelope_spectrum(
    x: np.ndarray,
    dt_s: float,
    band_Hz: tuple[float, float],
    order: int = 4,
    window: str = "rectangular",
    squared: bool = False,
    spectrum: np.ndarray | None = None,
) -> EnvelopeSpectrum:
    """Band-pass, Hilbert envelope e = |z| (``squared``: e = |z|^2), amplitude spectrum
    2 |DFT(w (e - mean e))| / sum(w) of the whole record given.

    Parameters
    ----------
    x : ndarray
        The record [V].
    dt_s : float
        Its sampling step [s].
    band_Hz : tuple of float
        The band-pass before the envelope [Hz].
    order : int
        Order of the Butterworth band-pass [-].
    window : str
        ``"rectangular"`` (a record of whole fault periods: every harmonic on a bin) or ``"hann"`` (lines
        between bins, as with slip: its sidelobes fall as 1/k^3, so a strong line does not leak into the
        search windows of another family, where the rectangular window's 1/k does).
    squared : bool
        The squared envelope spectrum (SES) instead of the envelope's.
    spectrum : ndarray, optional
        ``scipy.fft.rfft(x)``, to save the transform when several bands are read on one record.
    """
    if window not in WINDOWS:
        raise ValueError(f"envelope spectrum window '{window}' unknown; use one of {', '.join(WINDOWS)}")
    z = analytic_band_signal(x, dt_s, band_Hz, order, spectrum)
    e = (z.real**2 + z.imag**2) if squared else np.abs(z)
    n = e.size
    if window == "rectangular":
        amp = 2.0 * np.abs(scipy.fft.rfft(e - e.mean())) / n
    else:
        w = np.hanning(n + 1)[:n]  # periodic Hann
        amp = 2.0 * np.abs(scipy.fft.rfft(w * (e - e.mean()))) / w.sum()
    if n % 2 == 0:
        amp[-1] /= 2.0  # the Nyquist bin is not mirrored
    return EnvelopeSpectrum(np.fft.rfftfreq(n, dt_s), amp, (float(band_Hz[0]), float(band_Hz[1])), n)


def amplitude_spectrum(x: np.ndarray, dt_s: float) -> EnvelopeSpectrum:
    """Amplitude spectrum 2|DFT(x - mean x)|/N of the record itself, no band-pass, no envelope [V].

    The naive check: the same harmonic test on it fires for the healthy
    bearing too, whose roller passages put a strong line at BPFO.
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    amp = 2.0 * np.abs(scipy.fft.rfft(x - x.mean())) / n
    return EnvelopeSpectrum(np.fft.rfftfreq(n, dt_s), amp, (0.0, 0.5 / dt_s), n)


# --------------------------------------------------------------------------- kurtogram (the paper's)


def spectral_kurtosis(z: np.ndarray) -> float:
    """SK = <|z|^4> / <|z|^2>^2 - 2 of a complex band signal [-] (0 for Gaussian noise)."""
    p = np.abs(z) ** 2
    return float(np.mean(p * p) / np.mean(p) ** 2 - 2.0)


def kurtogram_bands(sample_rate_Hz: float, min_bandwidth_Hz: float) -> list[tuple[float, float]]:
    """The filter bank of :func:`kurtogram`: bandwidths Nyquist/{1.5, 2, 3, 4, 6, 8, ...}, half overlapping.

    Bands that would start at 0 Hz are left out (their envelope would carry
    the low-frequency content itself, not a modulation).
    """
    nyq = sample_rate_Hz / 2
    bands = []
    level = 0
    while True:
        div = (1.5 if level % 2 == 0 else 2.0) * 2 ** (level // 2)  # 1.5, 2, 3, 4, 6, 8, ...
        bw = nyq / div
        if bw < min_bandwidth_Hz * (1 - 1e-9):
            break
        j = 1
        while j * bw / 2 + bw <= nyq * (1 + 1e-9):
            bands.append((j * bw / 2, min(j * bw / 2 + bw, nyq)))
            j += 1
        level += 1
    if not bands:
        raise ValueError(
            f"kurtogram: no band of width >= {min_bandwidth_Hz} Hz fits below Nyquist {nyq:.6g} Hz; "
            "lower signals.kurtogram_min_bandwidth_Hz"
        )
    return bands


@dataclass(frozen=True)
class Kurtogram:
    """Spectral kurtosis of each band of a filter bank.

    Attributes
    ----------
    low_Hz, high_Hz : ndarray
        Band edges [Hz].
    kurtosis : ndarray
        Spectral kurtosis of the band signal [-].
    level : ndarray or None
        The band's level in Antoni's 1/3-binary tree, log2(Nyquist / bandwidth) (0, 1, 1.585, 2, ...) [-]
        (None for the paper's half-overlapping bank).
    """

    low_Hz: np.ndarray
    high_Hz: np.ndarray
    kurtosis: np.ndarray
    level: np.ndarray | None = None

    @property
    def best_band_Hz(self) -> tuple[float, float]:
        i = int(np.argmax(self.kurtosis))
        return float(self.low_Hz[i]), float(self.high_Hz[i])


def kurtogram(x: np.ndarray, dt_s: float, min_bandwidth_Hz: float, order: int = 4) -> Kurtogram:
    """Spectral kurtosis over the filter bank of :func:`kurtogram_bands` (each band filtered at full length)."""
    X = scipy.fft.rfft(np.asarray(x, dtype=float))
    bands = kurtogram_bands(1.0 / dt_s, min_bandwidth_Hz)
    sk = [spectral_kurtosis(analytic_band_signal(x, dt_s, b, order, spectrum=X)) for b in bands]
    lo, hi = np.array(bands).T
    return Kurtogram(lo, hi, np.array(sk))


def choose_band(x: np.ndarray, dt_s: float, settings: EnvelopeSettings) -> tuple[tuple[float, float], Kurtogram | None]:
    """The band of the envelope by the configured rule, and the kurtogram if it was used."""
    if settings.band_rule == "fixed":
        return (float(settings.band_Hz[0]), float(settings.band_Hz[1])), None
    if settings.band_rule == "kurtogram":
        kg = kurtogram(x, dt_s, settings.min_bandwidth_Hz, settings.filter_order)
        return kg.best_band_Hz, kg
    raise ValueError(f"signals.band_rule: unknown rule '{settings.band_rule}'; use 'kurtogram' or 'fixed'")


# --------------------------------------------------------------------------- fast kurtogram


def tree_bands(sample_rate_Hz: float, max_level: float) -> list[tuple[float, float, float]]:
    """Antoni's 1/3-binary tree: (level, low, high) of every band down to ``max_level`` [-], [Hz], [Hz].

    Level k (integer) splits [0, Nyquist] into 2^k bands of width Nyquist / 2^k; level k + log2(3) - 1
    (1.585, 2.585, ...) into 3 x 2^(k-1) bands of width Nyquist / (3 x 2^(k-1)). Level 0 is the whole band.
    """
    nyq = sample_rate_Hz / 2
    out = []
    levels = [0.0]
    k = 1
    while k <= max_level + 1e-9:
        levels.append(float(k))
        third = k + np.log2(3.0) - 1.0
        if third <= max_level + 1e-9:
            levels.append(float(third))
        k += 1
    for level in sorted(levels):
        n_bands = int(round(2.0**level))
        width = nyq / n_bands
        out.extend((level, i * width, (i + 1) * width) for i in range(n_bands))
    return out


def fast_kurtogram(x: np.ndarray, dt_s: float, min_bandwidth_Hz: float, min_low_Hz: float = 0.0) -> Kurtogram:
    """Spectral kurtosis of every band of Antoni's 1/3-binary tree, each band at its own (decimated) rate.

    Every band's complex signal is the record's positive-frequency DFT bins inside the band, shifted to
    baseband and transformed back with as many points as the band has bins: the band signal decimated to
    its bandwidth (an ideal band-pass in the frequency domain in place of Antoni's quasi-analytic FIR
    cascade). A level of the tree costs about one FFT of the record, so the whole kurtogram costs a few.

    Parameters
    ----------
    x : ndarray
        The record (pre-whitened or not).
    dt_s : float
        Its sampling step [s].
    min_bandwidth_Hz : float
        Narrowest band of the tree (the deepest level with bands at least this wide) [Hz].
    min_low_Hz : float
        Bands whose lower edge lies below this are left out (their envelope would carry the low-frequency
        content itself, not a modulation) [Hz].
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    fs = 1.0 / dt_s
    nyq = fs / 2
    if min_bandwidth_Hz >= nyq:
        raise ValueError(f"fast kurtogram: narrowest band {min_bandwidth_Hz:g} Hz is not below Nyquist {nyq:g} Hz")
    max_level = float(np.log2(nyq / min_bandwidth_Hz))
    spectrum = scipy.fft.rfft(x - x.mean())
    df = fs / n
    rows = []
    for level, lo, hi in tree_bands(fs, max_level):
        if lo < min_low_Hz - 1e-9 * nyq:
            continue
        a, b = int(np.ceil(lo / df)), int(np.floor(hi / df))
        a = max(a, 1)
        if b - a < 8:
            continue
        z = scipy.fft.ifft(spectrum[a:b])
        p = z.real**2 + z.imag**2
        mean = float(np.mean(p))
        rows.append((level, lo, hi, float(np.mean(p * p) / mean**2 - 2.0) if mean > 0 else 0.0))
    if not rows:
        raise ValueError(
            f"fast kurtogram: no band of width >= {min_bandwidth_Hz:g} Hz above {min_low_Hz:g} Hz fits below "
            f"Nyquist {nyq:g} Hz; record at a higher rate or lower the narrowest band"
        )
    level, lo, hi, sk = (np.array(c) for c in zip(*rows, strict=True))
    return Kurtogram(lo, hi, sk, level)
