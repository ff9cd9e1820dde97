"""Kinematics of any rolling bearing: CWRU's published multiples, designations, the rig file, slip."""

from __future__ import annotations

import pytest
import yaml

from piezobearing.bearing.geometry import BearingGeometry, kinematic_frequencies
from piezobearing.bearing.kinematics import (
    BearingError,
    Kinematics,
    RollingBearing,
    designation_sources,
    designations,
)

#: CWRU Bearing Data Center's fault frequencies as multiples of the shaft rate.
CWRU_MULTIPLES = {
    "SKF 6203": {"bpfi": 4.9469, "bpfo": 3.0530, "ftf": 0.3817, "2bsf": 3.9874},
    "SKF 6205": {"bpfi": 5.4152, "bpfo": 3.5848, "ftf": 0.39828, "2bsf": 4.7135},
}


@pytest.mark.parametrize("designation", sorted(CWRU_MULTIPLES))
def test_fault_frequencies_are_cwru_published_multiples_of_the_shaft_rate(designation):
    got = RollingBearing.from_designation(designation).multiples()
    for name, published in CWRU_MULTIPLES[designation].items():
        # CWRU prints 4-5 significant digits from the inch geometry: agreement to the last printed digit
        assert got[name] == pytest.approx(published, rel=2e-4), name


def test_the_papers_bearing_has_its_bpfo_at_1000_rpm():
    kin = RollingBearing.from_designation("N305 ECP").kinematics(1000 / 60)
    assert kin.bpfo_Hz == pytest.approx(70.83, abs=0.01)


@pytest.mark.parametrize("name", ["SKF 6205", "skf 6205", "6205", "SKF 6205-2RS JEM", "6205-2RS"])
def test_designations_are_found_with_or_without_maker_and_suffix(name):
    assert RollingBearing.from_designation(name).designation == "SKF 6205"


def test_every_designation_has_a_source_and_an_unknown_one_says_what_to_give():
    assert {b.designation for b in designations()} >= {"SKF 6203", "SKF 6205", "SKF N 305 ECP"}
    assert all(len(s) > 20 for s in designation_sources().values())
    with pytest.raises(BearingError, match="'SKF 9999' not in the table .*give the geometry instead"):
        RollingBearing.from_designation("SKF 9999")


def test_rig_file_bearing_section_as_the_shared_cwru_set_writes_it():
    rig = yaml.safe_load(
        """
bearing:
  designation: SKF 6203-2RS JEM
  n_rolling_elements: 8
  rolling_element_diameter_m: 0.0067462
  pitch_diameter_m: 0.0284988
  contact_angle_deg: 0.0
"""
    )
    bearing = RollingBearing.from_config(rig["bearing"], "fe00.yaml")
    assert bearing.n_rolling_elements == 8 and bearing.designation == "SKF 6203-2RS JEM"
    assert RollingBearing.from_config({"designation": "SKF 6203"}).pitch_diameter_m == pytest.approx(0.0284988)
    with pytest.raises(BearingError, match="rig.yaml: bearing.pitch_diameter_m missing"):
        RollingBearing.from_config({"n_rolling_elements": 8, "rolling_element_diameter_m": 0.006}, "rig.yaml")
    with pytest.raises(BearingError, match="whole number >= 3"):
        RollingBearing(2, 0.01, 0.04)


def test_contact_angle_and_slip_enter_as_the_textbook_formulas():
    bearing = RollingBearing(12, 0.008, 0.040, 30.0)
    kin = bearing.kinematics(25.0, cage_slip=0.02)
    g = 0.008 * 0.8660254037844387 / 0.040
    assert kin.ftf_Hz == pytest.approx(0.98 * 12.5 * (1 - g), rel=1e-12)
    assert kin.bpfo_Hz == pytest.approx(12 * kin.ftf_Hz, rel=1e-12)
    assert kin.bpfi_Hz == pytest.approx(12 * (25.0 - kin.ftf_Hz), rel=1e-12)
    assert kin.bsf_Hz == pytest.approx(0.98 * 0.040 / 0.016 * 25.0 * (1 - g * g), rel=1e-12)
    assert kin.n_rolling_elements == pytest.approx(12.0, rel=1e-12)
    assert kin.at_shaft_rate(50.0).bpfo_Hz == pytest.approx(2 * kin.bpfo_Hz, rel=1e-12)


def test_kinematics_json_round_trip_and_the_models_formula_is_this_one():
    geometry = BearingGeometry(11, 0.010, 0.044, 0.00976, 20e-6, 0.062, 0.017)
    from_lpm = kinematic_frequencies(geometry, 1000 / 60, 0.015)
    direct = Kinematics.from_geometry(RollingBearing(11, 0.010, 0.044), 1000 / 60, 0.015)
    assert from_lpm == direct
    assert Kinematics.from_dict(direct.to_dict()) == direct
    with pytest.raises(BearingError, match="kinematics.json: key 'bsf_Hz' missing"):
        Kinematics.from_dict({k: 1.0 for k in ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz")}, "kinematics.json")
