"""The public API: its docstrings' examples run as doctests (each a real run of the function), and its errors.

The examples' own numbers are their assertions: read_record reads a CSV back at its rate; calibrate finds
the default synthetic record's sensitivity and R in their physical ranges; simulate runs the bearing chain
on a short record; detect finds an SKF 6205's outer-race defect; diagnose lowers the default record's misfit.
"""

from __future__ import annotations

import doctest

import numpy as np
import pytest

import piezobearing
from piezobearing import api

FAST = ("read_record", "detect")
SLOW = ("calibrate", "simulate", "diagnose")


def _run_example(name: str) -> None:
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    (test,) = [t for t in finder.find(getattr(api, name), f"piezobearing.{name}", globs=dict(vars(api)))]
    assert test.examples, f"{name} has no example"
    runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0 and result.attempted == len(test.examples), name


@pytest.mark.parametrize("name", FAST)
def test_fast_examples_run(name):
    _run_example(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", SLOW)
def test_slow_examples_run(name):
    _run_example(name)


def test_the_package_exports_the_api():
    for name in FAST + SLOW:
        assert getattr(piezobearing, name) is getattr(api, name)
        assert getattr(api, name).__doc__.count(">>>") >= 2


def test_bad_inputs_stop_with_one_line():
    with pytest.raises(ValueError, match="kind 'tacho' unknown"):
        piezobearing.read_record("x.csv", kind="tacho")
    with pytest.raises(ValueError, match="shaft_speed_rpm"):
        piezobearing.detect(np.zeros(1000), 12000.0, "SKF 6205", 0.0)
    with pytest.raises(ValueError, match="two 1-D arrays"):
        piezobearing.calibrate(np.zeros(10), np.zeros(11), 1000.0)


def test_read_record_returns_one_record_type(tmp_path):
    """Every kind is a Record: the same rate, time axis, length and named columns, consistent with each other."""
    import pandas as pd

    t = np.arange(4000) / 2000.0
    force = 50 * np.exp(-((t - 1.0) / 0.1) ** 2)
    pd.DataFrame({"time_s": t, "force_N": force, "voltage_V": 0.02 * force + 0.001 * np.sin(9 * t)}).to_csv(
        tmp_path / "cal.csv", index=False)
    pd.DataFrame({"time_s": t, "voltage_V": np.sin(2 * np.pi * 70.8 * t),
                  "speed_rpm": np.full(t.size, 1500.0)}).to_csv(tmp_path / "run.csv", index=False)
    records = {
        "vibration": piezobearing.read_record(tmp_path / "run.csv", channel="voltage_V"),
        "bearing": piezobearing.read_record(tmp_path / "run.csv", kind="bearing"),
        "calibration": piezobearing.read_record(tmp_path / "cal.csv", kind="calibration"),
    }
    columns = {"vibration": {"voltage_V"}, "bearing": {"voltage_V", "speed_rpm"},
               "calibration": {"force_N", "voltage_V"}}
    for kind, record in records.items():
        assert isinstance(record, piezobearing.Record), kind
        assert record.sample_rate_Hz == pytest.approx(2000.0, rel=1e-9), kind
        assert record.duration_s == pytest.approx(2.0, rel=1e-9), kind
        np.testing.assert_allclose(record.time_s - record.time_s[0], t, rtol=0, atol=1e-9)
        assert set(record.data) == columns[kind], kind
        assert all(v.shape == t.shape for v in record.data.values()), kind
    np.testing.assert_allclose(records["vibration"].data["voltage_V"], records["bearing"].voltage_V, rtol=1e-12)
