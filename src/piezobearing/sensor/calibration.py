"""The PZT disk on its cable: the RC model of Eq. 5-6 and the calibration analysis.

The disk (charge constant d33, free permittivity eps33^T, area A, height h)
has the capacitance Cp = eps33^T A / h. In parallel with the cable
capacitance Cc and the DAQ input resistance R it obeys

.. math::  C \\dot V + V / R = d_{33} \\dot F, \\qquad C = C_p + C_c,

Eq. 5 of the paper with the cable added to Cp, as the paper does in Sec.
III-B. Compression is counted positive and produces a positive voltage (the
paper's minus sign is the electrode polarity). The sinusoidal steady state is

.. math::  H(j\\omega) = \\frac{d_{33}}{C} \\frac{j\\omega\\tau}{1 + j\\omega\\tau},\\quad \\tau = RC.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.special import stdtrit

from ..fitting.least_squares import FitResult, fit
from ..fitting.params import Param
from .materials import epsilon_0, pzt_from_config


@dataclass(frozen=True)
class SensorCircuit:
    """PZT disk, cable and DAQ input.

    Parameters
    ----------
    pzt_diameter_m, pzt_height_m : float
        Disk diameter and height [m].
    d33_C_per_N : float
        Charge constant d33 [C/N].
    eps33_T_rel : float
        Relative permittivity at constant stress eps33^T / eps0 [-].
    cable_length_m : float
        Coaxial cable length [m].
    cable_capacitance_F_per_m : float
        Cable capacitance per length [F/m].
    resistance_ohm : float
        DAQ input resistance R [Ohm].
    extra_capacitance_F : float
        Capacitance across the electrodes beyond Cp and the cable [F].
    daq_capacitance_F : float
        Input capacitance of the DAQ [F].
    """

    pzt_diameter_m: float = 4.7e-3
    pzt_height_m: float = 3.4e-3
    d33_C_per_N: float = 400e-12
    eps33_T_rel: float = 1800.0
    cable_length_m: float = 2.0
    cable_capacitance_F_per_m: float = 90e-12
    resistance_ohm: float = 50e6
    extra_capacitance_F: float = 0.0
    daq_capacitance_F: float = 0.0

    @property
    def area_m2(self) -> float:
        return np.pi * self.pzt_diameter_m**2 / 4

    @property
    def pzt_capacitance_F(self) -> float:
        """Cp = eps33^T A / h [F]."""
        return self.eps33_T_rel * epsilon_0 * self.area_m2 / self.pzt_height_m

    @property
    def cable_capacitance_F(self) -> float:
        return self.cable_capacitance_F_per_m * self.cable_length_m

    @property
    def capacitance_F(self) -> float:
        """Total C = Cp + Ccable + extra + C_DAQ [F]."""
        return self.pzt_capacitance_F + self.cable_capacitance_F + self.extra_capacitance_F + self.daq_capacitance_F

    @property
    def tau_s(self) -> float:
        """Time constant R C [s]."""
        return self.resistance_ohm * self.capacitance_F

    @property
    def open_circuit_gain_V_per_N(self) -> float:
        """d33 / C: the high-frequency (open-circuit) sensitivity [V/N]."""
        return self.d33_C_per_N / self.capacitance_F

    @property
    def free_disk_gain_V_per_N(self) -> float:
        """Eq. 3 without cable: h d33 / (eps33^T A) = d33 / Cp [V/N]."""
        return self.d33_C_per_N / self.pzt_capacitance_F

    def with_resistance(self, resistance_ohm: float) -> "SensorCircuit":
        return replace(self, resistance_ohm=float(resistance_ohm))

    @classmethod
    def from_config(cls, sensor: dict, resistance_ohm: float) -> "SensorCircuit":
        """Build from the validated ``sensor`` config section (d33 and eps33^T: the configured
        ``material``'s, or the section's own values where they are not null)."""
        pzt = pzt_from_config(sensor)
        return cls(
            pzt_diameter_m=sensor["pzt_diameter_m"],
            pzt_height_m=sensor["pzt_height_m"],
            d33_C_per_N=pzt.d33_C_per_N,
            eps33_T_rel=pzt.eps33_T_rel,
            cable_length_m=sensor["cable_length_m"],
            cable_capacitance_F_per_m=sensor["cable_capacitance_F_per_m"],
            resistance_ohm=float(resistance_ohm),
            daq_capacitance_F=sensor.get("daq_capacitance_F", 0.0),
        )


def design_resistance_ohm(sensor: dict, fitted_ohm: float) -> float:
    """The DAQ input resistance of the ``sensor`` config section, or the calibration's fitted R where it is null [Ohm]."""
    r = sensor.get("daq_resistance_ohm")
    return float(fitted_ohm) if r is None else float(r)


