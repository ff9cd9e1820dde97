"""The fault-detection chain (piezobearing.signals.detection) on signals of known content."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import butter, sosfreqz

from piezobearing.sensor.calibration import SensorCircuit, circuit_voltage, frequency_response
from piezobearing.sensor.response import fem_ratio, sensor_model
from piezobearing.signals import daq, detection, envelope

FS = 2550.0  # the paper's sampling rate [Hz]
DT = 1.0 / FS
BPFO = FS / 36  # the paper's dt is exactly 1/(36 BPFO)


def am_impulse_train(n, dt, sample_rate_Hz, carrier_Hz, mod_Hz, mod_depth=0.5, decay_s=2e-3, t0=0.0):
    """Decaying resonance bursts at ``sample_rate_Hz``, amplitude-modulated at ``mod_Hz`` (an inner-race-like signal)."""
    t = np.arange(n) * dt
    x = np.zeros(n)
    for tk in np.arange(t0, t[-1], 1.0 / sample_rate_Hz):
        m = t >= tk
        tau = t[m] - tk
        a = 1.0 + mod_depth * np.cos(2 * np.pi * mod_Hz * tk)
        x[m] += a * np.exp(-tau / decay_s) * np.sin(2 * np.pi * carrier_Hz * tau)
    return x


def bearing_force(n, impulse_N=0.0, width_s=4.0e-3):
    """Sensor force of a stand-in bearing: a smooth load bump per roller passage, plus a sharp
    two-sample defect impulse per passage over the defect when ``impulse_N`` > 0 [N]."""
    t = np.arange(n) * DT
    ph = (t * BPFO) % 1.0
    bump = sum(np.exp(-0.5 * ((ph - 0.4 + s) / (BPFO * width_s)) ** 2) for s in (-1, 0, 1))
    f = 200.0 + 50.0 * bump
    if impulse_N:
        i = np.flatnonzero(np.diff(np.floor(t * BPFO - 0.3)) > 0) + 1
        f[i] -= impulse_N
        f[np.minimum(i + 1, n - 1)] += 0.5 * impulse_N
    return f


def bearing_voltage(n, impulse_N=0.0):
    return circuit_voltage(bearing_force(n, impulse_N), DT, SensorCircuit())


ENV = envelope.EnvelopeSettings()
IND = detection.IndicatorSettings()


# --------------------------------------------------------------------------- noise


def test_noise_has_the_requested_snr_and_is_seeded():
    x = np.sin(2 * np.pi * 50 * np.arange(200_000) * DT) + 0.3
    acq = daq.add_noise(x, DT, daq.NoiseSettings(model="relative", snr_dB=10.0), np.random.default_rng(1))
    y, sigma = acq.voltage_V, acq.noise_std_V
    assert sigma == pytest.approx(np.sqrt(np.mean(x**2) / 10.0), rel=1e-12)
    # realised noise power within 4 standard errors (relative s.e. sqrt(2/N)) of sigma^2
    assert np.mean((y - x) ** 2) / sigma**2 == pytest.approx(1.0, abs=4 * np.sqrt(2 / x.size))
    y2 = daq.add_noise(x, DT, daq.NoiseSettings(model="relative", snr_dB=10.0), np.random.default_rng(1)).voltage_V
    assert np.array_equal(y, y2)
    a = detection.noise_rng(3, "healthy", 0).standard_normal(5)
    assert np.array_equal(a, detection.noise_rng(3, "healthy", 0).standard_normal(5))
    assert not np.array_equal(a, detection.noise_rng(3, "faulty", 0).standard_normal(5))


# --------------------------------------------------------------------------- record length and bins


def test_whole_periods_put_bpfo_on_a_bin():
    n = detection.whole_period_samples(2550, DT, BPFO)  # 1 s at the paper's dt
    assert n == 2520  # 70 periods of 36 samples
    df = 1.0 / (n * DT)
    assert BPFO / df == pytest.approx(70.0, abs=1e-9)
    # the paper's printed dt = 0.392156e-3 s and BPFO = 70.8 Hz: still within 0.02 bin
    n2 = detection.whole_period_samples(2550, 0.392156e-3, 70.8)
    off = 70.8 * n2 * 0.392156e-3
    assert abs(off - round(off)) < 0.02
    with pytest.raises(ValueError, match="shorter than one fault period"):
        detection.whole_period_samples(20, DT, BPFO)


# --------------------------------------------------------------------------- spectral kurtosis and bands


def test_spectral_kurtosis_of_known_signals():
    rng = np.random.default_rng(0)
    n = 100_000
    noise = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    assert envelope.spectral_kurtosis(noise) == pytest.approx(0.0, abs=0.05)  # s.e. about 2/sqrt(n)
    assert envelope.spectral_kurtosis(np.exp(2j * np.pi * 0.1 * np.arange(n))) == pytest.approx(-1.0, abs=1e-9)
    train = np.zeros(n, dtype=complex)
    train[::50] = 1.0  # one sample in 50: SK = 50 - 2
    assert envelope.spectral_kurtosis(train) == pytest.approx(48.0, rel=1e-9)


def test_kurtogram_bank_and_choice():
    bands = envelope.kurtogram_bands(FS, 300.0)
    nyq = FS / 2
    assert all(0 < lo < hi <= nyq + 1e-9 and hi - lo >= 300.0 - 1e-9 for lo, hi in bands)
    assert (nyq / 3, nyq) in [(pytest.approx(lo), pytest.approx(hi)) for lo, hi in bands]
    # bursts ringing at 900 Hz in noise: the chosen band contains the carrier
    n = 5100
    x = am_impulse_train(n, DT, 53.7, 900.0, 8.0)
    x += detection.noise_std_for_snr(x, 0.0) * np.random.default_rng(2).standard_normal(n)
    lo, hi = envelope.kurtogram(x, DT, 300.0).best_band_Hz
    assert lo < 900.0 < hi
    with pytest.raises(ValueError, match="kurtogram_min_bandwidth_Hz"):
        envelope.kurtogram_bands(FS, 2000.0)


def test_band_gain_is_a_zero_phase_butterworth():
    f = np.array([100.0, 700.0, 900.0, 1200.0])
    g = envelope.band_gain(f, FS, (600.0, 1000.0), 4)
    assert g[0] < 1e-6 and g[1] > 0.9 and g[2] > 0.9 and g[3] < 0.01
    assert envelope.band_gain(np.array([600.0]), FS, (600.0, 1000.0), 4)[0] == pytest.approx(0.5, rel=1e-6)  # -3 dB x 2
    with pytest.raises(ValueError, match="Nyquist"):
        envelope.band_gain(f, FS, (600.0, 1400.0), 4)


@pytest.mark.parametrize(("rate_Hz", "band_Hz", "order"), [
    (12000.0, (1000.0, 3000.0), 4), (2550.0, (100.0, 400.0), 4), (25600.0, (3000.0, 6000.0), 2),
    (12000.0, (500.0, 6000.0), 4), (48000.0, (12000.0, 24000.0), 3),
])
def test_band_gain_equals_scipys_butterworth_sections(rate_Hz, band_Hz, order):
    """The closed form is the squared magnitude of ``butter(..., output="sos")`` evaluated by ``sosfreqz``,
    band-pass and high-pass (a band to Nyquist), at every bin of a record, DC and Nyquist included."""
    f = np.fft.rfftfreq(24000, 1.0 / rate_Hz)
    lo, hi = band_Hz
    if hi >= rate_Hz / 2:
        sos = butter(order, lo, btype="highpass", fs=rate_Hz, output="sos")
    else:
        sos = butter(order, [lo, hi], btype="bandpass", fs=rate_Hz, output="sos")
    reference = np.abs(sosfreqz(sos, worN=f, fs=rate_Hz)[1]) ** 2
    gain = envelope.band_gain(f, rate_Hz, band_Hz, order)
    assert gain[0] == 0.0
    np.testing.assert_allclose(gain, reference, rtol=0, atol=1e-12 * reference.max())
    passband = reference > 1e-3
    np.testing.assert_allclose(gain[passband], reference[passband], rtol=1e-10)


# --------------------------------------------------------------------------- envelope spectrum


@pytest.mark.parametrize("sample_rate_Hz", [53.7, BPFO])
def test_envelope_peak_of_am_impulse_train_within_one_bin(sample_rate_Hz):
    """Bursts at a known rate, amplitude-modulated at 8 Hz, in noise at 0 dB: the envelope spectrum's
    largest peak near the rate lies within one bin of it, its harmonics too, and the modulation
    sidebands rate +- 8 Hz stand out of the floor."""
    n = detection.whole_period_samples(5100, DT, sample_rate_Hz)
    x = am_impulse_train(n, DT, sample_rate_Hz, 900.0, 8.0)
    x += detection.noise_std_for_snr(x, 0.0) * np.random.default_rng(5).standard_normal(n)
    spec = envelope.envelope_spectrum(x, DT, (600.0, 1200.0))
    f, a = spec.frequency_Hz, spec.amplitude_V
    df = spec.resolution_Hz
    for k in (1, 2, 3):
        win = (f > (k - 0.5) * sample_rate_Hz) & (f < (k + 0.5) * sample_rate_Hz)
        assert abs(f[win][np.argmax(a[win])] - k * sample_rate_Hz) <= df
    floor = np.median(a[(f > 20) & (f < 400)])
    for side in (sample_rate_Hz - 8.0, sample_rate_Hz + 8.0):
        assert a[np.argmin(np.abs(f - side))] > 5 * floor


def test_envelope_spectrum_amplitude_of_a_known_modulation():
    """A 900 Hz carrier, amplitude 1 + 0.4 cos(2 pi 70 t): the envelope's line at 70 Hz has amplitude 0.4."""
    n = 2550
    t = np.arange(n) * DT
    x = (1 + 0.4 * np.cos(2 * np.pi * 70.0 * t)) * np.cos(2 * np.pi * 900.0 * t)
    spec = envelope.envelope_spectrum(x, DT, (600.0, 1200.0))
    i = int(round(70.0 / spec.resolution_Hz))
    assert spec.amplitude_V[i] == pytest.approx(0.4, rel=1e-3)
    assert spec.amplitude_V[0] == pytest.approx(0.0, abs=1e-12)


