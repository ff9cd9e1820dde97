"""The DAQ, the fault bands, the envelope detector and order tracking on signals of known content.

The fault signals here are synthetic impulse trains with known fault
frequencies: resonance bursts at the (slipped) fault rate, with the load-zone
modulation each fault type has (none for the outer race, the shaft angle for
the inner race, the cage angle for a roller). The full chain through the LPM
is checked in the stage tests.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import binom

from piezobearing import config
from piezobearing.signals import classification, daq, detection, detectors, envelope, order
from piezobearing.signals.fault_bands import band_metrics, fault_lines, slipped_frequencies

#: No-slip kinematics of the N 305 ECP at 1000 rpm (Z = 11, D_r/D_p = 10/44).
FR = 1000.0 / 60.0
G = 10.0 / 44.0
FTF = 0.5 * FR * (1 - G)
KIN = {"shaft_Hz": FR, "ftf_Hz": FTF, "bpfo_Hz": 11 * FTF, "bpfi_Hz": 11 * (FR - FTF),
       "bsf_Hz": 0.5 * 44.0 / 10.0 * FR * (1 - G**2)}
FS = 2550.0
#: The workflow's signals settings (band 500-1250 Hz, three harmonics, slip up to 3 %, pfa 1e-3) and its
#: envelope detector's settings for simulated records (no pre-whitening, the model's exact speed).
SIGNALS = config.load()["signals"]
CONFIGURED = detectors.envelope.Settings.from_config(SIGNALS)


def fault_signal(fault_type: str, slip: float, rng: np.random.Generator, fs: float = FS, duration_s: float = 1.0,
                 resonance_Hz: float = 900.0, decay_s: float = 1.5e-3, jitter: float = 0.0) -> np.ndarray:
    """Resonance bursts at the slipped fault rate, amplitude set by the load zone [V, unit peak].

    outer_race: every impact alike. inner_race: the defect's shaft angle
    through a load zone max(0, cos)^1.5, so impacts at the BPFI carry shaft-rate
    sidebands. rolling_element: impacts at 2 BSF, weighted by the cage angle
    of the roller through the load zone (FTF sidebands). ``jitter``: standard
    deviation of each interval over its mean [-].
    """
    f = slipped_frequencies(KIN, slip)
    rate = {"outer_race": f["bpfo_Hz"], "inner_race": f["bpfi_Hz"], "rolling_element": f["2bsf_Hz"]}[fault_type]
    n = int(round(duration_s * fs))
    t = np.arange(n) / fs
    start = rng.uniform(-1.0, 0.0) / rate
    gaps = (1.0 + jitter * rng.standard_normal(int(duration_s * rate) + 3)) / rate
    times = start + np.concatenate([[0.0], np.cumsum(gaps)])
    phase0 = rng.uniform(0, 2 * np.pi)
    x = np.zeros(n)
    for tk in times[(times > -10 * decay_s) & (times < t[-1])]:
        if fault_type == "inner_race":
            a = max(0.0, np.cos(2 * np.pi * f["shaft_Hz"] * tk + phase0)) ** 1.5
        elif fault_type == "rolling_element":
            a = max(0.0, np.cos(2 * np.pi * f["ftf_Hz"] * tk + phase0)) ** 1.5
        else:
            a = 1.0
        m = t >= tk
        tau = t[m] - tk
        x[m] += a * np.exp(-tau / decay_s) * np.sin(2 * np.pi * resonance_Hz * tau)
    return x


# --------------------------------------------------------------------------- fault bands


def test_slipped_frequencies_closed_form():
    """FTF, BPFO, BSF fall by (1 - s); BPFI rises by Z s FTF_0; the shaft rate stays."""
    s = 0.015
    f = slipped_frequencies(KIN, s)
    assert f["shaft_Hz"] == pytest.approx(FR)
    assert f["bpfo_Hz"] == pytest.approx((1 - s) * KIN["bpfo_Hz"], rel=1e-12)
    assert f["bpfi_Hz"] == pytest.approx(KIN["bpfi_Hz"] + 11 * s * FTF, rel=1e-12)
    assert f["bpfo_Hz"] + f["bpfi_Hz"] == pytest.approx(11 * FR, rel=1e-12)  # Z f_r, whatever the slip
    assert f["2bsf_Hz"] == pytest.approx(2 * (1 - s) * KIN["bsf_Hz"], rel=1e-12)
    assert KIN["bpfo_Hz"] == pytest.approx(70.83, abs=0.01)


def test_fault_lines_and_bands():
    """Outer race: k BPFO over [k BPFO (1 - s_max), k BPFO]; inner race: k BPFI +- f_r; roller: k 2 BSF +- FTF."""
    smax = 0.03
    outer = fault_lines(KIN, "outer_race", 3, 1, smax)
    assert [ln.harmonic for ln in outer] == [1, 2, 3]
    assert outer[2].low_Hz == pytest.approx(3 * KIN["bpfo_Hz"] * (1 - smax))
    assert outer[2].high_Hz == pytest.approx(3 * KIN["bpfo_Hz"])
    inner = fault_lines(KIN, "inner_race", 2, 1, smax)
    assert len(inner) == 6 and inner[0].sideband == -1
    assert inner[1].low_Hz == pytest.approx(KIN["bpfi_Hz"]) and inner[1].high_Hz > inner[1].low_Hz
    assert inner[2].frequency_Hz - inner[1].frequency_Hz == pytest.approx(FR)
    roll = fault_lines(KIN, "rolling_element", 1, 2, smax)
    mid = slipped_frequencies(KIN, smax / 2)
    assert [ln.frequency_Hz for ln in roll] == pytest.approx([mid["2bsf_Hz"] + m * mid["ftf_Hz"] for m in (-2, -1, 0, 1, 2)])


def test_band_metrics_find_a_slipped_line():
    """A tone at the 1.5 %-slipped BPFO is the peak of the first BPFO band, with its power A^2/2."""
    fs, n = 1000.0, 4000
    f1 = slipped_frequencies(KIN, 0.015)["bpfo_Hz"]
    x = 0.3 * np.cos(2 * np.pi * f1 * np.arange(n) / fs)
    spec = envelope.amplitude_spectrum(x, 1 / fs)
    m = band_metrics(spec.frequency_Hz, spec.amplitude_V, fault_lines(KIN, "outer_race", 1, 0, 0.03))[0]
    assert m["peak_frequency_Hz"] == pytest.approx(f1, abs=spec.resolution_Hz)
    assert m["band_power_V2"] == pytest.approx(0.3**2 / 2, rel=0.05)


# --------------------------------------------------------------------------- the envelope detector


def test_envelope_detector_false_alarms_on_noise_records():
    """White noise through the workflow's envelope detector (its fixed band, pfa 0.06): any-fault calls at most
    the stated rate (the count a detector at exactly that rate exceeds with probability 0.001)."""
    settings = replace(CONFIGURED, false_alarm_probability=0.06)
    n = 300
    rng = np.random.default_rng(3)
    calls = sum(detectors.detect(rng.standard_normal(int(FS)), FS, KIN, "envelope", settings).fault_type != "none"
                for _ in range(n))
    assert calls <= binom.ppf(0.999, n, settings.false_alarm_probability), calls


def test_envelope_detector_finds_a_slipped_outer_race_fault_where_the_exact_bin_fails():
    """1.5 % slip, 10 dB: the envelope detector's slip windows find the outer-race fault in >= 48 of 50 seeds, the
    paper's exact BPFO bins in at most half."""
    paper = detectors.paper.Settings.from_config(SIGNALS)
    found, exact = 0, 0
    for seed in range(50):
        rng = np.random.default_rng([5, seed])
        x = fault_signal("outer_race", 0.015, rng)
        y = daq.add_noise(x, 1 / FS, daq.NoiseSettings(snr_dB=10.0), rng).voltage_V
        found += detectors.detect(y, FS, KIN, "envelope", CONFIGURED).fault_type == "outer_race"
        exact += detectors.detect(y, FS, KIN, "paper", paper).fault_type == "outer_race"
    assert found >= 48
    assert exact <= 25


