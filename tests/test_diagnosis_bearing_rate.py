"""The rate the running-bearing model is held at: a record sampled faster than
``bearing_diagnosis.max_model_rate_Hz`` is averaged in blocks of whole samples (the DAQ model's own box filter),
stamped at each block's centre; a record at or below it is held as it is."""

import numpy as np
import pytest

from piezobearing import config as cfg
from piezobearing.diagnosis.bearing.subject import model_rate
from piezobearing.io import BearingRecord, average_blocks


def record(sample_rate_Hz: float, duration_s: float = 0.5, clip_at: int | None = None) -> BearingRecord:
    t = np.arange(int(round(sample_rate_Hz * duration_s))) / sample_rate_Hz
    clipped = np.zeros(t.size, dtype=bool)
    if clip_at is not None:
        clipped[clip_at] = True
    return BearingRecord(t, np.sin(2 * np.pi * 70.0 * t), None, "synthetic", (), clipped)


def test_default_keeps_the_papers_clock_and_averages_25600_in_blocks_of_ten():
    max_rate = cfg.load()["bearing_diagnosis"]["max_model_rate_Hz"]
    same, info = model_rate(record(2550.0), max_rate)
    assert info["block_samples"] == 1 and same.time_s.size == 1275 and "held as it is" in info["reason"]
    fast, info = model_rate(record(25600.0, clip_at=17), max_rate)
    assert info["block_samples"] == 10 and info["model_rate_Hz"] == pytest.approx(2560.0, rel=1e-12)
    assert "averaged in blocks of 10 samples to 2560 Hz" in info["reason"]
    # each block's mean over its samples, stamped at the block's centre (each sample the mean of its own window)
    raw = record(25600.0)
    assert fast.time_s[3] == pytest.approx(raw.time_s[30:40].mean(), rel=1e-12)
    assert fast.voltage_V[3] == pytest.approx(raw.voltage_V[30:40].mean(), rel=1e-12)
    assert fast.clipped[1] and fast.clipped.sum() == 1


def test_no_block_below_the_slowest_rate():
    """3000 Hz over 2600 Hz: two samples would give 1500 Hz, below the 2 kHz a record needs; held as it is, said."""
    rec, info = model_rate(record(3000.0), 2600.0)
    assert info["block_samples"] == 1 and rec.time_s.size == 1500
    assert "the model may miss the shaft's resonance" in info["reason"]


def test_average_blocks_drops_the_incomplete_last_block():
    rec = average_blocks(record(25600.0, 0.50004), 10)
    assert rec.time_s.size == 12801 // 10
