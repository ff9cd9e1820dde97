"""The views a running bearing's residual is judged in, besides the engine's whitened time residual.

Each does not depend on phase luck: it is laid on the fitted kinematics
(the start phase, speed and slip of the fit being judged).

- ``per_passage``: the error in each roller passage over the sensor (one
  roller pitch of cage angle, centred on a roller at the sensor); a passage
  whose whitened energy exceeds the chi-square quantile at the Bonferroni
  level is named with its time and number.
- ``synchronous_average``: measured, model and residual averaged over the
  roller-passage period (64 bins of cage phase within a pitch); a residual
  bin beyond its standard error's Bonferroni band names the point of the
  passage (degrees of cage angle from a roller over the sensor).
- ``envelope``: the envelope spectrum (Hilbert magnitude of the band
  0.25-0.45 f_s) of the measured voltage and the residual, with every fault
  band marked (FTF, BPFO, BPFI, BSF, 2 x BSF and their harmonics, the shaft
  rate); a residual line at a fault band above the band's noise
  (exceedance at the family's false-alarm level) names the band.
- ``orders``: the residual spectrum against the noise floor, with each
  peak named in orders of the shaft and of the roller-pass rate
  (the engine's spectrum test finds the peaks; this names them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import hilbert
from scipy.stats import chi2 as chi2_dist
from scipy.stats import norm

from ...bearing.surrogate import cage_phase
from ..residual_tests import residual_tests
from ..subject import Judgement
from . import chain

#: Bins of the synchronous average over one roller pitch.
SYNC_BINS = 64


def fitted_kinematics(values: dict, record) -> dict:
    """Shaft speed, slip and the cage phase at every sample of a fit [Hz, -, rad]."""
    rig = record.rig
    if rig.tach_Hz is None:
        speed = values.get("shaft_speed_Hz", rig.shaft_speed_Hz) * (1 + values.get("speed_deviation_ratio", 0.0))
    else:
        speed = rig.tach_Hz * (1 + values.get("speed_deviation_ratio", 0.0))
    slip = values.get("cage_slip_ratio", 0.0)

    phi = cage_phase(record.time_s, speed, rig.geometry, values.get("start_phase_rad", 0.0), slip)
    f_mean = float(np.mean(speed))
    return {"shaft_Hz": f_mean, "slip": slip, "phase_rad": phi, "frequencies": rig.frequencies(f_mean, slip)}


def passages(phase_rad: np.ndarray, pitch_rad: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """[start, stop) and centre index of each whole roller passage over the sensor.

    A passage is the half-pitch either side of a roller standing at the
    sensor (cage phase a multiple of the pitch).
    """
    k = np.floor(phase_rad / pitch_rad + 0.5)
    edges = np.flatnonzero(np.diff(k) != 0) + 1
    start, stop = edges[:-1], edges[1:]
    centre = np.array(
        [a + int(np.argmin(np.abs(np.mod(phase_rad[a:b] + pitch_rad / 2, pitch_rad) - pitch_rad / 2))) for a, b in zip(start, stop, strict=True)],
        dtype=int,
    )
    return start, stop, centre


@dataclass(frozen=True)
class PerPassage:
    """The error per roller passage over the sensor."""

    key: str = "per_passage"

    def judge(self, fit, problem, settings) -> Judgement:
        rec = problem.record
        kin = fitted_kinematics(fit.values, rec)
        start, stop, centre = passages(kin["phase_rad"], rec.rig.pitch_rad)
        v = problem.voltage_V
        rows, energy = [], []
        for j, (a, b) in enumerate(zip(start, stop, strict=True)):
            r = fit.residual_V[a:b]
            e = float(np.sum(fit.whitened[a:b] ** 2))
            energy.append((e, b - a))
            rows.append(
                {
                    "passage": j + 1,
                    "time_s": float(rec.time_s[centre[j]]),
                    "nrmse": float(np.sqrt(np.mean(r**2) / max(np.mean(v[a:b] ** 2), 1e-300))),
                    "residual_rms_V": float(np.sqrt(np.mean(r**2))),
                    "excess_ratio": e / (b - a),
                }
            )
        alpha = settings.test_alpha / max(len(rows), 1)
        found = []
        flagged = [
            (row, e / m) for row, (e, m) in zip(rows, energy, strict=True) if e > chi2_dist.isf(alpha, m)
        ]
        flagged.sort(key=lambda x: -x[1])
        for row, ratio in flagged[:5]:
            found.append(
                {
                    "test": "per_passage",
                    "passage": row["passage"],
                    "time_s": row["time_s"],
                    "max_ratio": ratio,
                    "where": f"roller passage {row['passage']} (t = {row['time_s']:.4f} s): residual energy "
                    f"{ratio:.1f}x the floor",
                }
            )
        if len(flagged) > 5:
            found.append(
                {
                    "test": "per_passage",
                    "where": f"{len(flagged)} of {len(rows)} roller passages above the floor "
                    f"(every {len(rows) / len(flagged):.1f} passages on average)",
                }
            )
        arrays = {
            "time_s": rec.time_s[centre] if centre.size else np.zeros(0),
            "excess_ratio": np.array([r["excess_ratio"] for r in rows]),
            "threshold": np.array(
                [chi2_dist.isf(alpha, m) / m for _, m in energy] if energy else np.zeros(0)
            ),
        }
        return Judgement(
            {"n_passages": len(rows), "flagged": len(flagged), "passages": rows[:400]}, arrays, found
        )


@dataclass(frozen=True)
class SynchronousAverage:
    """Measured, model and residual averaged over the roller-passage period."""

    key: str = "synchronous_average"

    def judge(self, fit, problem, settings) -> Judgement:
        rec = problem.record
        kin = fitted_kinematics(fit.values, rec)
        pitch = rec.rig.pitch_rad
        # bin 0 is centred on a roller standing at the sensor
        b = np.floor(np.mod(kin["phase_rad"] + pitch / (2 * SYNC_BINS), pitch) / pitch * SYNC_BINS).astype(int)
        b = np.clip(b, 0, SYNC_BINS - 1)
        count = np.bincount(b, minlength=SYNC_BINS).astype(float)
        ok = count > 1

        def avg(x):
            return np.bincount(b, weights=x, minlength=SYNC_BINS) / np.maximum(count, 1)

        meas, model, res = avg(problem.voltage_V), avg(fit.model_V), avg(fit.residual_V)
        sigma = problem.floor.voltage_noise_V / np.sqrt(np.maximum(count, 1))
        z = np.where(ok, res / sigma, 0.0)
        thr = float(norm.isf(settings.test_alpha / (2 * SYNC_BINS)))
        angle = np.degrees(np.arange(SYNC_BINS) * pitch / SYNC_BINS)
        angle = np.where(angle > np.degrees(pitch) / 2, angle - np.degrees(pitch), angle)
        found = []
        bad = np.flatnonzero(np.abs(z) > thr)
        if bad.size:
            i = bad[np.argmax(np.abs(z[bad]))]
            found.append(
                {
                    "test": "synchronous_average",
                    "bins": int(bad.size),
                    "angle_deg": float(angle[i]),
                    "z": float(z[i]),
                    "where": f"synchronous average over the roller passage: residual {res[i] * 1e3:+.2f} mV "
                    f"({z[i]:+.1f} standard errors) at {angle[i]:+.1f} deg of cage angle from a roller over the "
                    f"sensor ({bad.size} of {SYNC_BINS} bins beyond the band)",
                }
            )
        summary = {
            "bins": SYNC_BINS,
            "threshold_z": thr,
            "max_abs_z": float(np.max(np.abs(z))),
            "residual_rms_V": float(np.sqrt(np.mean(res[ok] ** 2))) if ok.any() else 0.0,
            "measured_peak_to_peak_V": float(np.ptp(meas[ok])) if ok.any() else 0.0,
        }
        arrays = {"angle_deg": angle, "measured_V": meas, "model_V": model, "residual_V": res, "band_V": thr * sigma}
        return Judgement(summary, arrays, found)


def fault_lines(freqs: dict, f_max: float, n_harm: int = 3) -> list[dict]:
    """The fault bands to mark: k x (FTF, BPFO, BPFI, BSF, 2 BSF, shaft), k = 1..n_harm, below f_max [Hz]."""
    out = []
    for name, f in (
        ("shaft", freqs["shaft_Hz"]),
        ("FTF", freqs["ftf_Hz"]),
        ("BPFO", freqs["bpfo_Hz"]),
        ("BPFI", freqs["bpfi_Hz"]),
        ("BSF", freqs["bsf_Hz"]),
        ("2xBSF", 2 * freqs["bsf_Hz"]),
    ):
        for k in range(1, n_harm + 1):
            if k * f < f_max:
                out.append({"name": name if k == 1 else f"{k}x{name}", "frequency_Hz": k * f})
    return out


def envelope_spectrum(x: np.ndarray, fs: float, band: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude spectrum of the Hilbert envelope of x band-passed (ideal, in the DFT) to ``band`` [Hz, V]."""
    n = x.size
    spec = np.fft.rfft(x - np.mean(x))
    f = np.fft.rfftfreq(n, 1 / fs)
    spec[(f < band[0]) | (f > band[1])] = 0
    env = np.abs(hilbert(np.fft.irfft(spec, n)))
    env = env - env.mean()
    win = np.hanning(n)
    a = 2 * np.abs(np.fft.rfft(env * win)) / np.sum(win)
    return f, a


