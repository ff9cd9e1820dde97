"""The sensor design study: figures of merit, the adhesive layer, load share scaling, detection at absolute noise."""

from __future__ import annotations

import copy
import json
from dataclasses import replace

import numpy as np
import pytest

from piezobearing.sensor import design, fem
from piezobearing.sensor.calibration import SensorCircuit
from piezobearing.sensor.materials import ALUMINA, EPOXY, piezo_material, stress_charge_form
from piezobearing.sensor.mesh import (
    GROUP_ADHESIVE,
    MeshDensity,
    StackGeometry,
    cylinder_mesh,
    hex_volumes,
    stack_mesh,
)
from piezobearing.sensor.response import sensor_model
from piezobearing.signals import daq, detection
from piezobearing.signals.envelope import EnvelopeSettings

GEO = StackGeometry(bottom_disk_diameter_m=5e-3, top_disk_diameter_m=3e-3)
PZT = piezo_material("apc850_paper")
MATS = fem.StackMaterials(stress_charge_form(PZT), PZT.density_kg_per_m3, ALUMINA, EPOXY)


def test_linear_from_is_where_the_rc_high_pass_reaches_95_percent():
    c = SensorCircuit(resistance_ohm=50e6)
    f_c = 1 / (2 * np.pi * c.tau_s)
    f = design.linear_from_Hz(f_c, 0.05)
    x = f / f_c
    assert x / np.sqrt(1 + x * x) == pytest.approx(0.95, rel=1e-12)
    assert f == pytest.approx(3.0424 * f_c, rel=1e-4)


@pytest.mark.parametrize("key", ["apc850_paper", "pzt8"])
def test_stack_stiffness_of_a_rod_is_EA_over_L_short_and_open(key):
    """Uniform uniaxial stress (one end u_z = 0, end electrodes): k = A / (s33 L), s33^E shorted, s33^D open."""
    pzt = piezo_material(key)
    mats = fem.StackMaterials(stress_charge_form(pzt), pzt.density_kg_per_m3, ALUMINA)
    r, length = 1.0e-3, 3.0e-3
    asm = fem.assemble(cylinder_mesh(r, length, n_core=2, n_ring=1, n_layers=3), mats, order=2)
    rs = fem.reduce(asm, fem.BoundaryConditions("SS", (("top", (2,)),), hot_z_m=0.0, ground_z_m=length))
    k_short, k_open = design.stack_stiffness_N_per_m(rs)
    s33_e = np.linalg.inv(pzt.c_E_Pa)[2, 2]
    s33_d = s33_e - pzt.d33_C_per_N**2 / pzt.eps33_T_F_per_m
    area = np.pi * r**2
    assert k_short == pytest.approx(area / (s33_e * length), rel=1e-6)
    assert k_open == pytest.approx(area / (s33_d * length), rel=1e-6)


def test_design_figures_are_the_sensor_fem_stages_numbers(paper_config):
    """The study's figures of merit come from the same FEM path as sensor_modal / sensor_harmonic."""
    from piezobearing.stages.sensor_fem import SensorFemParams, harmonic_results

    p = SensorFemParams.from_config(paper_config)
    mesh = stack_mesh(p.geometry, p.density, 1.0)
    rc = SensorCircuit.from_config(paper_config["sensor"], 50e6)
    sweep, band = harmonic_results(mesh, p, rc, 30.0)
    st = design.DesignSettings(p.order, p.damping_ratio, p.n_ritz_modes, p.reference_frequency_Hz, p.band_ratio_dB,
                               0.05)
    d = design.design_figures(mesh, p.materials, fem.MeasuringCircuit(50e6, p.cable_capacitance_F), st)
    assert d["first_resonance_short_Hz"] == pytest.approx(band["first_axial_short_Hz"], rel=1e-9)
    assert d["first_resonance_open_Hz"] == pytest.approx(band["first_axial_open_Hz"], rel=1e-9)
    assert d["band_high_Hz"] == pytest.approx(band["band_high_Hz"], rel=1e-9)
    assert d["sensitivity_V_per_N"] == pytest.approx(band["mid_band_sensitivity_V_per_N"], rel=1e-9)
    assert d["corner_Hz"] == pytest.approx(band["fem_corner_Hz"], rel=1e-12)
    # mid-band is the plateau d33_eff / (C_FEM + C_cable) to 1e-4
    assert d["sensitivity_V_per_N"] == pytest.approx(d["open_circuit_gain_V_per_N"], rel=1e-4)
    assert d["first_resonance_open_Hz"] > d["first_resonance_short_Hz"]
    assert d["stack_stiffness_open_N_per_m"] > d["stack_stiffness_short_N_per_m"]
    # the study's force-to-voltage gain is the one sensor model's (RC x the FEM's correction below the DAQ's
    # Nyquist frequency, as the workflow's sensor_voltage applies it) to 0.17 % (a median ratio over the band, not
    # the static one; the FEM's tau is 1.5 % shorter than the RC model's: C_FEM against eps33 A / h)
    one = sensor_model(paper_config, rc, 1275.0, (sweep["frequency_Hz"].to_numpy(),
                                                  sweep["voltage_per_force_V_per_N"].to_numpy()))
    assert one.correction is not None
    assert d["open_circuit_gain_V_per_N"] == pytest.approx(one.gain_V_per_N, rel=3e-3)