# --------------------------------------------------------------------------- indicator and threshold


def test_threshold_is_the_F_quantile():
    # one harmonic, floor of many bins: approaches the exponential quantile -ln(pfa)
    assert detection.indicator_threshold(1e-3, 1, 100_000) == pytest.approx(-np.log(1e-3), rel=1e-3)
    assert detection.indicator_threshold(1e-3, 3, 60) > detection.indicator_threshold(1e-3, 3, 10_000)
    with pytest.raises(ValueError):
        detection.indicator_threshold(0.0, 3, 60)


@pytest.mark.parametrize("rule", ["fixed", "kurtogram"])
def test_false_alarm_rate_on_noise_alone(rule):
    """Gaussian noise alone: the indicator exceeds the threshold for pfa = 0.05 at most at that rate
    (binomial upper bound), and not absurdly less often (the threshold is not slack). The records analysed as one
    array (``analyse_many``: analyse()'s result per record, identical, test below)."""
    env = envelope.EnvelopeSettings(band_rule=rule, band_Hz=(500.0, 1250.0))
    ind = detection.IndicatorSettings(false_alarm_probability=0.05)
    trials = 400 if rule == "fixed" else 200
    rng = np.random.default_rng(11)
    x = np.array([rng.standard_normal(2550) for _ in range(trials)])
    hits = sum(r["detected"] for r in detection.analyse_many(x, DT, BPFO, env, ind))
    rate = hits / trials
    se = np.sqrt(0.05 * 0.95 / trials)
    assert rate <= 0.05 + 3 * se
    assert rate >= 0.01