def rc_voltage(force_N: np.ndarray, dt_s: float, gain_V_per_N: float, tau_s: float,
               period_s: float | None = None) -> np.ndarray:
    """Voltage of the first-order high-pass tau dV/dt + V = gain tau dF/dt.

    Exact for a force that is piecewise linear between samples: on each step
    dF/dt is the constant slope s_k and

    .. math::  V_{k+1} = a V_k + g\\,\\frac{\\tau}{h}(1 - a)(F_{k+1} - F_k),\\quad a = e^{-h/\\tau}.

    Parameters
    ----------
    force_N : numpy.ndarray
        Force at the instants k dt [N].
    dt_s, gain_V_per_N, tau_s : float
        Step [s], open-circuit gain [V/N] and time constant [s].
    period_s : float or None
        None: the circuit starts at rest (V_0 = 0) with the force at F_0, as a
        circuit switched on with the record (the calibration's hammer records).
        A period T [s] (at most the record's span (n - 1) dt): the circuit
        starts in its periodic steady state for the force's first period
        repeated, as the sensor of a machine that has run for a long time (a
        running bearing, T its roller-passage period): see
        :func:`periodic_start_V`. The start is exact for a force of period T;
        for a nearly periodic one it is wrong by the change of the force's
        exponentially weighted mean over one period, and that error decays as
        exp(-t / tau).
    """
    f = np.asarray(force_N, dtype=float)
    a = np.exp(-dt_s / tau_s)
    b = gain_V_per_N * (tau_s / dt_s) * (-np.expm1(-dt_s / tau_s))
    df = np.diff(f, prepend=f[0])
    # Imported here: scipy.signal costs about a second of import, which every job that imports this module
    # for its circuit types (most of the workflow's) would pay.
    from scipy.signal import lfilter

    v = lfilter([b], [1.0, -a], df)
    if period_s is not None:
        v = v + periodic_start_V(f, v, dt_s, gain_V_per_N, tau_s, period_s) * np.exp(-dt_s * np.arange(f.size) / tau_s)
    return v


def periodic_start_V(force_N: np.ndarray, v_rest_V: np.ndarray, dt_s: float, gain_V_per_N: float, tau_s: float,
                     period_s: float) -> float:
    """The voltage V_0 [V] at which the RC circuit starts in its periodic steady state for the force's first period.

    Write V = g (F - u) with tau du/dt + u = F: u is the circuit's state (the
    charge the resistor has not yet drained, in newtons of force). The response
    started at rest, ``v_rest_V`` (u(0) = F_0), plus the free decay
    c exp(-t/tau) is the response from u(0) = F_0 - c/g. The state repeats after
    one period, u(T) = u(0), when

    .. math::  c = g\\,\\frac{F_0 - u_{rest}(T)}{1 - e^{-T/\\tau}},\\quad u_{rest}(T) = F(T) - V_{rest}(T)/g,

    with V_rest(T) and F(T) evaluated exactly inside the step that holds T (the
    force is linear there). It is the state, not the voltage, that must repeat:
    where the force does not repeat exactly (slip jitter, another defect's
    period, a speed ramp) F(T) differs from F_0 and V jumps with it, u does not.
    """
    n = force_N.size
    if not 0.0 < period_s <= (n - 1) * dt_s * (1 + 1e-12):
        raise ValueError(f"rc_voltage: period_s = {period_s} s must lie in (0, {(n - 1) * dt_s:.6g}] s (the "
                         "record's span); lengthen the record or start at rest (period_s None)")
    m = min(int(np.floor(period_s / dt_s + 1e-9)), n - 1)
    phi = max(period_s / dt_s - m, 0.0)
    slope = force_N[m + 1] - force_N[m] if m < n - 1 else 0.0  # F rises by `slope` over the step after t_m
    q = np.exp(-phi * dt_s / tau_s)
    v_t = v_rest_V[m] * q + gain_V_per_N * (tau_s / dt_s) * (-np.expm1(-phi * dt_s / tau_s)) * slope
    u_t = force_N[m] + phi * slope - v_t / gain_V_per_N
    return float(gain_V_per_N * (force_N[0] - u_t) / -np.expm1(-period_s / tau_s))


