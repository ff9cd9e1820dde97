"""The envelope detector's null distribution: closed-form line densities cached by window size against the
interpolated densities computed per line (``baselines/null_interpolated.py``), CPU seconds and thresholds.

Two measurements. Speed: 20 healthy-machine records (2 s at 12 kHz, shaft 29-30 Hz, ``null_calibration.healthy_machine``,
as tests/test_envelope_detector.py draws them), each judged at the false-alarm probabilities 0.05 and 1e-3, every cache
cleared before each method. Accuracy: the thresholds of four families at five probabilities by each method,
against the closed form on a grid four times finer (same span). Writes results/benchmarks/envelope_null.json.
Usage: python benchmarks/bench_envelope_null.py
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from baselines import null_interpolated  # benchmarks/ is the script's folder, first on sys.path

from piezobearing.bearing.kinematics import RollingBearing
from piezobearing.signals.detectors import envelope as envelope_detector
from piezobearing.signals.detectors.null_calibration import healthy_machine

FS = 12_000.0  # the records' sampling rate [Hz]

BEARING = RollingBearing.from_designation("SKF 6205")
N_RECORDS = 20
#: Families of the comparison: window sizes of each line, the floors' Gamma shape.
FAMILIES = [((5,), 20.0), ((3, 3, 3), 5.2), ((4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9), 5.2),
            ((2, 2, 3, 3, 4, 4, 5, 5, 6), 12.5)]
PROBABILITIES = (0.05, 1.7e-2, 3.3e-4, 1.7e-4, 1e-5)


def clear_caches() -> None:
    envelope_detector.null_distribution.cache_clear()
    envelope_detector._line_ratio_density.cache_clear()


def records() -> list[tuple[np.ndarray, dict]]:
    out = []
    for j in range(N_RECORDS):
        rng = np.random.default_rng([17, j])
        shaft = rng.uniform(29.0, 30.0)
        x = healthy_machine(rng, shaft, 2.0, FS)
        out.append((x, BEARING.kinematics(shaft * rng.uniform(0.99, 1.01)).to_dict()))
    return out


def judge_all(data: list[tuple[np.ndarray, dict]]) -> tuple[float, list[str]]:
    """CPU seconds to judge every record at both probabilities, and the calls."""
    settings = (envelope_detector.Settings(false_alarm_probability=0.05), envelope_detector.Settings())
    clear_caches()
    start = time.process_time()
    calls = [envelope_detector.detect(x, FS, kin, s).fault_type for x, kin in data for s in settings]
    return time.process_time() - start, calls


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n")[0]).parse_args()  # no options: --help only
    data = records()
    new_s, new_calls = judge_all(data)
    closed_form = envelope_detector._null_on_grid
    envelope_detector._null_on_grid = null_interpolated.null_on_grid
    try:
        old_s, old_calls = judge_all(data)
        clear_caches()
        old_nulls = [envelope_detector.null_distribution(b, s) for b, s in FAMILIES]
    finally:
        envelope_detector._null_on_grid = closed_form
    clear_caches()
    accuracy = []
    for (bins, shape), old in zip(FAMILIES, old_nulls, strict=True):
        new = envelope_detector.null_distribution(bins, shape)
        fine = closed_form(bins, shape, float(new.x[-1]), 4 * (new.x.size - 1) + 1)
        for alpha in PROBABILITIES:
            if alpha <= max(old.survival[-1], new.survival[-1], fine.survival[-1]):
                continue  # beyond a grid's reach (the union bound's threshold)
            reference = fine.threshold(alpha)
            accuracy.append({"window_bins": list(bins), "floor_shape": shape, "probability": alpha,
                             "interpolated_rel_error": old.threshold(alpha) / reference - 1.0,
                             "closed_form_rel_error": new.threshold(alpha) / reference - 1.0})
    result = {
        "records": N_RECORDS,
        "detections": len(new_calls),
        "interpolated_cpu_s": old_s,
        "closed_form_cpu_s": new_s,
        "ratio": old_s / new_s,
        "same_calls": old_calls == new_calls,
        "largest_interpolated_rel_error": max(abs(a["interpolated_rel_error"]) for a in accuracy),
        "largest_closed_form_rel_error": max(abs(a["closed_form_rel_error"]) for a in accuracy),
        "thresholds": accuracy,
    }
    out = Path("results/benchmarks/envelope_null.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"interpolated {old_s:.2f} CPU s, closed form {new_s:.2f} CPU s, ratio {old_s / new_s:.2f}; "
          f"same calls: {result['same_calls']}; largest threshold error against a 4x finer grid: "
          f"{result['largest_interpolated_rel_error']:.1e} interpolated, "
          f"{result['largest_closed_form_rel_error']:.1e} closed form -> {out}")


if __name__ == "__main__":
    main()