def test_adhesive_layer_meshes_as_a_thin_layer_and_softens_the_stack():
    none = stack_mesh(GEO, MeshDensity(), 1.0)
    same = stack_mesh(replace(GEO, adhesive_height_m=0.0), MeshDensity(), 1.0)
    assert np.array_equal(none.coors, same.coors) and np.array_equal(none.cells, same.cells)
    a = 20e-6
    glued = stack_mesh(replace(GEO, adhesive_height_m=a), MeshDensity(), 1.0)
    vol = hex_volumes(glued)
    # two layers of thickness a over the narrower face: the 4.7 mm PZT on the 5 mm disk, the 3 mm disk on the PZT
    expected = np.pi * (4.7e-3**2 + 3e-3**2) / 4 * a / 4
    assert vol[glued.groups == GROUP_ADHESIVE].sum() == pytest.approx(expected, rel=1e-9)
    z = replace(GEO, adhesive_height_m=a).z_interfaces_m
    assert z[1] == pytest.approx(1e-3 + a) and z[2] - z[1] == pytest.approx(3.4e-3)
    st = design.DesignSettings(n_ritz_modes=6)
    circ = fem.MeasuringCircuit(50e6, 180e-12)
    d0 = design.design_figures(none, MATS, circ, st)
    d1 = design.design_figures(glued, MATS, circ, st)
    assert d1["first_resonance_short_Hz"] < 0.97 * d0["first_resonance_short_Hz"]
    assert d1["stack_stiffness_open_N_per_m"] < 0.9 * d0["stack_stiffness_open_N_per_m"]
    # epoxy in series: 1/k grows by at least the layers' own compliance (a / (E A)), within the 3D spreading
    extra = a / (EPOXY.young_Pa * np.pi * 4.7e-3**2 / 4) + a / (EPOXY.young_Pa * np.pi * 3e-3**2 / 4)
    grow = 1 / d1["stack_stiffness_open_N_per_m"] - 1 / d0["stack_stiffness_open_N_per_m"]
    assert 0.5 * extra < grow < 1.5 * extra


def test_housing_spring_adds_the_bond_layer_in_series():
    from piezobearing.housing.fem import pzt_axial_modulus, sensor_stiffness

    k0 = sensor_stiffness(PZT, 4.7e-3, 3.4e-3, ALUMINA, 5e-3, 1e-3)
    k1 = sensor_stiffness(PZT, 4.7e-3, 3.4e-3, ALUMINA, 5e-3, 1e-3, "open", EPOXY, 20e-6)
    assert 1 / k1 - 1 / k0 == pytest.approx(20e-6 / (EPOXY.young_Pa * np.pi * 4.7e-3**2 / 4), rel=1e-9)
    a_t, a_p = np.pi * 5e-3**2 / 4, np.pi * 4.7e-3**2 / 4
    assert k0 == 1 / (1e-3 / (ALUMINA.young_Pa * a_t) + 3.4e-3 / (pzt_axial_modulus(PZT, "open") * a_p))


