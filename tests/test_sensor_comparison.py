"""The embedded sensor against the housing accelerometer: the paper's case through both chains to one detector."""

from __future__ import annotations

import copy

import pytest

from piezobearing.chain import signals as sout
from piezobearing.comparison import rig as cmp


def _rig(config: dict, level: float, floor: bool = False) -> dict:
    """The paper's case on a short record and a coarse housing mesh (modes to 2.5 x 12.8 kHz), one seed; the
    ideal bearing (``floor`` False: no roughness, waviness or unbalance) or the comparison's floor."""
    cfg = copy.deepcopy(config)
    if not floor:
        cfg["sensor_comparison"]["bearing_floor"].update(roughness_rms_m=0.0, waviness_orders=[],
                                                         waviness_amplitudes_m=[], unbalance_kg_m=0.0)
    cfg["bearing"].update(duration_s=0.5, settle_s=0.02)
    cfg["housing"]["mesh_level"] = 0.35
    cfg["signals"]["sensor_fem_correction"] = False
    cfg["sensor_comparison"]["n_seeds"] = 1
    cfg["base_motion"]["level"] = level
    return cfg


@pytest.fixture(scope="module")
def at_rest(paper_config):
    cfg = _rig(paper_config, 0.0)
    circuit = sout.sensor_circuit(cfg, {"resistance_ohm": 50.0e6})  # the paper's DAQ input resistance
    return cmp.compare(cfg, circuit, None)


@pytest.fixture(scope="module")
def at_rest_floor(paper_config):
    """The frame at rest with the comparison's floor: three healthy and one faulty realisation."""
    cfg = _rig(paper_config, 0.0, floor=True)
    circuit = sout.sensor_circuit(cfg, {"resistance_ohm": 50.0e6})
    return cmp.compare(cfg, circuit, None, n_seeds=(3, 1))


def test_model_step_must_serve_the_faster_daq(paper_config):
    cfg = copy.deepcopy(paper_config)
    cfg["sensor_comparison"]["time_step_s"] = 1e-4
    with pytest.raises(ValueError, match="sensor_comparison.time_step_s"):
        cmp.ComparisonSettings.from_config(cfg)


@pytest.mark.slow
def test_paper_case_at_rest_both_sensors(at_rest):
    """The 0.9 mm outer-race groove at 1000 rpm, the machine frame at rest.

    The embedded sensor detects it: its outer-race family passes the envelope detector's threshold by tens
    of dB (the groove lies over the sensor: each roller's drop unloads the sensor by newtons, against a DAQ
    noise of microvolts on a volt-per-newton sensor).

    The accelerometer detects it too, and the physics says why: with the frame at rest nothing masks the
    housing's response to the roller's impacts but the transducer's own noise (about 1.4 ug/sqrt(Hz)) and its
    DAQ's (0.3 uV/sqrt(Hz), 3 ug/sqrt(Hz) at 100 mV/g); the impacts ring the housing's modes at the cap by
    tens of mg. Without surroundings the long transmission path costs the accelerometer amplitude, not
    detectability.

    Neither sensor's healthy record is free of lines at BPFO: the rollers' passage is periodic at BPFO itself
    (the load zone's varying compliance; over the sensor, each roller's load), so the envelope detector's
    nominal false-alarm probability does not hold on this rig and the healthy bearing is called too.
    """
    pzt, accel = at_rest["sensors"]["pzt"], at_rest["sensors"]["accelerometer"]
    assert at_rest["disturbance_rms_m_per_s2"] == 0.0
    assert pzt["detection"]["families"]["outer_race"]["detected"]
    assert pzt["margin_dB"] > 20.0
    assert accel["detection"]["families"]["outer_race"]["detected"]
    assert accel["margin_dB"] > 10.0
    # nothing clipped: the PZT's DAQ range (sensor_comparison.pzt_range_V) holds its peaks
    assert pzt["clipped_samples"] == 0 and accel["clipped_samples"] == 0, pzt["levels"]
    # the roller passage at BPFO: the healthy bearing's outer-race family passes too
    assert pzt["detection_healthy"]["families"]["outer_race"]["margin_dB"] > 0.0
    assert accel["detection_healthy"]["families"]["outer_race"]["margin_dB"] > 0.0
    # the PZT's voltage is volts, the accelerometer's millivolts: absolute noise per channel keeps the gains
    assert pzt["levels"]["faulty"]["clean_rms_V"] > 100 * accel["levels"]["faulty"]["clean_rms_V"]


@pytest.mark.slow
def test_floor_makes_every_seed_a_new_bearing(at_rest, at_rest_floor):
    """With the healthy bearing's floor on, every seed at rest is another bearing (its surfaces drawn anew):
    the healthy statistic spreads over the seeds, where the ideal bearing's at rest is one rig run; and the
    random floor between the roller passage's lines lowers the healthy outer-race family's margin below the
    ideal bearing's, on both sensors."""
    assert at_rest_floor["n_healthy_seeds"] == 3 and at_rest_floor["n_faulty_seeds"] == 1
    for s in cmp.SENSORS:
        healthy = at_rest_floor["sensors"][s]["healthy_margin_dB_per_seed"]
        assert len(set(healthy)) == 3, healthy
        ideal = at_rest["sensors"][s]["detection_healthy"]["families"]["outer_race"]["margin_dB"]
        assert max(healthy) < ideal, (s, healthy, ideal)
