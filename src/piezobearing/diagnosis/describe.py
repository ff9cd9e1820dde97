"""What lies outside the catalogue, described: how the error is laid out in time, in the input, and in the data.

The residual tests (:mod:`~piezobearing.diagnosis.residual_tests`) say
*whether* structure remains and *where* (frequencies, lags, windows). These
descriptions say *what it looks like*, each with the physical mechanisms it
suggests (the subject's words, :data:`MECHANISMS` by default):

- ``trend``: does the whitened residual's energy grow or fall along the
  record? Spearman's rank correlation of the window energies (the window
  test's windows) with time; a trend at p < ``ALPHA`` is described with the
  ratio of the last third's mean energy to the first third's.
- ``input_dependence``: does the error grow with the size of the input?
  Spearman's rank correlation, over the segments (impulses, passages), of the
  whitened residual's mean square in each segment with the input's
  excursion at its anchor (the press's peak force).
- ``stuck``: samples stuck at one level (:func:`stuck_runs`): runs of at
  least ``MIN_STUCK`` equal consecutive samples at the record's extremes, the
  signature of a clipped input range or a saturated amplifier. Reported by
  ``piezobearing validate`` and in every diagnosis; clipped samples cannot
  be fitted by any model of the catalogue.

These descriptions do not change the verdict (the four residual tests keep
their designed 1% false-alarm rate); they are computed on every record and
read where the verdict is ``unexplained``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import spearmanr

from .noise import runs
from .record import Segments

#: Significance of a description (trend, input dependence) [-].
ALPHA = 0.01
#: Fewest equal consecutive samples that count as stuck [-].
MIN_STUCK = 3

#: Mechanisms each description suggests (a subject may pass its own).
MECHANISMS = {
    "trend_up": "an offset between the two channels' clocks that grows (clock drift), a gain drifting with "
    "temperature or warm-up, a resistance or capacitance changing with humidity or temperature",
    "trend_down": "a transient at the start (settling, a charge left from handling), a gain or leakage "
    "settling after switch-on",
    "input_up": "a nonlinearity of the sensor or of the reference (stress-dependent sensitivity, contact "
    "stiffening, a force sensor's linearity error), saturation or clipping at the largest inputs",
    "input_down": "a dead zone or friction at small inputs (a preload not yet taken up), a quantised reference",
    "stuck": "the DAQ's input range exceeded (clipping) or an amplifier saturated; samples stuck at one level "
    "carry no information and no model of the catalogue can fit them: widen the input range or lower the gain",
}


def stuck_runs(x: np.ndarray, min_run: int = MIN_STUCK, time_s: np.ndarray | None = None) -> dict:
    """Runs of >= ``min_run`` equal consecutive samples at the record's maximum or minimum.

    Returns ``{"n_runs", "n_samples", "levels", "runs"}`` with every run as
    ``{"level", "start_s", "stop_s", "samples"}`` (``start_s`` etc. in samples
    when ``time_s`` is None). A smooth noisy signal repeats a value only by
    quantisation, and never for long at its extremes.
    """
    x = np.asarray(x, dtype=float)
    t = np.arange(x.size, dtype=float) if time_s is None else np.asarray(time_s, dtype=float)
    out = []
    if x.size >= min_run:
        same = np.concatenate([[False], x[1:] == x[:-1]])
        span = max(float(np.ptp(x)), 1e-300)
        for a, b in runs(same):  # a run of k True marks k + 1 equal samples, starting at a - 1
            a0, k = a - 1, b - a + 1
            level = float(x[a0])
            at_edge = min(abs(level - x.max()), abs(level - x.min())) <= 1e-9 * span
            if k >= min_run and at_edge:
                out.append(
                    {"level": level, "start_s": float(t[a0]), "stop_s": float(t[b - 1]), "samples": int(k)}
                )
    return {
        "n_runs": len(out),
        "n_samples": int(sum(r["samples"] for r in out)),
        "levels": sorted({r["level"] for r in out}),
        "runs": out,
    }


def _rank(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    if x.size < 5 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return float("nan"), 1.0
    r, p = spearmanr(x, y)
    return float(r), float(p)


def trend(window_t0_s: np.ndarray, window_ratio: np.ndarray) -> dict:
    """Spearman correlation of the window energies with time, and the last third's mean over the first's."""
    t, e = np.asarray(window_t0_s, dtype=float), np.asarray(window_ratio, dtype=float)
    ok = np.isfinite(e)  # a window of filled samples only is not judged (NaN)
    t, e = t[ok], e[ok]
    r, p = _rank(t, e)
    k = max(e.size // 3, 1)
    ratio = float(np.mean(e[-k:]) / max(np.mean(e[:k]), 1e-300)) if e.size else float("nan")
    sig = p < ALPHA
    d = {"spearman_r": r, "p": p, "significant": bool(sig), "last_over_first_third": ratio}
    if sig:
        up = r > 0
        d["where"] = (
            f"the error {'grows' if up else 'falls'} along the record: the residual's energy in the last third "
            f"is {ratio:.2f}x that in the first (Spearman r = {r:+.2f}, p = {p:.1g})"
        )
        d["mechanisms"] = MECHANISMS["trend_up" if up else "trend_down"]
    return d


def input_dependence(
    whitened: np.ndarray, input_: np.ndarray | None, segments: Segments, input_name: str
) -> dict:
    """Spearman correlation over the segments of the whitened mean square with the input's excursion at the anchor."""
    if input_ is None or len(segments) < 5:
        return {"significant": False, "n_segments": len(segments)}
    rest = float(np.median(input_))
    size = np.abs(np.asarray(input_)[np.asarray(segments.anchor_index, dtype=int)] - rest)
    e = np.array([np.mean(whitened[a:b] ** 2) for a, b in zip(segments.start, segments.stop, strict=True)])
    r, p = _rank(size, e)
    sig = p < ALPHA
    d = {"spearman_r": r, "p": p, "significant": bool(sig), "n_segments": len(segments)}
    if sig:
        lo, hi = np.argsort(size)[: max(len(size) // 3, 1)], np.argsort(size)[-max(len(size) // 3, 1) :]
        ratio = float(np.mean(e[hi]) / max(np.mean(e[lo]), 1e-300))
        d["largest_over_smallest_third"] = ratio
        up = r > 0
        d["where"] = (
            f"the error {'grows' if up else 'falls'} with the {input_name}: in the {segments.name}s of the largest "
            f"third of {input_name}s the residual's energy is {ratio:.2f}x that of the smallest third "
            f"(Spearman r = {r:+.2f} over {len(size)} {segments.name}s, p = {p:.1g})"
        )
        d["mechanisms"] = MECHANISMS["input_up" if up else "input_down"]
    return d


def describe(
    whitened: np.ndarray,
    window_t0_s: np.ndarray,
    window_ratio: np.ndarray,
    input_: np.ndarray | None,
    input_name: str,
    segments: Segments,
    voltage_V: np.ndarray,
    time_s: np.ndarray,
) -> dict:
    """The JSON block ``outside_catalogue``: trend, input dependence, stuck (clipped) voltage samples."""
    stuck = stuck_runs(voltage_V, time_s=time_s)
    if stuck["n_runs"]:
        lv = ", ".join(f"{v:.6g} V" for v in stuck["levels"])
        stuck["where"] = (
            f"the voltage is stuck at {lv} in {stuck['n_runs']} run(s) of {MIN_STUCK} or more equal samples "
            f"({stuck['n_samples']} samples, the first at t = {stuck['runs'][0]['start_s']:.3f} s): clipped"
        )
        stuck["mechanisms"] = MECHANISMS["stuck"]
    return {
        "trend": trend(window_t0_s, window_ratio),
        "input_dependence": input_dependence(whitened, input_, segments, input_name),
        "stuck": stuck,
    }