def test_sensor_spring_scales_the_whole_influence_line(ci_config):
    """The sensor is a rank-one spring: changing its stiffness multiplies the influence line by one factor,
    which is what lets the study scale the workflow's sensor force by the ratio of load shares."""
    from piezobearing.housing import fem as housing_fem
    from piezobearing.housing.mesh import build_housing_mesh
    from piezobearing.housing.transient import housing_geometry
    from piezobearing.sensor.materials import CAST_IRON, STEEL

    mesh = build_housing_mesh(housing_geometry(ci_config), False, 0.35)
    models = [housing_fem.build_model(mesh, STEEL, CAST_IRON, k, 0.1e-3) for k in (3.8e8, 1.5e9)]
    lines = [m.influence_line()[2] for m in models]
    big = np.abs(lines[0]) > 1e-3 * np.abs(lines[0]).max()
    ratio = lines[1][big] / lines[0][big]
    assert np.ptp(ratio) < 1e-6 * ratio.mean()
    assert 1.0 < ratio.mean() < 1.5e9 / 3.8e8  # stiffer takes more load, less than in proportion
    # the factor from the housing's port compliance, found from either model, predicts it
    for m, (k_new, k_ref) in zip(models, ((1.5e9, 3.8e8), (3.8e8, 1.5e9)), strict=True):
        f = housing_fem.spring_share_factor(k_new, k_ref, m.sensor_port_compliance_m_per_N())
        assert f == pytest.approx(ratio.mean() if k_new > k_ref else 1 / ratio.mean(), rel=1e-8)


def _impulse_records(n=2550, dt=1 / 2550, f0=2550 / 36):
    """Healthy: smooth bumps at f0; faulty: the bumps plus two-sample dips at f0 (volts)."""
    t = np.arange(n) * dt
    healthy = 40 * np.cos(2 * np.pi * f0 * t)
    faulty = healthy.copy()
    faulty[(np.round(t * f0 * 36) % 36) < 2] -= 5.0
    return {"healthy": healthy, "faulty": faulty}, dt, f0


def test_detection_margin_grows_with_the_gain_by_exactly_the_gain():
    """Without clipping or quantisation the noise limit scales with the signal: twice the gain, +6.02 dB."""
    v, dt, f0 = _impulse_records()
    noise = daq.NoiseSettings(model="absolute", noise_density_V_per_sqrtHz=1e-3, adc_bits=48, range_V=1e4)
    es = EnvelopeSettings("fixed", (500.0, 1250.0), 300.0, 4)
    ins = detection.IndicatorSettings(3, 0.5, 2, 1e-3)
    a = design.detection_at_noise(v, dt, f0, noise, 8, 3, es, ins, 0.95)
    b = design.detection_at_noise({k: 2 * x for k, x in v.items()}, dt, f0, noise, 8, 3, es, ins, 0.95)
    assert a["detection_rate_faulty"] == 1.0 and a["indicator_faulty"] > a["threshold"]
    assert b["detection_margin_dB"] - a["detection_margin_dB"] == pytest.approx(20 * np.log10(2), abs=1e-3)
    assert not a["clipped"] and not b["clipped"]
    assert b["indicator_faulty"] > a["indicator_faulty"]


def test_a_clipped_design_is_flagged_and_its_margin_kept_apart():
    """The records peak at 40 V; a +-30 V ADC clips them: `clipped`, no `detection_margin_dB` (NaN), the number
    measured on the clipped record apart; with the ideal ADC the margin is the unclipped design's (the same
    records on a +-100 V ADC that does not clip), and it grows with the gain by exactly the gain."""
    v, dt, f0 = _impulse_records()
    es = EnvelopeSettings("fixed", (500.0, 1250.0), 300.0, 4)
    ins = detection.IndicatorSettings(3, 0.5, 2, 1e-3)
    narrow = daq.NoiseSettings(model="absolute", noise_density_V_per_sqrtHz=1e-3, adc_bits=24, range_V=30.0)
    wide = replace(narrow, range_V=100.0)
    d = design.detection_at_noise(v, dt, f0, narrow, 3, 1, es, ins, 0.95)
    assert d["clipped"] and d["clipped_fraction"] > 0.1
    assert d["range_needed_V"] == pytest.approx(40.0, rel=1e-6) and d["range_V"] == 30.0
    assert np.isnan(d["detection_margin_dB"]) and np.isfinite(d["detection_margin_as_clipped_dB"])
    w = design.detection_at_noise(v, dt, f0, wide, 3, 1, es, ins, 0.95)
    assert not w["clipped"] and np.isnan(w["detection_margin_as_clipped_dB"])
    assert d["detection_margin_ideal_adc_dB"] == w["detection_margin_ideal_adc_dB"]
    assert w["detection_margin_dB"] == pytest.approx(w["detection_margin_ideal_adc_dB"], abs=0.5)
    g = design.detection_at_noise({k: 2 * x for k, x in v.items()}, dt, f0, narrow, 3, 1, es, ins, 0.95)
    assert g["detection_margin_ideal_adc_dB"] - d["detection_margin_ideal_adc_dB"] == pytest.approx(
        20 * np.log10(2), abs=1e-3)


