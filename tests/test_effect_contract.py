"""The contract every calibration effect meets (CONTRIBUTING.md, "Adding an effect")."""

from __future__ import annotations

import numpy as np
import pytest

from piezobearing.diagnosis.calibration.effects import CATALOGUE, ForceRecord
from piezobearing.fitting.units import UNITS

PROBE = ForceRecord(np.arange(2000) / 1000.0, np.zeros(2000))


@pytest.mark.parametrize("name", [*CATALOGUE, "_template"])
def test_every_effect_has_a_plausible_example_within_its_bounds(name):
    """Each effect's ``example`` (the one home of the size the tests, the error-rate study and hide-and-find
    hide) names its own parameters, lies within their bounds, is not the neutral value, and says why."""
    e = _effects()[name]
    params = {p.name: p for p in e.params(PROBE)}
    assert e.example and set(e.example) <= set(params)
    assert len(e.example_reason) > 20
    for k, v in e.example.items():
        p = params[k]
        assert p.lower <= v <= p.upper, (k, v)
        assert any(k.endswith(u.suffix) for u in UNITS), k
    assert any(v != params[k].value for k, v in e.example.items())


def _effects():
    from piezobearing.diagnosis.calibration.effects import _template

    return {**dict(CATALOGUE), "_template": _template.EFFECT}


@pytest.fixture(scope="module")
def press_record(ci_config):
    from piezobearing.diagnosis.calibration.presses import PressProtocol, synthesize
    from piezobearing.stages.calibration import nominal_circuit

    m = synthesize(PressProtocol.from_config(ci_config["synthesis"]), nominal_circuit(ci_config), ci_config["seed"])
    return ForceRecord(m.time_s, m.force_N), nominal_circuit(ci_config)


def test_the_template_is_a_complete_effect_left_out_of_the_catalogue():
    """CONTRIBUTING points to effects/_template.py: a working effect (fixture_mode) not in the catalogue."""
    from pathlib import Path

    from piezobearing.diagnosis.calibration.effects import _template

    assert _template.EFFECT.name == "fixture_mode" and "fixture_mode" not in CATALOGUE
    assert "_template.py" in Path(__file__).resolve().parents[1].joinpath("CONTRIBUTING.md").read_text()
    for part in ("Physics", "Model", "Parameters"):
        assert part in _template.__doc__


@pytest.mark.parametrize("key", list(_effects()))
def test_effect_hooks_keep_the_contract(key, press_record):
    """Every effect (the template too): neutral at its declared values (the model's voltage unchanged), a force
    hook that keeps the padded size, a noise-path factor that is a scalar or one per DFT bin (0 .. Nyquist),
    an example that changes the voltage, and starts of at most three dicts naming its own parameters."""
    from piezobearing.diagnosis.calibration.effects.base import StartContext
    from piezobearing.diagnosis.calibration.model import PAD, ForwardModel

    e = _effects()[key]
    record, circuit = press_record
    base = ForwardModel(circuit)
    model = base.with_effect(e)
    v0 = base.simulate(base.defaults(record), record)
    neutral = model.defaults(record)
    # neutral to 1e-4 of the peak: a log parameter declares its lower bound (a 10 us lag: 7e-5, a 1 uHz corner)
    assert np.allclose(model.simulate(neutral, record), v0, rtol=0, atol=1e-4 * np.max(np.abs(v0)))
    values = {**neutral, **e.example}
    assert not np.allclose(model.simulate(values, record), v0, rtol=0, atol=1e-3 * np.max(np.abs(v0)))
    f = np.concatenate([np.full(PAD, record.force_N[0]), record.force_N])
    assert e.force(f, values, record).shape == f.shape
    g = np.asarray(e.response(values, record))
    assert g.ndim == 0 or g.shape == record.freq_Hz.shape
    names = {p.name for p in e.params(record)}
    assert all(any(n.endswith(u.suffix) for u in UNITS) for n in names)
    starts = e.starts(StartContext(record, v0 + 1e-3 * np.sin(np.arange(record.n)), v0, neutral))
    assert 1 <= len(starts) <= 3 and all(set(s) <= names for s in starts)


# --------------------------------------------------------------------------- the running bearing's effects


@pytest.fixture(scope="module")
def rig_record(ci_config, ci_influence):
    """A 0.5 s healthy running-bearing record of the CI rig (its influence line solved once) as the engine sees it."""
    import copy

    from piezobearing.diagnosis.bearing.subject import SUBJECT, synthesise

    c = copy.deepcopy(ci_config)
    c["bearing_diagnosis"].update(synthetic_duration_s=0.5, synthetic_sample_rate_Hz=2550.0)
    influence = ci_influence
    return SUBJECT.problem((synthesise(c, 11, [], influence), influence), c)


def _bearing_effects():
    from piezobearing.diagnosis.bearing.effects import CATALOGUE as BEARING

    return dict(BEARING)


@pytest.mark.parametrize("name", list(_bearing_effects()))
def test_every_bearing_effect_has_a_plausible_example_that_changes_the_record(name, rig_record):
    """The running bearing's effects keep the same part of the contract: an ``example`` naming their own
    parameters within bounds, not neutral, with its reason, that changes the model's voltage (the values
    tests/test_diagnosis_bearing.py hides)."""
    e = _bearing_effects()[name]
    record = rig_record.record
    params = {p.name: p for p in e.params(record)}
    assert e.example and set(e.example) <= set(params)
    assert len(e.example_reason) > 20
    for k, v in e.example.items():
        assert params[k].lower <= v <= params[k].upper, (k, v)
        assert any(k.endswith(u.suffix) for u in UNITS), k
    assert any(v != params[k].value for k, v in e.example.items())
    model = rig_record.baseline
    ride = {}
    for r in e.rides_on:  # the effects it acts through, at their own examples, on both sides
        model = model.with_effect(_bearing_effects()[r])
        ride.update(_bearing_effects()[r].example)
    model = model.with_effect(e)
    neutral = {**rig_record.baseline_start, **model.defaults(record), **ride}
    v0 = model.simulate(neutral, record)
    v1 = model.simulate({**neutral, **e.example}, record)
    assert np.sqrt(np.mean((v1 - v0) ** 2)) > 1e-3 * np.sqrt(np.mean(v0**2))