@dataclass(frozen=True)
class EnvelopeBands:
    """The envelope spectrum of measured and residual with every fault band marked."""

    key: str = "envelope"

    def judge(self, fit, problem, settings) -> Judgement:
        rec = problem.record
        fs = rec.sample_rate_Hz
        band = (0.25 * fs, 0.45 * fs)
        kin = fitted_kinematics(fit.values, rec)
        f, a_meas = envelope_spectrum(problem.voltage_V, fs, band)
        _, a_res = envelope_spectrum(fit.residual_V, fs, band)
        lines = fault_lines(kin["frequencies"], min(band[1] - band[0], 0.5 * fs))
        df = f[1] - f[0]
        hw = max(2, int(np.ceil(0.01 * kin["frequencies"]["bpfo_Hz"] / df)))
        # the residual's envelope noise near each band: the median of the bins within 20 bins either side
        # of the band's window (the envelope spectrum of noise is not flat: it falls from 0 Hz to the
        # band's width), so the amplitudes there are Rayleigh-like with that median
        sel = (f > 2.0) & (f < band[1] - band[0])
        floor = float(np.median(a_res[sel])) if sel.any() else 0.0
        # the largest of M Rayleigh amplitudes exceeds c x median with prob 1 - (1 - exp(-c^2 ln 2))^M
        m = max(1, len(lines) * (2 * hw + 1))
        c = float(np.sqrt(-np.log(1 - (1 - settings.test_alpha) ** (1 / m)) / np.log(2)))
        found, marks = [], []
        for ln in lines:
            i = int(np.argmin(np.abs(f - ln["frequency_Hz"])))
            win = slice(max(i - hw, 0), i + hw + 1)
            j = win.start + int(np.argmax(a_res[win]))
            near = np.r_[a_res[max(i - hw - 20, 1) : max(i - hw, 1)], a_res[i + hw + 1 : i + hw + 21]]
            local = float(np.median(near)) if near.size >= 8 else floor
            ratio = float(a_res[j] / local) if local > 0 else 0.0
            marks.append({**ln, "residual_ratio": ratio, "measured_V": float(a_meas[i])})
            if ratio > c:
                found.append(
                    {
                        "test": "envelope",
                        "band": ln["name"],
                        "frequency_Hz": float(f[j]),
                        "ratio": ratio,
                        "where": f"residual envelope line at {ln['name']} ({f[j]:.2f} Hz), {ratio:.1f}x the "
                        f"envelope floor around it (threshold {c:.1f}x)",
                    }
                )
        found.sort(key=lambda d: -d["ratio"])
        summary = {"band_Hz": list(band), "threshold_ratio": c, "floor_V": floor, "lines": marks}
        keep = f <= min(band[1] - band[0], 8 * kin["frequencies"]["bpfo_Hz"])
        arrays = {
            "freq_Hz": f[keep],
            "measured_V": a_meas[keep],
            "residual_V": a_res[keep],
            "line_Hz": np.array([ln["frequency_Hz"] for ln in lines]),
        }
        return Judgement(summary, arrays, found[:5])