def circuit_voltage(force_N: np.ndarray, dt_s: float, circuit: SensorCircuit) -> np.ndarray:
    """Voltage of ``circuit`` for the sampled force (Eq. 6, exact discretisation)."""
    return rc_voltage(force_N, dt_s, circuit.open_circuit_gain_V_per_N, circuit.tau_s)


def frequency_response(frequency_Hz: np.ndarray, circuit: SensorCircuit) -> np.ndarray:
    """Complex V/F [V/N] of the RC model at the given frequencies."""
    jwt = 2j * np.pi * np.asarray(frequency_Hz, dtype=float) * circuit.tau_s
    return circuit.open_circuit_gain_V_per_N * jwt / (1 + jwt)


def rc_response(freq_Hz: np.ndarray, dt_s: float, gain: float, tau_s: float, zi: np.ndarray | None = None) -> np.ndarray:
    """Frequency response of :func:`rc_voltage` as a discrete filter.

    The exact discretisation is V_k = a V_{k-1} + b (F_k - F_{k-1}) with
    a = exp(-dt/tau), b = gain (tau/dt)(1 - a), so

    .. math::  G(z) = b \\frac{1 - z^{-1}}{1 - a z^{-1}},\\quad z = e^{j 2\\pi f\\,dt}.

    It tends to the continuous gain * j w tau / (1 + j w tau) for f dt << 1. ``zi``: z^-1 at ``freq_Hz``
    (:func:`unit_delay`) when the caller keeps it for its frequency grid (a fit asks at every R).
    """
    a = np.exp(-dt_s / tau_s)
    b = gain * (tau_s / dt_s) * (-np.expm1(-dt_s / tau_s))
    zi = unit_delay(freq_Hz, dt_s) if zi is None else zi
    return b * (1 - zi) / (1 - a * zi)


def unit_delay(freq_Hz: np.ndarray, dt_s: float) -> np.ndarray:
    """z^-1 = exp(-j 2 pi f dt) at the frequencies [-] (complex)."""
    return np.exp(-2j * np.pi * np.asarray(freq_Hz, dtype=float) * dt_s)


# --------------------------------------------------------------------------- impulses


@dataclass(frozen=True)
class Impulse:
    """One detected impulse: sample indices of its window and its peaks."""

    start: int
    stop: int
    force_peak_index: int
    voltage_peak_index: int
    force_peak_N: float
    voltage_peak_V: float

    @property
    def sensitivity_V_per_N(self) -> float:
        return self.voltage_peak_V / self.force_peak_N