@pytest.mark.parametrize("fault_type", ["outer_race", "inner_race", "rolling_element"])
def test_envelope_detector_classifies_each_fault_type(fault_type):
    """Synthetic fault of each type at 1.5 % slip, 0.2 % jitter, 10 dB: classified right in >= 90 % of 30 seeds
    by the workflow's envelope detector. The records are 2 s long (0.5 Hz bins): at 1 s the inner race's
    lines and sidebands share bins with the rolling element's and the call goes to the rolling element."""
    got = []
    for seed in range(30):
        rng = np.random.default_rng([8, seed])
        x = fault_signal(fault_type, 0.015, rng, duration_s=2.0, jitter=0.002)
        y = daq.add_noise(x, 1 / FS, daq.NoiseSettings(snr_dB=10.0), rng).voltage_V
        got.append(detectors.detect(y, FS, KIN, "envelope", CONFIGURED).fault_type)
    cm = classification.confusion_matrix([fault_type] * len(got), got)
    assert cm["correct_rate"][fault_type] >= 0.9, cm["counts"]


def test_confusion_matrix_and_roc():
    cm = classification.confusion_matrix(["outer_race", "none", "none"], ["outer_race", "none", "inner_race"])
    assert cm["counts"][0][0] == 1 and cm["counts"][3][1] == 1 and cm["correct_rate"]["none"] == 0.5
    pfa, pd_ = classification.roc_points(np.array([3.0, 4.0]), np.array([1.0, 2.0]))
    assert classification.roc_auc(pfa, pd_) == pytest.approx(1.0)
    pfa, pd_ = classification.roc_points(np.array([1.0, 2.0]), np.array([1.0, 2.0]))
    assert classification.roc_auc(pfa, pd_) == pytest.approx(0.5)


