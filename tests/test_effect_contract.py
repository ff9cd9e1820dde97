"""The contract every calibration effect meets (CONTRIBUTING.md, "Adding an effect")."""

from __future__ import annotations

import numpy as np
import pytest

from piezobearing.diagnosis.calibration.effects import CATALOGUE, ForceRecord
from piezobearing.diagnosis.units import UNITS

PROBE = ForceRecord(np.arange(2000) / 1000.0, np.zeros(2000))


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_every_effect_has_a_plausible_example_within_its_bounds(name):
    """Each effect's ``example`` (the one home of the size the tests, the error-rate study and hide-and-find
    hide) names its own parameters, lies within their bounds, is not the neutral value, and says why."""
    e = CATALOGUE[name]
    params = {p.name: p for p in e.params(PROBE)}
    assert e.example and set(e.example) <= set(params)
    assert len(e.example_reason) > 20
    for k, v in e.example.items():
        p = params[k]
        assert p.lower <= v <= p.upper, (k, v)
        assert any(k.endswith(u.suffix) for u in UNITS), k
    assert any(v != params[k].value for k, v in e.example.items())