def test_healthy_roller_passage_fools_a_naive_indicator_but_not_the_envelope_band():
    """The healthy signal is periodic at BPFO (one load bump per roller): its raw spectrum has a huge BPFO
    line, so the same CFAR test on the raw spectrum 'detects' a fault; after the band-pass the smooth
    bumps are gone and only the defect's sharp impulses modulate the envelope."""
    n = detection.whole_period_samples(2550, DT, BPFO)
    v = bearing_voltage(n)
    y = daq.add_noise(v, DT, daq.NoiseSettings(model="relative", snr_dB=10.0), np.random.default_rng(0)).voltage_V
    raw = envelope.EnvelopeSpectrum(np.fft.rfftfreq(n, DT), 2 * np.abs(np.fft.rfft(y - y.mean())) / n, (0, FS / 2), n)
    assert detection.fault_indicator(raw, BPFO, IND)["detected"]
    assert not detection.analyse(y, DT, BPFO, ENV, IND).result["detected"]


@pytest.mark.parametrize("rule", ["kurtogram", "fixed"])
def test_bearing_stand_in_at_snr_10_over_20_seeds(rule):
    """Stand-in bearing (smooth roller bumps, 10 N two-sample defect impulses on 50 N bumps) through the
    RC sensor: at 10 dB the faulty record is detected and the healthy one is not, for 20 noise seeds."""
    env = envelope.EnvelopeSettings(band_rule=rule, band_Hz=(500.0, 1250.0))
    n = 2550
    vh, vf = bearing_voltage(n), bearing_voltage(n, impulse_N=10.0)
    for j in range(20):
        noise = np.random.default_rng(100 + j).standard_normal(n)
        rh = detection.analyse(vh + detection.noise_std_for_snr(vh, 10.0) * noise, DT, BPFO, env, IND).result
        rf = detection.analyse(vf + detection.noise_std_for_snr(vf, 10.0) * noise, DT, BPFO, env, IND).result
        assert rf["detected"] and not rh["detected"], (j, rf["indicator"], rh["indicator"])