# --------------------------------------------------------------------------- DAQ


def test_anti_alias_sampling_keeps_the_passband_and_drops_what_would_alias():
    """A 0.3 f_s tone passes at its amplitude; a 0.8 f_s tone (aliasing to 0.2 f_s) is gone."""
    fs_model, fs = 51200.0, 5120.0
    t = np.arange(int(fs_model)) / fs_model
    x = 1.0 * np.sin(2 * np.pi * 0.3 * fs * t) + 0.5 * np.sin(2 * np.pi * 0.8 * fs * t)
    s = daq.sample(x, 1 / fs_model, fs)
    assert s.dt_s == pytest.approx(1 / fs, rel=1e-12)
    spec = envelope.amplitude_spectrum(s.voltage_V, s.dt_s)
    a = dict(zip(np.round(spec.frequency_Hz, 6), spec.amplitude_V, strict=True))
    assert a[round(0.3 * fs, 6)] == pytest.approx(1.0, rel=1e-9)
    assert a[round(0.2 * fs, 6)] < 1e-9
    naive = envelope.amplitude_spectrum(x[::10], 10 / fs_model)  # decimation without a filter aliases
    assert naive.amplitude_V[np.argmin(np.abs(naive.frequency_Hz - 0.2 * fs))] == pytest.approx(0.5, rel=1e-6)


def test_sampling_at_a_non_integer_ratio_and_errors():
    """25.5 kHz model to a 10 kHz DAQ: a whole number of DAQ steps; a coarser model is refused."""
    fs_model = 25500.0
    x = np.sin(2 * np.pi * 1000.0 * np.arange(25500) / fs_model)
    s = daq.sample(x, 1 / fs_model, 10000.0)
    assert s.dt_s == pytest.approx(1e-4, rel=1e-12)
    assert np.max(np.abs(s.voltage_V - np.sin(2 * np.pi * 1000.0 * np.arange(s.voltage_V.size) * 1e-4))) < 1e-9
    with pytest.raises(ValueError, match="bearing.time_step_s"):
        daq.sample(x, 1 / fs_model, 51200.0)
    assert daq.sample(x, 1 / fs_model, fs_model).anti_alias.startswith("none")


