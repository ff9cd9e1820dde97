"""Shared fixtures: the validated configs and synthetic calibration records."""

from __future__ import annotations

import os

import pytest

from piezobearing import config as cfg
from piezobearing.stages.calibration import nominal_circuit
from piezobearing.synthesis import PressProtocol, synthesize

os.environ.setdefault("OMP_NUM_THREADS", "1")


@pytest.fixture(scope="session")
def paper_config() -> dict:
    return cfg.load()


@pytest.fixture(scope="session")
def ci_config() -> dict:
    return cfg.load(cfg.CONFIG_DIR / "ci.yaml")


@pytest.fixture(scope="session")
def paper_record(paper_config):
    """The default synthetic calibration record (25 s, 1 kHz, 13 presses, R = 50 MOhm)."""
    c = paper_config
    return synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"])