def test_harmonic_ratios_report_bins_and_floor():
    n = detection.whole_period_samples(2550, DT, BPFO)
    x = am_impulse_train(n, DT, BPFO, 900.0, 8.0, mod_depth=0.0)
    spec = envelope.envelope_spectrum(x + 0.01 * np.random.default_rng(3).standard_normal(n), DT, (600.0, 1200.0))
    h = detection.harmonic_ratios(spec, BPFO, IND)
    assert [e["k"] for e in h] == [1, 2, 3]
    for e in h:
        assert e["frequency_Hz"] == pytest.approx(e["k"] * BPFO, abs=1e-6)
        assert abs(e["bin_offset"]) < 1e-6
        assert e["ratio_dB"] > 20
        assert e["n_floor_bins"] >= 60
    with pytest.raises(ValueError, match="n_harmonics"):
        detection.harmonic_ratios(spec, BPFO, detection.IndicatorSettings(n_harmonics=40))


# --------------------------------------------------------------------------- study helpers, sensor model, events


def test_detection_limit():
    snr = np.array([-4.0, -2.0, 0.0, 2.0, 4.0])
    assert detection.detection_limit_dB(snr, np.array([0.0, 1.0, 0.9, 1.0, 1.0]), 0.95) == 2.0
    assert detection.detection_limit_dB(snr, np.array([1.0, 1.0, 1.0, 1.0, 1.0]), 0.95) == -4.0
    assert np.isnan(detection.detection_limit_dB(snr, np.array([0.0, 0.0, 0.0, 0.0, 0.5]), 0.95))