def test_adc_quantises_and_reports_clipping():
    """Step 2 range / 2^bits; samples beyond the range counted and held at the end codes."""
    y, n = daq.quantise(np.array([0.0, 0.26, -0.9, 1.3, -2.0]), 3, 1.0)  # q = 0.25
    assert y.tolist() == [0.0, 0.25, -1.0, 0.75, -1.0]
    assert n == 2
    st = daq.NoiseSettings(model="absolute", adc_bits=16, range_V=10.0, noise_density_V_per_sqrtHz=1e-5,
                           mains_amplitudes_V=(0.0,))
    a = daq.add_noise(np.full(1000, 12.0), 1e-4, st, np.random.default_rng(0))
    assert a.n_clipped == 1000 and a.report()["clipped"]


def test_absolute_noise_level_and_mains_lines():
    """Noise std e_n sqrt(f_s/2) whatever the signal; mains harmonics at their amplitudes."""
    fs = 10240.0
    st = daq.NoiseSettings(model="absolute", noise_density_V_per_sqrtHz=2e-5, adc_bits=24, range_V=10.0,
                           mains_frequency_Hz=50.0, mains_amplitudes_V=(0.01, 0.003))
    x = np.zeros(int(fs) * 2)
    a = daq.add_noise(x, 1 / fs, st, np.random.default_rng(1))
    assert a.noise_std_V == pytest.approx(2e-5 * np.sqrt(fs / 2))
    spec = envelope.amplitude_spectrum(a.voltage_V, 1 / fs)
    i50, i100 = (np.argmin(np.abs(spec.frequency_Hz - f)) for f in (50.0, 100.0))
    assert spec.amplitude_V[i50] == pytest.approx(0.01, rel=0.05)
    assert spec.amplitude_V[i100] == pytest.approx(0.003, rel=0.15)
    rel = daq.add_noise(np.ones(1000) * 2.0, 1e-3, daq.NoiseSettings(snr_dB=10.0), np.random.default_rng(2))
    assert rel.noise_std_V == pytest.approx(np.sqrt(4.0 / 10.0))  # relative: 10 dB below the record's power


# --------------------------------------------------------------------------- order tracking


def ramp_record(rng, fs=10240.0, duration_s=3.0, rpm=(900.0, 1500.0), snr_dB=0.0):
    """Outer-race impacts locked to the shaft angle on a linear speed ramp, a 1-pulse/rev tachometer."""
    n = int(duration_s * fs)
    t = np.arange(n) / fs
    f0, f1 = rpm[0] / 60, rpm[1] / 60
    theta = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / duration_s * t**2)
    bpfo_order = KIN["bpfo_Hz"] / KIN["shaft_Hz"]
    k = np.arange(1, int(theta[-1] / (2 * np.pi) * bpfo_order))
    t_imp = np.interp(2 * np.pi * k / bpfo_order, theta, t)
    x = np.zeros(n)
    for tk in t_imp:
        m = (t >= tk) & (t < tk + 0.01)
        x[m] += np.exp(-(t[m] - tk) / 1e-3) * np.sin(2 * np.pi * 2200.0 * (t[m] - tk))
    y = daq.add_noise(x, 1 / fs, daq.NoiseSettings(snr_dB=snr_dB), rng).voltage_V
    return t, theta, y, order.tachometer_signal(theta, 1)


def test_shaft_angle_from_tachometer_pulses():
    """One pulse per revolution on a 900 -> 1500 rpm ramp: the angle between pulses, relative to the first
    pulse, within twice the edge's timing uncertainty of half a sample (2 pi f_r dt = 15 mrad at 1500 rpm,
    10240 Hz)."""
    t, theta, _, tacho = ramp_record(np.random.default_rng(0))
    tp = order.pulse_times(tacho, t[1])
    ang = order.shaft_angle(tp, 1)
    inside = (t > tp[0]) & (t < tp[-1])
    err = (ang(t[inside]) - theta[inside]) - (ang(tp[0]) - np.interp(tp[0], t, theta))
    assert np.max(np.abs(np.mod(err + np.pi, 2 * np.pi) - np.pi)) < 2 * np.pi * 25.0 * t[1]
    with pytest.raises(ValueError, match="at least 4"):
        order.shaft_angle(tp[:3], 1)


