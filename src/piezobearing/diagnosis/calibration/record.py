"""The calibration record: reader and validator, and the record the forward model runs on.

A calibration record holds time, the reference force under the press and
the PZT voltage, in any format :func:`piezobearing.io.read_measurement`
reads (``calibration.channels`` and ``wav_full_scale_V`` name the channels). Beyond the
file checks, :func:`read_record` needs at least two impulses and a voltage
that swings positive under compression (an inverted polarity is reported,
never fitted). The forward model runs on a :class:`ForceRecord`: the engine's
:class:`~piezobearing.diagnosis.record.Record` whose input is the recorded force.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...io import Measurement, MeasurementError, check_channels, read_measurement
from ...sensor import calibration as cal
from ..noise import QUIET_BEFORE_S
from ..record import Record, Segments

#: A voltage that correlates less than this with the model's prediction from the measured force, for
#: every resistance of FLAT_RESISTANCE_FACTORS x calibration.initial_resistance_ohm, carries no sensor
#: signal (a disconnected channel: noise only). A good synthetic record reaches 0.99, a record whose
#: signal is 1/1000 of its 2 mV noise 0.17 (measured on the CI record).
FLAT_CORRELATION = 0.3
FLAT_RESISTANCE_FACTORS = np.array([0.1, 1.0, 10.0, 100.0])


@dataclass(frozen=True, eq=False)
class ForceRecord(Record):
    """Time axis and recorded reference force: ``ForceRecord(time_s, force_N)``.

    Attributes
    ----------
    time_s : ndarray
        Uniform sample times [s].
    input : ndarray
        Recorded reference force [N] (also :attr:`force_N`).
    """

    input_name: str = "force"
    input_unit: str = "N"

    @property
    def force_N(self) -> np.ndarray:
        """Recorded reference force [N]."""
        return self.input


def gap_memory_s(quiet_settle_s: float, tau_s: float) -> tuple[float, float]:
    """How long before and after a filled sample a calibration model still depends on it [s].

    Before: the fit's low-passed force spreads an interpolated force over its filter's length (50 ms,
    :data:`piezobearing.diagnosis.noise.QUIET_BEFORE_S`, as the floor's quiet mask); after: the circuit
    remembers it for ``quiet_settle_s`` + 5 RC time constants ``tau_s`` (the floor's settling after a press).
    """
    return (QUIET_BEFORE_S, quiet_settle_s + 5.0 * tau_s)


def left_out_samples(
    m: Measurement, quiet_settle_s: float, tau_s: float
) -> np.ndarray | None:
    """The samples of ``m`` that no fit of it counts: those filled across gaps of its clock and those within
    :func:`gap_memory_s` of them (the diagnosis's ``Record.left_out``); None when every sample was measured."""
    if m.filled is None:
        return None
    rec = ForceRecord(m.time_s, m.force_N, filled=m.filled, memory_s=gap_memory_s(quiet_settle_s, tau_s))
    return rec.left_out


def read_record(path: str, config: dict) -> tuple[Measurement, list[cal.Impulse]]:
    """Read and check a calibration record and detect its impulses (one-line MeasurementError otherwise).

    Uses the config sections ``calibration`` (resampling, impulse detection,
    the initial R of the polarity check) and ``sensor`` (the nominal circuit).
    """
    c = config["calibration"]
    m = read_measurement(
        path,
        resample_to_uniform=c["resample_to_uniform"],
        channels=c.get("channels"),
        wav_full_scale_V=c.get("wav_full_scale_V"),
    )
    return m, check_record(m, config, path)


def check_record(m: Measurement, config: dict, path) -> list[cal.Impulse]:
    """The checks of :func:`read_record` beyond the file's own on a record already read (``path`` names it in
    errors): no dead, constant or clipped channel, at least two impulses, a voltage with the sensor's signal
    and its polarity. Returns the impulses."""
    c = config["calibration"]
    check_channels(m)  # dead, constant or clipped
    imps = cal.detect_impulses(
        m.force_N, m.voltage_V, m.dt_s, c["min_prominence_fraction"], c["min_separation_s"]
    )
    if len(imps) < 2:
        raise MeasurementError(
            f"{path}: column force_N: {len(imps)} impulse(s) found, at least 2 are needed; record more presses "
            "or lower calibration.min_prominence_fraction / min_separation_s"
        )
    nominal = cal.SensorCircuit.from_config(config["sensor"], c["initial_resistance_ohm"])
    corr = max(
        abs(
            float(
                np.corrcoef(
                    cal.circuit_voltage(m.force_N - m.force_N[0], m.dt_s, nominal.with_resistance(r)),
                    m.voltage_V,
                )[0, 1]
            )
        )
        for r in c["initial_resistance_ohm"] * FLAT_RESISTANCE_FACTORS
    )
    if not corr >= FLAT_CORRELATION:
        raise MeasurementError(
            f"{path}: column voltage_V: flat, no sensor signal (correlation {corr:.2f} at best with the "
            "voltage the sensor model predicts from force_N, for any resistance from 0.1 to 100 times "
            "calibration.initial_resistance_ohm); check the sensor cable, the DAQ channel and its gain"
        )
    neg = cal.polarity_votes(m.force_N, m.voltage_V, m.dt_s, imps, nominal)
    if neg > len(imps) / 2:
        raise MeasurementError(
            f"{path}: column voltage_V: polarity inverted (in {neg} of {len(imps)} impulses the voltage "
            "is anti-correlated with the model's); swap the electrode leads or negate voltage_V in a copy of the file"
        )
    return imps


def impulse_segments(impulses: list[cal.Impulse]) -> Segments:
    """The impulses as the engine's segments, anchored at their force peaks."""
    return Segments(
        "impulse",
        "force_peak",
        np.array([i.start for i in impulses], dtype=int),
        np.array([i.stop for i in impulses], dtype=int),
        np.array([i.force_peak_index for i in impulses], dtype=int),
    )