@pytest.mark.slow
def test_one_sensor_design_case_on_workflow_files(tmp_path, ci_config):
    """The study kind on synthetic workflow inputs: contract columns, the paper's stack gives the workflow's share,
    and the detection runs on the DAQ's clock (sampled from the 2550 Hz model step at 2000 Hz, as the noisy rule
    does), so the noise's standard deviation is the density times sqrt(f_s / 2) of the DAQ."""
    import pandas as pd

    from piezobearing.plotting.studies import pareto_front
    from piezobearing.stages.studies import run_case, summarize

    cfg = copy.deepcopy(ci_config)
    cfg["housing"].update(mesh_level=0.35)
    cfg["signals"].update(study_n_seeds=3, sample_rate_Hz=2000.0, band_Hz=[500.0, 950.0])
    res = tmp_path / "resistance.json"
    res.write_text(json.dumps({"resistance_ohm": 50.0e6}))
    v, dt, f0 = _impulse_records(n=int(0.6 * 2550))
    forces = {}
    for case in ("healthy", "faulty"):
        forces[case] = tmp_path / f"force_{case}.csv"
        pd.DataFrame({"time_s": np.arange(len(v[case])) * dt, "force_N": 50 + v[case]}).to_csv(forces[case], index=False)
    kin = tmp_path / "kinematics.json"
    kin.write_text(json.dumps({"bpfo_Hz": f0, "ftf_Hz": 6.44, "shaft_Hz": 16.67, "bpfi_Hz": 112.5, "bsf_Hz": 34.77}))
    from piezobearing.stages.studies import sensor_design_housing

    housing = tmp_path / "housing.json"
    sensor_design_housing(str(housing), cfg)
    inputs = {"resistance": str(res), "force_healthy": str(forces["healthy"]), "force_faulty": str(forces["faulty"]),
              "kinematics": str(kin), "housing": str(housing)}
    outs = []
    for name, ov in (("paper", {"sensor__material": "apc850_paper"}),
                     ("pzt4", {"sensor__material": "pzt4", "sensor__pzt_height_m": 1.0e-3})):
        out = tmp_path / "sd" / name / "summary.json"
        run_case("sensor_design", name, ov, cfg, str(out), inputs)
        outs.append(str(out))
    csv, png = tmp_path / "sd" / "summary.csv", tmp_path / "sd" / "summary.png"
    summarize("sensor_design", outs, str(csv), str(png))
    df = pd.read_csv(csv)
    for col in ("material", "pzt_diameter_m", "pzt_thickness_m", "sensitivity_V_per_N", "first_resonance_short_Hz",
                "band_high_Hz", "linear_from_Hz", "load_share", "indicator_faulty"):
        assert col in df, col
    paper, hard = df.iloc[0], df.iloc[1]
    assert paper["load_share"] == pytest.approx(paper["load_share_configured"], rel=1e-12)
    assert hard["load_share"] > paper["load_share"]  # a stiffer stack takes a larger share of the roller load
    assert hard["first_resonance_short_Hz"] > paper["first_resonance_short_Hz"]
    assert hard["sensitivity_V_per_N"] < paper["sensitivity_V_per_N"]
    assert paper["noise_std_V"] == pytest.approx(paper["noise_density_V_per_sqrtHz"] * np.sqrt(1000.0), rel=1e-9)
    assert png.stat().st_size > 0
    assert sorted(pareto_front(np.array([1.0, 2.0, 3.0]), np.array([3.0, 1.0, 2.0]))) == [0, 2]


def test_every_configured_study_case_name_fits_a_file_name(paper_config, ci_config):
    """Paramspace names a case by every column and value; the case's folder, its log and its benchmark file
    (rules/study_case_<study>/<case>.tsv) carry that name. One over 251 characters stops the workflow
    (OSError: File name too long)."""
    import pandas as pd
    from snakemake.utils import Paramspace

    for s in paper_config["studies"] + ci_config["studies"]:
        df = pd.read_csv(s["table"], sep="\t", comment="#")
        cases = Paramspace(df, filename_params="*", single_wildcard="case").instance_patterns
        longest = max(len(f"{c}.tsv") for c in cases)
        assert longest <= 255, f"{s['table']}: case file names up to {longest} characters"
