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
    filled : ndarray of bool or None
        Samples that were not measured but filled (interpolated across a gap of the recorded clock)
        (None: all measured). The fit's likelihood, the noise floor and the residual tests leave them
        out, together with the samples within ``memory_s`` of them (:attr:`kept`).
    memory_s : (float, float)
        How long before and after a filled sample the model's output still depends on it [s]: the
        subject's model memory (a calibration: its fit's input filter before, the settling of the
        circuit after), so that the interpolated input's error does not count as misfit.
    """

    time_s: np.ndarray
    input: np.ndarray | None = None
    input_name: str = "input"
    input_unit: str = ""
    _cache: dict = field(default_factory=dict, compare=False, repr=False)
    filled: np.ndarray | None = field(default=None, compare=False, repr=False)
    memory_s: tuple[float, float] = (0.0, 0.0)

    @property
    def input_key(self) -> str:
        """The input's name with its unit (``force_N``)."""
        return f"{self.input_name}_{self.input_unit}" if self.input_unit else self.input_name

    @property
    def sample_rate_Hz(self) -> float:
        return 1.0 / self.dt_s

    @property
    def left_out(self) -> np.ndarray | None:
        """The filled samples and those within ``memory_s`` of them (None when every sample was measured)."""
        if self.filled is None or not np.any(self.filled):
            return None
        if "left_out" not in self._cache:
            f = np.asarray(self.filled, dtype=bool)
            before, after = (int(round(m / self.dt_s)) for m in self.memory_s)
            d = np.diff(np.concatenate([[0], f.astype(np.int8), [0]]))
            out = f.copy()
            for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True):
                out[max(a - before, 0) : min(b + after, f.size)] = True
            self._cache["left_out"] = out
        return self._cache["left_out"]

    @property
    def kept(self) -> np.ndarray | None:
        """0.0 at the samples :attr:`left_out`, 1.0 elsewhere (None when every sample was measured) [-]."""
        lo = self.left_out
        return None if lo is None else (~lo).astype(float)

    @property
    def n_measured(self) -> int:
        """Samples the likelihood counts (``n`` less those :attr:`left_out`): its number of data."""
        lo = self.left_out
        return self.n if lo is None else int(self.n - np.count_nonzero(lo))

    def filled_gaps(self) -> dict:
        """Where samples were filled and for how long: ``{"n_samples", "gaps": [{start_s, stop_s,
        duration_s, samples}], "treatment"}`` (JSON and report; ``n_samples`` 0 when none were)."""
        n = 0 if self.filled is None else int(np.count_nonzero(self.filled))
        out: dict = {"n_samples": n, "gaps": []}
        if n:
            d = np.diff(np.concatenate([[0], np.asarray(self.filled, dtype=np.int8), [0]]))
            for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True):
                out["gaps"].append(
                    {
                        "start_s": float(self.time_s[a]),
                        "stop_s": float(self.time_s[b - 1]),
                        "duration_s": float((b - a) * self.dt_s),
                        "samples": int(b - a),
                    }
                )
            out["memory_s"] = list(self.memory_s)
            out["n_left_out"] = self.n - self.n_measured
            out["treatment"] = (
                "filled by linear interpolation when the record was resampled to a uniform clock; left out of "
                f"the fit's likelihood, the noise floor and the residual tests, with {self.memory_s[0] * 1e3:.3g} ms "
                f"before and {self.memory_s[1] * 1e3:.3g} ms after each gap where the model still depends on "
                f"the filled input ({out['n_left_out']} samples in all)"
            )
        return out

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
