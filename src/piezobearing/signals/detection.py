"""From sensor voltage to fault detection (paper Sec. IV, Fig. 9 and 10).

The chain for one record ``x`` (voltage [V], uniform step ``dt`` [s]):

1. **Noise at a given SNR.** White Gaussian noise of variance
   sigma^2 = P_s / 10^(SNR/10), with P_s = mean(x^2) the mean-square value
   of the whole record (MATLAB's ``awgn(x, snr, 'measured')``); SNR in dB.
2. **Whole periods.** The record is cut to the largest whole number m of
   fault periods 1/f0, so the DFT bin spacing is f0/m and every harmonic
   k f0 falls on bin k m (exactly when f0 dt is rational with the record,
   as for the paper's dt = 1/(36 BPFO)).
3. **Band.** Either a configured band or the kurtogram's: the band of a
   1/3-binary filter bank (bandwidths Nyquist/{1.5, 2, 3, 4, 6, ...}, half
   overlapping, none reaching down to 0 Hz, none narrower than a minimum
   bandwidth) where the spectral kurtosis of the complex band signal z,
   SK = <|z|^4> / <|z|^2>^2 - 2, is largest (Antoni & Randall 2006).
   SK is 0 for Gaussian noise, -1 for one sinusoid, and large for an
   impulse train: the band where the defect's impulses stand out most.
4. **Envelope.** z is the analytic signal of x band-passed with the zero-phase
   magnitude |H|^2 of a Butterworth band-pass (what ``sosfiltfilt`` does),
   applied in the frequency domain on the whole-period record (no edge
   transient: the record is one period of its periodic extension). The
   envelope is |z|.
5. **Envelope spectrum.** A(f) = 2 |DFT(|z| - mean |z|)| / N [V], single-sided.
6. **Fault indicator.** For k = 1..K, r_k = A(k f0)^2 / mean A^2 over the
   local floor (bins within ``floor_halfwidth`` f0 of k f0, except the
   ``guard_bins`` next to any harmonic of f0). The indicator is
   I = sum_k r_k; the fault is detected when I exceeds the threshold of a
   constant-false-alarm-rate test on the noise floor (see
   :func:`indicator_threshold`).

Why a band-pass before the envelope: the healthy sensor force is itself
periodic at BPFO (every roller passing the sensor gives a smooth load bump),
so any BPFO line in the raw spectrum or in a broadband envelope fires for the
healthy bearing too. The bumps are smooth, so their harmonics die out within
a few multiples of BPFO; a defect adds short impulses whose spectrum is flat
up to the Nyquist frequency. In a band above the bumps' harmonics the healthy
signal is just noise (its envelope spectrum is flat), while the faulty one is
an impulse train at BPFO (its envelope has lines at k BPFO).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import fdtri

from .envelope import (
    EnvelopeSettings,
    EnvelopeSpectrum,
    Kurtogram,
    band_gain,
    choose_band,
    envelope_spectrum,
    kurtogram_bands,
)

#: Stable codes of the cases, used to derive independent noise streams (the fault types: the
#: classification's records per type, rule fault_type_voltage).
CASE_CODES = {"healthy": 0, "faulty": 1, "outer_race": 2, "inner_race": 3, "rolling_element": 4}


# --------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class IndicatorSettings:
    """The fault indicator and its threshold.

    Parameters
    ----------
    n_harmonics : int
        Harmonics k = 1..K of the fault frequency summed in the indicator [-].
    floor_halfwidth : float
        Half-width of the local noise-floor window, as a fraction of the fault frequency [-].
    guard_bins : int
        Bins next to each harmonic of the fault frequency left out of the floor [-].
    false_alarm_probability : float
        Probability that noise alone exceeds the threshold [-].
    """

    n_harmonics: int = 3
    floor_halfwidth: float = 0.5
    guard_bins: int = 2
    false_alarm_probability: float = 1e-3

    @classmethod
    def from_config(cls, sig: dict) -> "IndicatorSettings":
        return cls(
            n_harmonics=sig["n_harmonics"],
            floor_halfwidth=sig["floor_halfwidth"],
            guard_bins=sig["floor_guard_bins"],
            false_alarm_probability=sig["false_alarm_probability"],
        )


# --------------------------------------------------------------------------- noise


def signal_power_V2(x: np.ndarray) -> float:
    """Mean-square value of the whole record, P_s = mean(x^2) [V^2]."""
    x = np.asarray(x, dtype=float)
    return float(np.mean(x * x))


def noise_std_for_snr(x: np.ndarray, snr_dB: float) -> float:
    """Standard deviation of white noise that gives ``snr_dB`` = 10 log10(P_s / sigma^2) [V]."""
    return float(np.sqrt(signal_power_V2(x) / 10.0 ** (snr_dB / 10.0)))


def noise_rng(master_seed: int, case: str, replicate: int) -> np.random.Generator:
    """The noise generator of one record: independent streams per case and replicate."""
    return np.random.default_rng([int(master_seed), 6, CASE_CODES[case], int(replicate)])


# --------------------------------------------------------------------------- record length


def whole_period_samples(n_samples: int, dt_s: float, f0_Hz: float) -> int:
    """Number of samples spanning the largest whole number of periods 1/f0 in the record.

    m = floor(n dt f0) periods take round(m / (f0 dt)) samples; the DFT of that
    many samples has f0 on bin m to within |round(m/(f0 dt)) - m/(f0 dt)| f0 dt
    of a bin.
    """
    per = 1.0 / (f0_Hz * dt_s)  # samples per period
    m = int(np.floor(n_samples / per + 1e-9))
    if m < 1:
        raise ValueError(
            f"record of {n_samples} samples ({n_samples * dt_s:.4g} s) is shorter than one fault period "
            f"{1 / f0_Hz:.4g} s; simulate a longer record"
        )
    return min(n_samples, int(round(m * per)))


# --------------------------------------------------------------------------- indicator


def indicator_threshold(false_alarm_probability: float, n_harmonics: int, n_floor_bins: int) -> float:
    """Threshold of I = sum_k r_k for a given false-alarm probability.

    Under noise alone each envelope-spectrum bin is, by the central limit
    theorem over many envelope correlation lengths, a circular complex
    Gaussian: A^2 is exponential about the local mean power, and the mean of
    M floor bins is Gamma(M)/M distributed. With one common floor estimate,
    I = sum_k X_k / Y is exactly K F(2K, 2M); with a separate floor per
    harmonic (independent denominators) the tail of I is lighter, so
    K F_{1-pfa}(2K, 2M), with M the smallest floor count, is a conservative
    threshold (the false-alarm rate is at most ``false_alarm_probability``).
    """
    if not 0 < false_alarm_probability < 1:
        raise ValueError("signals.false_alarm_probability must lie in (0, 1)")
    return float(n_harmonics * fdtri(2 * n_harmonics, 2 * n_floor_bins, 1.0 - false_alarm_probability))


def harmonic_ratios(spec: EnvelopeSpectrum, f0_Hz: float, settings: IndicatorSettings) -> list[dict]:
    """Envelope amplitude at k f0 over the local noise floor, k = 1..K.

    Each entry: k, frequency_Hz (of the bin), bin_offset (distance of k f0
    from the bin, in bins), amplitude_V, floor_V (root-mean-square amplitude
    of the floor bins), ratio (power ratio r_k = A^2 / floor^2), ratio_dB,
    n_floor_bins.
    """
    f, a = spec.frequency_Hz, spec.amplitude_V
    df = spec.resolution_Hz
    g = settings.guard_bins
    near_harmonic = np.zeros(f.size, dtype=bool)
    kmax = int(f[-1] / f0_Hz) + 1
    for j in range(1, kmax + 1):
        near_harmonic |= np.abs(f - j * f0_Hz) <= (g + 0.5) * df
    out = []
    for k in range(1, settings.n_harmonics + 1):
        fk = k * f0_Hz
        i = int(round(fk / df))
        if i >= f.size - 1:
            raise ValueError(
                f"harmonic {k} of {f0_Hz:.6g} Hz lies above the spectrum's top {f[-1]:.6g} Hz; "
                "lower signals.n_harmonics"
            )
        win = (np.abs(f - fk) <= settings.floor_halfwidth * f0_Hz) & ~near_harmonic & (f > 0)
        nfl = int(win.sum())
        if nfl < 4:
            raise ValueError(
                f"only {nfl} noise-floor bins around {fk:.6g} Hz; lengthen the record or widen "
                "signals.floor_halfwidth"
            )
        floor = float(np.sqrt(np.mean(a[win] ** 2)))
        r = float(a[i] ** 2 / floor**2) if floor > 0 else float("inf")
        out.append(
            {
                "k": k,
                "frequency_Hz": float(f[i]),
                "bin_offset": float(fk / df - i),
                "amplitude_V": float(a[i]),
                "floor_V": floor,
                "ratio": r,
                "ratio_dB": float(10 * np.log10(r)) if r > 0 else float("-inf"),
                "n_floor_bins": nfl,
            }
        )
    return out


def fault_indicator(spec: EnvelopeSpectrum, f0_Hz: float, settings: IndicatorSettings) -> dict:
    """The indicator I = sum_k r_k, its threshold and the decision (see the module docstring)."""
    harm = harmonic_ratios(spec, f0_Hz, settings)
    value = float(sum(h["ratio"] for h in harm))
    m = min(h["n_floor_bins"] for h in harm)
    thr = indicator_threshold(settings.false_alarm_probability, settings.n_harmonics, m)
    return {
        "fault_frequency_Hz": float(f0_Hz),
        "harmonics": harm,
        "indicator": value,
        "threshold": thr,
        "detected": bool(value > thr),
        "false_alarm_probability": settings.false_alarm_probability,
        "band_Hz": list(spec.band_Hz),
        "resolution_Hz": spec.resolution_Hz,
    }


@dataclass(frozen=True)
class Analysis:
    """Everything :func:`analyse` found for one record."""

    spectrum: EnvelopeSpectrum
    kurtogram: Kurtogram | None
    result: dict


def analyse(
    x: np.ndarray, dt_s: float, f0_Hz: float, envelope_settings: EnvelopeSettings, indicator_settings: IndicatorSettings
) -> Analysis:
    """Whole periods, band, envelope spectrum and fault indicator of one record."""
    n = whole_period_samples(len(x), dt_s, f0_Hz)
    xw = np.asarray(x, dtype=float)[:n]
    band, kg = choose_band(xw, dt_s, envelope_settings)
    spec = envelope_spectrum(xw, dt_s, band, envelope_settings.filter_order)
    return Analysis(spec, kg, fault_indicator(spec, f0_Hz, indicator_settings))


def analyse_many(
    records: np.ndarray, dt_s: float, f0_Hz: float, envelope_settings: EnvelopeSettings,
    indicator_settings: IndicatorSettings
) -> list[dict]:
    """Of :func:`analyse`'s ``result`` for each row of ``records`` (R, n) [V]: band_Hz, indicator, threshold,
    detected and each harmonic's k, ratio, ratio_dB, as array operations over the rows with the filter gains,
    bins and threshold computed once (:func:`snr_sweep`'s batch: the same operations per record, identical
    values, test)."""
    x = np.asarray(records, dtype=float)
    return _sweep_seed_batch(x, _SweepPlan(x.shape[1], dt_s, f0_Hz, envelope_settings, indicator_settings))


# --------------------------------------------------------------------------- SNR study


def snr_sweep(
    voltage_V: np.ndarray,
    dt_s: float,
    f0_Hz: float,
    case: str,
    snr_dB: list[float],
    n_seeds: int,
    master_seed: int,
    envelope_settings: EnvelopeSettings,
    indicator_settings: IndicatorSettings,
    method: str = "batch",
) -> list[dict]:
    """Detection of one noiseless record over SNRs and noise seeds.

    Replicate j uses the generator :func:`noise_rng` (master_seed, case, j)
    at every SNR (common random numbers: the same noise shape, scaled), so
    replicate 0 at the configured SNR is the record of the ``noisy`` stage.

    ``method="batch"`` (default) analyses all SNRs of a seed at once as array
    operations (:func:`_sweep_seed_batch`), with the filter gains, bins and
    threshold computed once; ``method="loop"`` calls :func:`analyse` record
    by record (the previous method). Both give the same rows (same operations
    per record; benchmarks/bench_signals.py compares them).
    """
    if method not in ("batch", "loop"):
        raise ValueError(f"method must be 'batch' or 'loop', got {method!r}")
    v = np.asarray(voltage_V, dtype=float)
    sigmas = np.array([noise_std_for_snr(v, s) for s in snr_dB])
    plan = _SweepPlan(len(v), dt_s, f0_Hz, envelope_settings, indicator_settings) if method == "batch" else None
    rows = []
    for j in range(n_seeds):
        shape = noise_rng(master_seed, case, j).standard_normal(len(v))
        if method == "batch":
            res = _sweep_seed_batch(v[None, :] + sigmas[:, None] * shape[None, :], plan)
        else:
            res = [analyse(v + sg * shape, dt_s, f0_Hz, envelope_settings, indicator_settings).result for sg in sigmas]
        for s, r in zip(snr_dB, res, strict=True):
            rows.append(
                {
                    "case": case,
                    "snr_dB": float(s),
                    "seed": j,
                    "band_low_Hz": r["band_Hz"][0],
                    "band_high_Hz": r["band_Hz"][1],
                    "indicator": r["indicator"],
                    "threshold": r["threshold"],
                    "detected": r["detected"],
                    **{f"ratio_{h['k']}_dB": h["ratio_dB"] for h in r["harmonics"]},
                }
            )
    return rows


class _SweepPlan:
    """What every record of a sweep shares: length, band gains, floor windows, threshold."""

    def __init__(self, n_samples: int, dt_s: float, f0_Hz: float, es: EnvelopeSettings, ins: IndicatorSettings):
        self.n = whole_period_samples(n_samples, dt_s, f0_Hz)
        self.dt_s, self.f0_Hz, self.es, self.ins = dt_s, f0_Hz, es, ins
        self.f = np.fft.rfftfreq(self.n, dt_s)
        if es.band_rule == "fixed":
            self.bands = [(float(es.band_Hz[0]), float(es.band_Hz[1]))]
        elif es.band_rule == "kurtogram":
            self.bands = kurtogram_bands(1.0 / dt_s, es.min_bandwidth_Hz)
        else:
            raise ValueError(f"signals.band_rule: unknown rule '{es.band_rule}'; use 'kurtogram' or 'fixed'")
        self.gains = [band_gain(self.f, 1.0 / dt_s, b, es.filter_order) for b in self.bands]
        # the indicator's bins and floor windows, as harmonic_ratios finds them
        fe = np.fft.rfftfreq(self.n, dt_s)
        probe = EnvelopeSpectrum(fe, np.ones(fe.size), self.bands[0], self.n)
        harm = harmonic_ratios(probe, f0_Hz, ins)
        df = probe.resolution_Hz
        g = ins.guard_bins
        near = np.zeros(fe.size, dtype=bool)
        for j in range(1, int(fe[-1] / f0_Hz) + 2):
            near |= np.abs(fe - j * f0_Hz) <= (g + 0.5) * df
        self.harm = harm
        self.bins = [int(round(h["k"] * f0_Hz / df)) for h in harm]
        self.windows = [
            np.flatnonzero((np.abs(fe - h["k"] * f0_Hz) <= ins.floor_halfwidth * f0_Hz) & ~near & (fe > 0))
            for h in harm
        ]
        m = min(h["n_floor_bins"] for h in harm)
        self.threshold = indicator_threshold(ins.false_alarm_probability, ins.n_harmonics, m)

    def analytic(self, spectra: np.ndarray, gain: np.ndarray) -> np.ndarray:
        """Analytic band signals of rows with rfft ``spectra`` (as :func:`analytic_band_signal`)."""
        n = self.n
        y = spectra * gain
        z = np.zeros((spectra.shape[0], n), dtype=complex)
        z[:, : y.shape[1]] = y
        z[:, 1 : (n + 1) // 2] *= 2.0
        return np.fft.ifft(z, axis=1)


def _sweep_seed_batch(records: np.ndarray, plan: _SweepPlan) -> list[dict]:
    """:func:`analyse`'s result (band, indicator, harmonics) for each row of ``records`` (r, n_samples)."""
    n = plan.n
    x = np.ascontiguousarray(records[:, :n], dtype=float)
    spectra = np.fft.rfft(x, axis=1)
    if plan.es.band_rule == "kurtogram":
        sk = np.empty((x.shape[0], len(plan.bands)))
        for b, gain in enumerate(plan.gains):
            p = np.abs(plan.analytic(spectra, gain)) ** 2
            sk[:, b] = np.mean(p * p, axis=1) / np.mean(p, axis=1) ** 2 - 2.0
        choice = np.argmax(sk, axis=1)
    else:
        choice = np.zeros(x.shape[0], dtype=int)
    amp = np.empty((x.shape[0], n // 2 + 1))
    for b in np.unique(choice):
        rows = np.flatnonzero(choice == b)
        e = np.abs(plan.analytic(spectra[rows], plan.gains[b]))
        a = 2.0 * np.abs(np.fft.rfft(e - e.mean(axis=1, keepdims=True), axis=1)) / n
        if n % 2 == 0:
            a[:, -1] /= 2.0
        amp[rows] = a
    out = []
    for r in range(x.shape[0]):
        a = amp[r]
        harm = []
        for h, i, win in zip(plan.harm, plan.bins, plan.windows, strict=True):
            floor = float(np.sqrt(np.mean(a[win] ** 2)))
            ratio = float(a[i] ** 2 / floor**2) if floor > 0 else float("inf")
            harm.append(
                {"k": h["k"], "ratio": ratio, "ratio_dB": float(10 * np.log10(ratio)) if ratio > 0 else float("-inf")}
            )
        value = float(sum(h["ratio"] for h in harm))
        band = plan.bands[choice[r]]
        out.append(
            {
                "band_Hz": [float(band[0]), float(band[1])],
                "indicator": value,
                "threshold": plan.threshold,
                "detected": bool(value > plan.threshold),
                "harmonics": harm,
            }
        )
    return out


def detection_limit_dB(snr_dB: np.ndarray, rate: np.ndarray, required_rate: float) -> float:
    """Lowest SNR of the grid from which upward the detection rate stays >= ``required_rate`` [dB].

    NaN if even the highest SNR falls short.
    """
    order = np.argsort(snr_dB)
    s, r = np.asarray(snr_dB)[order], np.asarray(rate)[order]
    ok = r >= required_rate
    if not ok[-1]:
        return float("nan")
    i = len(ok) - 1
    while i > 0 and ok[i - 1]:
        i -= 1
    return float(s[i])


# --------------------------------------------------------------------------- defect events (Fig. 9)


def defect_event_times(
    faulty_V: np.ndarray, healthy_V: np.ndarray, dt_s: float, f0_Hz: float, t0_s: float = 0.0
) -> np.ndarray:
    """Times of the defect impulses: per fault period, the largest |faulty - healthy| [s].

    Both records must share their time base (same start and roller positions);
    the difference is then the defect's own contribution.
    """
    d = np.abs(np.asarray(faulty_V, dtype=float) - np.asarray(healthy_V, dtype=float))
    per = 1.0 / (f0_Hz * dt_s)
    m = int(np.floor(d.size / per + 1e-9))
    edges = np.round(np.arange(m + 1) * per).astype(int)
    idx = [a + int(np.argmax(d[a:b])) for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]
    return t0_s + np.array(idx) * dt_s
