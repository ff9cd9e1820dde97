"""The record a forward model runs on, and the stretches a report names findings by.

A :class:`Record` holds the time axis and, when the subject has one, the
measured input channel that drives its forward model (the reference force of
a calibration). The measured output (the sensor voltage) travels beside it:
the engine judges models of a voltage.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


class UniformClock:
    """Length and step of a uniform clock ``time_s`` (a field of the dataclass that inherits this)."""

    time_s: np.ndarray

    @property
    def n(self) -> int:
        return int(self.time_s.size)

    @property
    def dt_s(self) -> float:
        return float((self.time_s[-1] - self.time_s[0]) / (self.n - 1))


@dataclass(frozen=True, eq=False)
class Record(UniformClock):
    """Time axis and measured input of one record.

    Attributes
    ----------
    time_s : ndarray
        Uniform sample times [s].
    input : ndarray or None
        The measured input channel the forward model is driven by, on the
        same clock (None when the subject has no measured input) [unit of the input].
    input_name : str
        What the input is, for the report and keys (``force``).
    input_unit : str
        The input's unit suffix (``N``): keys such as ``force_N`` and ``force_noise_N``.
    """

    time_s: np.ndarray
    input: np.ndarray | None = None
    input_name: str = "input"
    input_unit: str = ""
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def input_key(self) -> str:
        """The input's name with its unit (``force_N``)."""
        return f"{self.input_name}_{self.input_unit}" if self.input_unit else self.input_name

    @property
    def sample_rate_Hz(self) -> float:
        return 1.0 / self.dt_s

    @property
    def freq_Hz(self) -> np.ndarray:
        """Frequencies of the real DFT of a record of this length [Hz]."""
        if "freq" not in self._cache:
            self._cache["freq"] = np.fft.rfftfreq(self.n, self.dt_s)
        return self._cache["freq"]


@dataclass(frozen=True)
class Segments:
    """Stretches of a record that findings are named by (the impulses of a calibration, roller passages).

    Attributes
    ----------
    name : str
        What one stretch is (``impulse``); JSON keys and arrays use it (``n_impulses``, ``impulse_start``).
    anchor : str
        The instant of each stretch times are given from (``force_peak``: key ``from_force_peak_s``).
    start, stop : ndarray of int
        Sample index range [start, stop) of each stretch.
    anchor_index : ndarray of int
        Sample index of each stretch's anchor.
    """

    name: str
    anchor: str
    start: np.ndarray
    stop: np.ndarray
    anchor_index: np.ndarray

    def __len__(self) -> int:
        return int(np.asarray(self.start).size)

    @classmethod
    def none(cls, name: str = "segment", anchor: str = "start") -> "Segments":
        e = np.zeros(0, dtype=int)
        return cls(name, anchor, e, e, e)

    def containing(self, index: int) -> int | None:
        """Position of the stretch holding sample ``index`` (the first, if several), or None."""
        for j in range(len(self)):
            if self.start[j] <= index < self.stop[j]:
                return j
        return None