def name_frequency(f_Hz: float, freqs: dict, tol: float = 0.01) -> str:
    """A frequency in the bearing's terms: 'k x shaft', 'k x BPFO', ... within ``tol`` (relative), else ''."""
    best = None
    for name, key in (("shaft", "shaft_Hz"), ("FTF", "ftf_Hz"), ("BPFO", "bpfo_Hz"), ("BPFI", "bpfi_Hz"), ("BSF", "bsf_Hz")):
        f0 = freqs[key]
        k = round(f_Hz / f0)
        if 1 <= k <= 40:
            err = abs(f_Hz - k * f0) / f_Hz
            if err <= tol and (best is None or err < best[0] or (err == best[0] and k < best[2])):
                best = (err, name, k)
    if best is None:
        return ""
    _, name, k = best
    return f"{k} x {name}" if k > 1 else name


@dataclass(frozen=True)
class Orders:
    """The residual's spectral peaks (the engine's spectrum test) named in shaft and bearing orders."""

    key: str = "orders"
    tests_of: object = None

    def judge(self, fit, problem, settings) -> Judgement:
        rec = problem.record
        kin = fitted_kinematics(fit.values, rec)
        t = residual_tests(fit.whitened, rec.input, rec.dt_s, settings, problem.segments, rec.time_s)
        rows = []
        for pk in t.peaks[:10]:
            f = pk["frequency_Hz"]
            rows.append(
                {
                    "frequency_Hz": f,
                    "shaft_order": f / kin["shaft_Hz"],
                    "roller_pass_order": f / kin["frequencies"]["bpfo_Hz"],
                    "named": name_frequency(f, kin["frequencies"]),
                    "excess_dB": pk["excess_dB"],
                }
            )
        found = [
            {
                "test": "orders",
                "frequency_Hz": r["frequency_Hz"],
                "where": f"residual line at {r['frequency_Hz']:.2f} Hz = {r['shaft_order']:.3f} x shaft "
                f"({r['named'] or 'no bearing frequency'}), {r['excess_dB']:.1f} dB above the floor",
            }
            for r in rows[:3]
        ]
        return Judgement({"peaks": rows, "shaft_Hz": kin["shaft_Hz"], **kin["frequencies"]}, {}, found)


REPRESENTATIONS = (PerPassage(), SynchronousAverage(), EnvelopeBands(), Orders())
__all__ = ["REPRESENTATIONS", "chain"]