def detect_impulses(
    force_N: np.ndarray,
    voltage_V: np.ndarray,
    dt_s: float,
    min_prominence_fraction: float = 0.2,
    min_separation_s: float = 0.5,
) -> list[Impulse]:
    """Find the impulses of a calibration record.

    Force peaks must rise above ``min_prominence_fraction`` of the record's
    force range and lie ``min_separation_s`` apart. Each impulse's window runs
    from the midpoint after the previous peak to the midpoint before the next,
    and its voltage peak is the voltage maximum in that window.
    """
    f = np.asarray(force_N, dtype=float)
    v = np.asarray(voltage_V, dtype=float)
    span = float(np.ptp(f))
    if span <= 0:
        return []
    from scipy.signal import find_peaks  # imported here: see rc_voltage

    peaks, _ = find_peaks(
        f, prominence=min_prominence_fraction * span, distance=max(1, int(round(min_separation_s / dt_s)))
    )
    bounds = np.concatenate([[0], (peaks[:-1] + peaks[1:]) // 2, [len(f)]])
    out = []
    for k, p in enumerate(peaks):
        lo, hi = int(bounds[k]), int(bounds[k + 1])
        iv = lo + int(np.argmax(v[lo:hi]))
        out.append(Impulse(lo, hi, int(p), iv, float(f[p]), float(v[iv])))
    return out


def polarity_votes(
    force_N: np.ndarray, voltage_V: np.ndarray, dt_s: float, impulses: list[Impulse], circuit: SensorCircuit
) -> int:
    """How many impulses have a voltage anti-correlated with the RC model's prediction.

    The prediction is :func:`circuit_voltage` of the measured force with the
    nominal ``circuit``; whatever R it assumes, the predicted and the true
    voltage correlate positively within an impulse when the leads are right
    (compression positive), so a record where most impulses correlate
    negatively has its polarity inverted. Comparing the positive and negative
    swings instead would misfire on presses released faster than applied.
    """
    v = np.asarray(voltage_V, dtype=float)
    pred = circuit_voltage(force_N, dt_s, circuit)
    n = 0
    for imp in impulses:
        a, b = pred[imp.start : imp.stop], v[imp.start : imp.stop]
        if np.dot(a - a.mean(), b - b.mean()) < 0:
            n += 1
    return n


def sensitivity_summary(impulses: list[Impulse], time_s: np.ndarray) -> dict:
    """Mean, standard deviation and 95% interval of the per-impulse sensitivity [V/N].

    The interval is the Student-t interval of the mean.
    """
    s = np.array([imp.sensitivity_V_per_N for imp in impulses])
    n = len(s)
    mean = float(s.mean())
    std = float(s.std(ddof=1)) if n > 1 else float("nan")
    # stdtrit is scipy.stats.t.ppf's own function (bit for bit), without scipy.stats' import.
    half = float(stdtrit(n - 1, 0.975) * std / np.sqrt(n)) if n > 1 else float("nan")
    return {
        "sensitivity_V_per_N": mean,
        "sensitivity_std_V_per_N": std,
        "sensitivity_ci95_V_per_N": [mean - half, mean + half],
        "n_impulses": n,
        "impulses": [
            {
                "time_force_peak_s": float(time_s[imp.force_peak_index]),
                "force_peak_N": imp.force_peak_N,
                "voltage_peak_V": imp.voltage_peak_V,
                "sensitivity_V_per_N": imp.sensitivity_V_per_N,
            }
            for imp in impulses
        ],
    }


# --------------------------------------------------------------------------- resistance fit


def resistance_param(initial_ohm: float) -> Param:
    """The free parameter R of the baseline model, fitted on a log scale (1 kOhm to 1 TOhm)."""
    return Param("resistance_ohm", float(initial_ohm), 1e3, 1e12, log=True)


def fit_resistance(
    force_N: np.ndarray,
    voltage_V: np.ndarray,
    dt_s: float,
    circuit: SensorCircuit,
    initial_ohm: float,
    left_out: np.ndarray | None = None,
) -> FitResult:
    """Fit R of Eq. 6 to a measured voltage by nonlinear least squares.

    The voltage is simulated from the measured force with
    :func:`circuit_voltage` (all other constants fixed at ``circuit``) and R
    is varied on a log scale. Samples marked in ``left_out`` (bool, one per
    sample: filled across a gap of the recorded clock, or within the model's
    memory of one) are not in the residual, so the fit, its ``n_data`` and
    its intervals count measured samples only. Returns a
    :class:`piezobearing.fitting.least_squares.FitResult`.
    """
    v = np.asarray(voltage_V, dtype=float)
    keep = slice(None) if left_out is None else ~np.asarray(left_out, dtype=bool)

    def residual(p: dict) -> np.ndarray:
        return (circuit_voltage(force_N, dt_s, circuit.with_resistance(p["resistance_ohm"])) - v)[keep]

    return fit(residual, [resistance_param(initial_ohm)])