def test_order_tracking_finds_the_fault_that_the_ramp_smears():
    """On the 900 -> 1500 rpm ramp BPFO sweeps 64-106 Hz and the envelope detector on the record in time misses
    it; resampled at uniform shaft angle (512 samples per revolution) with the kinematics in orders it finds it
    in every seed. The band in orders, 70-170, holds the 2200 Hz resonance over the ramp (88-147 orders); the
    record's content up to 5120 Hz reaches 341 orders at 15 rev/s and folds above 171 orders, outside it. The
    time envelope resampled in angle (``order_envelope_spectrum``) peaks at the BPFO order to a bin."""
    samples_per_rev = 512
    in_orders = replace(detectors.envelope.Settings(), band_Hz=(70.0, 170.0), mains_Hz=(), refine_speed=False,
                        speed_tolerance=0.0, frequency_tolerance=0.0)
    kin_orders = order.kinematics_in_orders(KIN)
    mean_speed = {k: v * 1.2 for k, v in KIN.items()}  # kinematics at the mean 1200 rpm
    for seed in range(5):
        t, _, y, tacho = ramp_record(np.random.default_rng([21, seed]))
        angle = order.shaft_angle(order.pulse_times(tacho, t[1]), 1)
        resampled = order.angular_resample(y, t[1], angle, samples_per_rev)
        in_angle = detectors.detect(resampled.values, samples_per_rev, kin_orders, "envelope", in_orders)
        in_time = detectors.detect(y, 1 / t[1], mean_speed, "envelope", detectors.envelope.Settings())
        assert in_angle.fault_type == "outer_race", in_angle.families["outer_race"].margin_dB
        assert in_time.fault_type == "none"
        assert in_angle.families["outer_race"].margin_dB > in_time.families["outer_race"].margin_dB + 10.0
        spectrum = order.order_envelope_spectrum(y, t[1], (1500.0, 3000.0), angle, samples_per_rev=64)
        near = (spectrum.frequency_Hz > 2.0) & (spectrum.frequency_Hz < 8.0)
        peak = spectrum.frequency_Hz[near][np.argmax(spectrum.amplitude_V[near])]
        assert peak == pytest.approx(kin_orders["bpfo_Hz"], abs=spectrum.resolution_Hz)


def test_the_tail_probabilities_from_scipy_special_are_scipy_stats_bit_for_bit():
    """The chi-square log tail of the outer-race tests (``log_chi2_sf``) and the indicator's F threshold
    (``indicator_threshold``) take SciPy's special functions directly, not scipy.stats (its import, 0.45 CPU s,
    no longer paid by the jobs that need nothing else of it): the same bits as ``chi2.logsf`` (both sides of
    the median, q = 0, inf, NaN, dof <= 0, and the asymptotic term where it underflows) and ``f.isf``."""
    import warnings

    from scipy.special import gammaln
    from scipy.stats import chi2, f

    from piezobearing.signals.outer_race import log_chi2_sf

    def reference(q, dof):  # the function as it was: scipy.stats, then the asymptotic term
        q, dof = np.broadcast_arrays(np.asarray(q, float), np.asarray(dof, float))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            v = np.asarray(chi2.logsf(q, dof), float)
            bad = ~np.isfinite(v)
            a = 0.5 * dof[bad]
            v[bad] = -0.5 * q[bad] + (a - 1.0) * np.log(0.5 * q[bad]) - gammaln(a)
        return v

    rng = np.random.default_rng(3)
    q = np.concatenate([[0.0, -1.0, np.inf, np.nan, 1e-300, 2e4, 1e5, 3.0], rng.exponential(20, 3000),
                        rng.uniform(0, 3000, 1000)])
    dof = np.concatenate([[2, 3, 4, 1, 2, 2, 2, 0], rng.integers(1, 80, 3000), rng.integers(1, 400, 1000)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = log_chi2_sf(q, dof)
    assert ours.tobytes() == reference(q, dof).tobytes()
    assert np.isfinite(ours[5:7]).all() and ours[5] < -9000  # the asymptotic tail, not -inf
    assert log_chi2_sf(q[20], dof[20]) == reference(q[20], dof[20])[()]  # scalars too
    for p in (1e-6, 1e-3, 0.05, 0.5, 0.999):
        for k in (1, 3, 10):
            for m in (1, 7, 60, 1000):
                assert detection.indicator_threshold(p, k, m) == float(k * f.isf(p, 2 * k, 2 * m))
