"""A synthetic stand-in for the paper's calibration experiment (Sec. III-B, Fig. 5).

A hand presses a rod onto the PZT disk, which sits on a reference force
sensor: n impulses over the record, each a smooth press and release,
with amplitudes, durations and timing that vary from press to press. The
PZT disk on its cable into the DAQ turns the true force into a voltage
through the RC model (:mod:`piezobearing.sensor.calibration`); both channels then
get white sensor noise. Every draw comes from one seeded generator.

Why the pulses look as they do: the impulse-peak sensitivity of a
first-order high-pass depends on how fast the force rises relative to
tau = RC. With the paper's constants (C = Cp + Ccable = 81.3 + 180 pF,
R = 50 MOhm, tau = 13.1 ms, d33/C = 1.53 V/N), a half-cosine press of rise
time T_r >> tau has its steepest slope pi F / (2 T_r), and the voltage peaks
near gain * tau * slope, so the peak ratio is about (d33/C) tau pi / (2 T_r);
the paper's 74.4 mV/N then needs T_r of about 0.42 s. The default rise times
(0.36-0.50 s) were chosen for that reason: the synthetic sensitivity lands
near the paper's number by construction, not as a prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...io import Measurement
from ...sensor.calibration import SensorCircuit, circuit_voltage
from .synthesis import hidden_voltage


@dataclass(frozen=True)
class PressProtocol:
    """How the hand presses: counts, ranges [min, max] and noise levels (SI units)."""

    duration_s: float
    sample_rate_Hz: float
    n_impulses: int
    peak_force_N: tuple[float, float]
    rise_time_s: tuple[float, float]
    fall_time_s: tuple[float, float]
    timing_jitter_s: float
    force_noise_N: float
    voltage_noise_V: float

    @classmethod
    def from_config(cls, syn: dict) -> "PressProtocol":
        return cls(
            duration_s=syn["duration_s"],
            sample_rate_Hz=syn["sample_rate_Hz"],
            n_impulses=syn["n_impulses"],
            peak_force_N=tuple(syn["peak_force_N"]),
            rise_time_s=tuple(syn["rise_time_s"]),
            fall_time_s=tuple(syn["fall_time_s"]),
            timing_jitter_s=syn["timing_jitter_s"],
            force_noise_N=syn["force_noise_N"],
            voltage_noise_V=syn["voltage_noise_V"],
        )


def press_pulse(t: np.ndarray, t_peak: float, peak_N: float, rise_s: float, fall_s: float) -> np.ndarray:
    """One press: half-cosine rise over ``rise_s`` to ``peak_N`` at ``t_peak``, half-cosine release.

    Smooth (continuous slope at both ends and at the peak), zero outside
    [t_peak - rise_s, t_peak + fall_s].
    """
    f = np.zeros_like(t)
    up = (t >= t_peak - rise_s) & (t < t_peak)
    down = (t >= t_peak) & (t <= t_peak + fall_s)
    f[up] = 0.5 * (1 - np.cos(np.pi * (t[up] - (t_peak - rise_s)) / rise_s))
    f[down] = 0.5 * (1 + np.cos(np.pi * (t[down] - t_peak) / fall_s))
    return peak_N * f


def press_force(protocol: PressProtocol, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Time axis and true (noise-free) force of the whole record."""
    p = protocol
    n_samples = int(round(p.duration_s * p.sample_rate_Hz)) + 1
    t = np.arange(n_samples) / p.sample_rate_Hz
    spacing = p.duration_s / p.n_impulses
    centres = spacing * (np.arange(p.n_impulses) + 0.5)
    force = np.zeros_like(t)
    for c in centres:
        rise = rng.uniform(*p.rise_time_s)
        fall = rng.uniform(*p.fall_time_s)
        t_peak = c + rng.uniform(-p.timing_jitter_s, p.timing_jitter_s)
        t_peak = float(np.clip(t_peak, rise, p.duration_s - fall))
        force += press_pulse(t, t_peak, rng.uniform(*p.peak_force_N), rise, fall)
    return t, force


def synthesize(
    protocol: PressProtocol,
    circuit: SensorCircuit,
    seed: int,
    hidden_effects: list[dict] | None = None,
) -> Measurement:
    """A synthetic calibration record: true force through the circuit, then noise on both channels.

    ``hidden_effects`` ([{name, params}], as ``synthesis.hidden_effects``)
    puts catalogue effects into the voltage: it is then the forward model
    of the diagnosis (:func:`piezobearing.diagnosis.calibration.synthesis.hidden_voltage`,
    the RC baseline plus those effects) driven by the noise-free force. Parameters not given take
    the effect's neutral default.
    """
    rng = np.random.default_rng(seed)
    t, force = press_force(protocol, rng)
    force_meas = force + rng.normal(0.0, protocol.force_noise_N, t.size)
    if hidden_effects:
        voltage = hidden_voltage(circuit, list(hidden_effects), t, force_meas, force)
    else:
        voltage = circuit_voltage(force, 1.0 / protocol.sample_rate_Hz, circuit)
    voltage_meas = voltage + rng.normal(0.0, protocol.voltage_noise_V, t.size)
    return Measurement(t, force_meas, voltage_meas, "synthetic")
