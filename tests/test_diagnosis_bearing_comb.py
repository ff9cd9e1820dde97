"""The lines rule's comb at the shaft's orders (``answer.shaft_comb``): lines locked to the shaft are a comb, a
moving defect's forest of lines (whole, half and quarter orders) is not, nor is one line or white noise.

Residuals of 0.5 s at 2550 Hz (the feasibility records' length: 2 Hz bins, a shaft order 8.3 bins) built from
sines of known frequency in white noise; the threshold is the lines rule's for 16 carriers at alpha 0.0025.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from piezobearing.diagnosis.bearing.answer import lines_threshold_dB, shaft_comb

FS, N, SHAFT = 2550.0, 1275, 1000.0 / 60.0
#: A line's amplitude over the noise's standard deviation: about 23 dB above the floor in one Hann-windowed bin.
AMPLITUDE = 1.0


def diagnosis(residual: np.ndarray):
    """The parts of a diagnosis and its fit that :func:`shaft_comb` reads."""
    kin = {"shaft_Hz": SHAFT, "bpfo_Hz": 4.25 * SHAFT, "bpfi_Hz": 6.75 * SHAFT, "bsf_Hz": 2.0 * SHAFT,
           "ftf_Hz": 0.39 * SHAFT}
    rig = SimpleNamespace(shaft_speed_Hz=SHAFT, tach_Hz=None, frequencies=lambda shaft, slip: kin)
    record = SimpleNamespace(rig=rig, dt_s=1.0 / FS, n=N)
    d = SimpleNamespace(record=record, voltage_V=residual, problem=SimpleNamespace(
        floor=SimpleNamespace(voltage_noise_V=1.0)))
    fit = SimpleNamespace(values={}, residual_V=residual, model_V=np.zeros(N))
    return d, fit


def record(orders, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(N) / FS
    x = rng.standard_normal(N)
    for k, m in enumerate(orders):
        x += AMPLITUDE * np.sin(2 * np.pi * m * SHAFT * t + 0.7 * k)
    return x


def comb_orders(residual, own_Hz=()) -> list[int]:
    d, fit = diagnosis(residual)
    return sorted(int(round(f / SHAFT)) for f in shaft_comb(d, fit, lines_threshold_dB(0.0025, 16), list(own_Hz)))


def test_lines_at_the_shafts_orders_are_a_comb():
    assert comb_orders(record(range(20, 41))) == list(range(20, 41))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_moving_defects_forest_of_lines_is_not_a_comb(seed):
    """Lines at every quarter order (an inner race's k BPFI + j f_r with BPFI = 6.75 f_r): the half orders stand
    beside the whole ones, so no order stands alone."""
    assert comb_orders(record(np.arange(20, 40.01, 0.25), seed)) == []


def test_one_line_at_an_order_or_white_noise_is_not_a_comb():
    assert comb_orders(record([30])) == []
    assert comb_orders(record([30, 60])) == []
    for seed in range(5):
        assert comb_orders(record([], seed)) == []


def test_a_faults_own_lines_are_no_neighbours():
    """An inner race's carrier at a whole order with its sidebands -/+ f_r beside it is not a comb: the sidebands
    are the fault's own lines."""
    own = [27 * SHAFT, 26 * SHAFT, 28 * SHAFT]
    assert comb_orders(record([26, 27, 28]), own) == []
    assert comb_orders(record([26, 27, 28])) == [26, 27, 28]
