r"""The embedded sensor from force to voltage: one model for the workflow, the diagnosis and its records.

.. math::  \tau \dot V + V = k\, G\, \tau \dot F, \qquad G = \frac{d_{33}}{C},\ \tau = R C

The RC model of Eq. 6 (:func:`~piezobearing.sensor.calibration.rc_voltage`,
exact for a force linear between samples) with its gain times the sensor
FEM's correction k: the median of |H_FEM| / |H_RC| over the FEM's
frequencies up to the record's Nyquist frequency (the FEM is flat there: its
first resonance is near 120 kHz, so one number carries it). k comes from

- the workflow's sensor FEM (``results/sensor/harmonic.csv``, rule
  ``sensor_harmonic``) where it is at hand;
- else the paper sensor's FEM response shipped with the package
  (``sensor/paper_sensor_fem.csv``: 0.938 up to 1275 Hz, 0.940 up to 12.8 kHz);
- k = 1 (the RC model alone) with ``signals.sensor_fem_correction: false``.

:attr:`SensorModel.source` says which. The DAQ samples the voltage on its
own clock (:func:`piezobearing.signals.daq.sample`: the identity where the
force is already box-averaged on the record's clock, as in the diagnosis).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .calibration import SensorCircuit, frequency_response, rc_voltage

#: The paper sensor's |H_FEM| / |H_RC| against frequency, shipped with the package (see its header).
PAPER_SENSOR_FEM = Path(__file__).with_name("paper_sensor_fem.csv")


def fem_ratio(frequency_Hz: np.ndarray, fem_over_rc: np.ndarray, f_max_Hz: float) -> dict:
    """The constant correction of the RC model in a band: the median of |H_FEM| / |H_RC| up to ``f_max_Hz``.

    Where fewer than two FEM frequencies lie below ``f_max_Hz``, the two lowest. Returns ``factor`` (the
    median), its spread ``min``, ``max`` over those frequencies (a frequency-dependent correction shows as a
    wide spread), their range ``frequencies_Hz`` and count ``n_frequencies``.
    """
    f = np.asarray(frequency_Hz, dtype=float)
    ratio = np.abs(np.asarray(fem_over_rc, dtype=float))
    sel = f <= f_max_Hz
    if sel.sum() < 2:
        sel = np.zeros(f.size, dtype=bool)
        sel[np.argsort(f)[:2]] = True
    r = ratio[sel]
    return {
        "factor": float(np.median(r)),
        "min": float(r.min()),
        "max": float(r.max()),
        "frequencies_Hz": [float(f[sel].min()), float(f[sel].max())],
        "n_frequencies": int(sel.sum()),
    }


@dataclass(frozen=True)
class SensorModel:
    """The sensor circuit and the FEM's correction of its gain.

    Parameters
    ----------
    circuit : SensorCircuit
        PZT, cable and DAQ input (R, C).
    fem_factor : float
        |H_FEM| / |H_RC| in the record's band (1: the RC model alone) [-].
    source : str
        Where ``fem_factor`` comes from (the workflow's FEM, the paper sensor's, or none), in words.
    correction : dict or None
        :func:`fem_ratio`'s record of the factor (None for the RC model alone).
    """

    circuit: SensorCircuit
    fem_factor: float
    source: str
    correction: dict | None = None

    @property
    def gain_V_per_N(self) -> float:
        """d33 / C times the FEM's correction [V/N]."""
        return self.circuit.open_circuit_gain_V_per_N * self.fem_factor

    @property
    def tau_s(self) -> float:
        """R C [s]."""
        return self.circuit.tau_s

    def voltage(self, force_N: np.ndarray, dt_s: float, period_s: float | None = None) -> np.ndarray:
        """The sensor's voltage [V] for a force [N] linear between samples dt_s apart [s]: from rest, or
        (``period_s``) in the periodic steady state of the force's first period
        (:func:`~piezobearing.sensor.calibration.rc_voltage`)."""
        return rc_voltage(force_N, dt_s, self.gain_V_per_N, self.tau_s, period_s)

    def describe(self) -> str:
        """One line: the model and its numbers."""
        return (f"RC model (R = {self.circuit.resistance_ohm:.4g} ohm, C = {self.circuit.capacitance_F:.4g} F, "
                f"d33/C = {self.circuit.open_circuit_gain_V_per_N:.4g} V/N) x FEM correction "
                f"{self.fem_factor:.4g}: {self.source}")

    def to_dict(self) -> dict:
        """JSON-ready: the circuit's numbers, the factor, its source and record."""
        return {
            "model": "rc" if self.correction is None else "rc_times_fem",
            "resistance_ohm": self.circuit.resistance_ohm,
            "capacitance_F": self.circuit.capacitance_F,
            "tau_s": self.tau_s,
            "open_circuit_gain_V_per_N": self.circuit.open_circuit_gain_V_per_N,
            "fem_factor": self.fem_factor,
            "gain_V_per_N": self.gain_V_per_N,
            "source": self.source,
            "fem_correction": self.correction,
        }


def read_paper_sensor_fem() -> tuple[np.ndarray, np.ndarray]:
    """The shipped paper sensor's frequencies [Hz] and |H_FEM| / |H_RC| [-]."""
    d = pd.read_csv(PAPER_SENSOR_FEM, comment="#")
    return d["frequency_Hz"].to_numpy(), d["fem_over_rc"].to_numpy()


def sensor_model(
    config: dict,
    circuit: SensorCircuit,
    nyquist_Hz: float,
    harmonic: tuple[np.ndarray, np.ndarray] | None = None,
    harmonic_source: str = "results/sensor/harmonic.csv",
) -> SensorModel:
    """The sensor model of ``config`` for a record whose Nyquist frequency is ``nyquist_Hz``.

    ``harmonic``: the sensor FEM's (frequency [Hz], |V/F| [V/N]) of this configuration (the workflow's rule
    sensor_harmonic, read from ``harmonic_source``; a third item, where given, is the file it was read from and
    stands for ``harmonic_source``); without it the paper sensor's shipped response. With
    ``signals.sensor_fem_correction: false`` the RC model alone.
    """
    if not config["signals"]["sensor_fem_correction"]:
        return SensorModel(circuit, 1.0, "RC model alone (signals.sensor_fem_correction: false)")
    if harmonic is not None:
        if len(harmonic) > 2:
            harmonic_source = str(harmonic[2])
        f, h = (np.asarray(x, dtype=float) for x in harmonic[:2])
        corr = fem_ratio(f, np.abs(h) / np.abs(frequency_response(f, circuit)), nyquist_Hz)
        return SensorModel(circuit, corr["factor"], f"this configuration's sensor FEM ({harmonic_source})", corr)
    f, ratio = read_paper_sensor_fem()
    corr = fem_ratio(f, ratio, nyquist_Hz)
    return SensorModel(circuit, corr["factor"], f"the paper sensor's FEM, shipped ({PAPER_SENSOR_FEM.name}): "
                       "no sensor FEM response of this configuration was given", corr)