def test_snr_sweep_replicate_zero_is_the_noisy_stage_record():
    n = 2550
    v = bearing_voltage(n, impulse_N=3.0)
    rows = detection.snr_sweep(v, DT, BPFO, "faulty", [10.0], 2, 7, ENV, IND)
    y = daq.add_noise(v, DT, daq.NoiseSettings(model="relative", snr_dB=10.0), detection.noise_rng(7, "faulty", 0)).voltage_V
    assert rows[0]["indicator"] == pytest.approx(detection.analyse(y, DT, BPFO, ENV, IND).result["indicator"], rel=1e-12)
    assert rows[0]["indicator"] != rows[1]["indicator"]


@pytest.mark.parametrize("rule", ["fixed", "kurtogram"])
def test_batched_snr_sweep_gives_the_rows_of_the_record_by_record_analysis(rule):
    """The batched sweep (all SNRs of a seed as one array) decides and reports exactly as analyse() per record."""
    v = bearing_voltage(2550, impulse_N=3.0)
    es = envelope.EnvelopeSettings(band_rule=rule, band_Hz=(500.0, 1200.0))
    grid = [-10.0, 0.0, 5.0, 10.0, 30.0]
    batch = detection.snr_sweep(v, DT, BPFO, "faulty", grid, 3, 7, es, IND)
    loop = detection.snr_sweep(v, DT, BPFO, "faulty", grid, 3, 7, es, IND, method="loop")
    assert batch == loop  # same operations per record: identical floats, bands and decisions
    assert {r["detected"] for r in batch} == {True, False}  # the grid spans both decisions
    x = v + np.random.default_rng(3).standard_normal((4, v.size)) * np.array([[0.1], [1.0], [3.0], [10.0]])
    for many, one in zip(detection.analyse_many(x, DT, BPFO, es, IND), (detection.analyse(r, DT, BPFO, es, IND).result for r in x),
                         strict=True):
        assert many == {k: one[k] for k in many if k != "harmonics"} | {
            "harmonics": [{k: h[k] for k in ("k", "ratio", "ratio_dB")} for h in one["harmonics"]]}


def test_fem_correction_factor():
    c = SensorCircuit()
    f = np.array([500.0, 1000.0, 5000.0, 1e5])
    rc = np.abs(frequency_response(f, c))
    fem = 0.9 * rc * np.array([1.0, 1.0, 1.05, 3.0])  # flat below Nyquist, resonant far above
    out = fem_ratio(f, fem / rc, FS / 2)
    assert out["factor"] == pytest.approx(0.9) and out["n_frequencies"] == 2
    out = fem_ratio(f[2:], fem[2:] / rc[2:], FS / 2)  # no FEM point below Nyquist: the lowest two
    assert out["frequencies_Hz"] == [5000.0, 1e5]


def test_sensor_model_names_the_file_of_its_fem_response():
    """A FEM response read from a file other than the workflow's (diagnose-bearing --sensor-response) is named."""
    c = SensorCircuit()
    f = np.array([500.0, 1000.0, 5000.0])
    h = 0.94 * np.abs(frequency_response(f, c))
    config = {"signals": {"sensor_fem_correction": True}}
    model = sensor_model(config, c, FS / 2, (f, h, "/elsewhere/harmonic.csv"))
    assert model.fem_factor == pytest.approx(0.94) and "/elsewhere/harmonic.csv" in model.source
    assert "results/sensor/harmonic.csv" in sensor_model(config, c, FS / 2, (f, h)).source


def test_defect_event_times_find_the_impulses():
    n = 2550
    vh, vf = bearing_voltage(n), bearing_voltage(n, impulse_N=3.0)
    t = detection.defect_event_times(vf, vh, DT, BPFO)
    assert len(t) == 70
    assert np.allclose(np.diff(t), 1 / BPFO, atol=1.01 * DT)
