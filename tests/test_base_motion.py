"""Base motion of the housing's foot: the LPM's inertial loads, the housing FEM's surface accelerations and
sensor force (closed forms; the reduced modal model against the direct solve), the accelerometer's model."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from piezobearing.bearing import lpm as brg
from piezobearing.comparison import accelerometer as acc
from piezobearing.housing import base_motion as bm
from piezobearing.housing import fem
from piezobearing.housing import reduced as reduced_housing
from piezobearing.housing import transient as st
from piezobearing.housing.mesh import build_housing_mesh
from piezobearing.stages import housing_model

LEVEL = 0.35  # a coarse mesh: about 5k DOFs
RATE_HZ = 51200.0  # the comparison's model rate: two samples per sample of a 25.6 kHz DAQ


def lock_in(x: np.ndarray, t: np.ndarray, f_Hz: float) -> complex:
    """Complex amplitude of the component of x at f over whole periods: 2/N sum x exp(-j w t)."""
    return complex(2.0 * np.mean(x * np.exp(-2j * np.pi * f_Hz * t)))


@pytest.fixture(scope="module")
def housing(paper_config):
    """The healthy housing on a coarse mesh, its modes to beyond 30 kHz, the three mounting places."""
    m = build_housing_mesh(st.housing_geometry(paper_config), False, LEVEL)
    model = st.make_model(m, paper_config)
    modes = fem.compute_modes(model, 12)
    probes = tuple(fem.mounting_probe(m, p) for p in fem.MOUNTING_POSITIONS)
    base = fem.base_motion_operators(model, modes, probes)
    alpha, beta = fem.rayleigh_coefficients(0.02, (1000.0, 10000.0))
    ops = fem.reduced_operators(model, modes, alpha, beta)
    return {"mesh": m, "model": model, "modes": modes, "base": base, "ops": ops, "alpha": alpha, "beta": beta}


# --------------------------------------------------------------------------- the surroundings


def test_base_motion_rms_follows_its_psd_and_lines():
    s = bm.BaseMotionSettings(level=2.0, psd_frequencies_Hz=(10.0, 1000.0, 10000.0),
                              psd_m2_per_s4_per_Hz=(1e-3, 1e-2, 1e-3), mains_amplitudes_m_per_s2=(0.5, 0.2),
                              gear_mesh_frequency_Hz=433.0, gear_mesh_amplitudes_m_per_s2=(1.0,))
    t = np.arange(2**18) / 51200.0
    a = bm.realisation(s, seed=3)(t)
    expected = s.expected_rms_m_per_s2()
    for axis in range(2):
        assert np.sqrt(np.mean(a[:, axis] ** 2)) == pytest.approx(expected, rel=0.03)
    assert bm.rms_m_per_s2(a) == pytest.approx(np.sqrt(2) * expected, rel=0.03)
    np.testing.assert_array_equal(a, bm.realisation(s, seed=3)(t))  # deterministic by seed
    assert not np.allclose(a, bm.realisation(s, seed=3, replicate=1)(t))
    assert np.corrcoef(a[:, 0], a[:, 1])[0, 1] == pytest.approx(0.0, abs=0.02)  # the axes draw apart
    off = bm.BaseMotionSettings(level=0.0)
    assert not off.active and not np.any(bm.realisation(off, seed=3)(t))


def test_bad_psd_stops_naming_the_key():
    with pytest.raises(ValueError, match="base_motion.psd_frequencies_Hz"):
        bm.BaseMotionSettings(psd_frequencies_Hz=(100.0, 10.0), psd_m2_per_s4_per_Hz=(1.0, 1.0))


# --------------------------------------------------------------------------- the LPM under base motion


def _short_bearing(config: dict) -> dict:
    b = copy.deepcopy(config["bearing"])
    b.update(duration_s=0.2, settle_s=0.05, defects=[])
    return b


def test_lpm_rollers_carry_the_shafts_inertial_load(paper_config):
    """Ground acceleration a_z = A sin(w t) far below the shaft-on-rollers resonance (~2 kHz): the rollers'
    resultant changes by -m_s a (the shaft, held by this bearing alone, is pushed by its own inertia); the
    pedestal's inertia goes to its spring, not through the rollers."""
    b = _short_bearing(paper_config)
    f_tone, amp = 30.0, 20.0

    def tone(t):
        return np.stack([np.zeros_like(t), amp * np.sin(2 * np.pi * f_tone * t)], axis=1)

    run = st.run_lpm(b, False, base_motion=tone)
    t, q, psi = run["fine_time_s"], run["fine_load_N"], None
    p = run["params"]
    psi = p.roller_angles(t)
    fz = np.sum(q * -np.cos(psi), axis=1)  # the rollers' resultant on the pedestal along z
    sel = t >= 0
    z = lock_in(fz[sel] + b["radial_load_N"], t[sel], f_tone)
    a = lock_in(run["fine_base_acceleration_m_per_s2"][sel, 1], t[sel], f_tone)
    assert abs(z / (-b["shaft_mass_kg"] * a) - 1) < 0.01
    # the python loop and the compiled kernel agree under a time-varying load
    n = 2000
    ab = tone(-b["settle_s"] + 1e-5 * np.arange(n + 1))
    r1 = brg.simulate_lpm(p, -b["settle_s"], n, 1e-5, method="compiled", base_acceleration_m_per_s2=ab)
    r2 = brg.simulate_lpm(p, -b["settle_s"], n, 1e-5, method="python", base_acceleration_m_per_s2=ab)
    np.testing.assert_allclose(r1.load_N, r2.load_N, rtol=1e-9, atol=1e-9 * b["radial_load_N"])


def test_lpm_without_base_motion_is_unchanged(paper_config):
    """A ground at rest given as zeros gives the same bits as no ground motion at all."""
    b = _short_bearing(paper_config)
    p = brg.LPMParameters.from_config(b, False)
    n = 500
    r0 = brg.simulate_lpm(p, 0.0, n, 1e-5)
    r1 = brg.simulate_lpm(p, 0.0, n, 1e-5, base_acceleration_m_per_s2=np.zeros((n + 1, 2)))
    np.testing.assert_array_equal(r0.load_N, r1.load_N)
    np.testing.assert_array_equal(r0.shaft_m, r1.shaft_m)


# --------------------------------------------------------------------------- the housing under base motion


def test_mounting_places_lie_on_their_surfaces(housing, paper_config):
    g = housing["mesh"].geometry
    by = {p.position: p for p in housing["base"].probes}
    assert by["top"].coordinates_m[2] == pytest.approx(g.body_top_m)
    assert by["side"].coordinates_m[1] == pytest.approx(g.body_half_width_m)
    assert abs(by["side"].coordinates_m[2]) < 0.01
    assert by["foot"].coordinates_m[2] == pytest.approx(-g.body_bottom_m)
    with pytest.raises(ValueError, match="accelerometer.position"):
        fem.mounting_probe(housing["mesh"], "bottom")


def test_windowed_roller_loads_equal_the_column_loads(housing):
    """The roller loads projected over each patch's few columns equal the column loads' projection over every
    column (HousingModel.column_loads), across the raceway's ends (psi = +-pi) and at the columns themselves."""
    model, ops = housing["model"], housing["ops"]
    columns = fem.RacewayColumns.of(model)
    rng = np.random.default_rng(5)
    nt, z = 3000, 11
    psi = np.mod(rng.uniform(0, 2 * np.pi, (1, z)) + np.linspace(0, 30, nt)[:, None], 2 * np.pi) - np.pi
    psi[0, :4] = model.mesh.raceway_psi[:4]
    psi[1, :2] = (np.pi, -np.pi)
    q = rng.uniform(0.0, 300.0, (nt, z))
    wy, wz = model.column_loads(q, psi)
    g, f = fem.project_roller_loads(columns, ops, q, psi)
    # summed in another order (patch by patch, not column by column): equal to 1e-12 of the largest
    g_all, f_all = wy @ ops.static_y + wz @ ops.static_z, wy @ ops.modal_y + wz @ ops.modal_z
    np.testing.assert_allclose(g, g_all, rtol=1e-12, atol=1e-12 * np.abs(g_all).max())
    np.testing.assert_allclose(f, f_all, rtol=1e-12, atol=1e-12 * np.abs(f_all).max())
    # the window's weights are the dense weights, and the window holds all that are not zero
    cols, w = columns.patch_window(psi.ravel(), columns.window())
    dense = np.zeros((psi.size, columns.psi_rad.size))
    np.put_along_axis(dense, cols, w, axis=1)
    np.testing.assert_allclose(dense, model.patch_weights(psi.ravel()), rtol=1e-12, atol=0)


def test_housing_file_round_trip(housing, tmp_path, paper_config):
    """A housing model written by the rule sensor_comparison_housing reads back the same; a file of another
    config or mesh stops the comparison."""
    h = reduced_housing.Housing(fem.RacewayColumns.of(housing["model"]), housing["ops"], housing["base"], housing["model"].n_dofs)
    reads = housing_model.housing_reads(paper_config)
    housing_model.save_housing(h, False, reads, tmp_path / "h.npz")
    back = housing_model.load_housing(tmp_path / "h.npz", False, reads)
    assert back.at("side").record() == h.at("side").record()
    for name in ("modal_y", "static_z", "sensor_modal", "omega", "zeta"):
        np.testing.assert_array_equal(getattr(back.ops, name), getattr(h.ops, name))
    np.testing.assert_array_equal(back.base.probe_modal, h.base.probe_modal)
    np.testing.assert_array_equal(back.columns.psi_rad, h.columns.psi_rad)
    with pytest.raises(ValueError, match="sensor_comparison_housing"):
        housing_model.load_housing(tmp_path / "h.npz", True, reads)
    other = copy.deepcopy(paper_config)
    other["housing"]["mesh_level"] = 0.5
    with pytest.raises(ValueError, match="another"):
        housing_model.load_housing(tmp_path / "h.npz", False, housing_model.housing_reads(other))


def test_effective_mass_grows_to_the_dragged_mass(housing):
    """Gamma_i^2 summed over all modes is r^T M r; the cumulative share grows with the modes and stays below 1."""
    frac = housing["base"].effective_mass_fraction()
    assert np.all(np.diff(frac, axis=1) >= -1e-12)
    assert np.all(frac[:, -1] < 1.0 + 1e-9) and np.all(frac[:, -1] > 0.5)


def test_rigid_housing_reads_the_base_through_the_transfer_function(housing):
    """Far below the housing's first mode (~3 kHz) the housing moves with its foot: every mounting place reads
    the base's acceleration along its normal, and the accelerometer's voltage is H(f) times it."""
    h, base, ops = 1 / RATE_HZ, housing["base"], housing["ops"]
    n = 2**14
    t = h * np.arange(n)
    f_y, f_z = 100.0 * 51200 / 2**14 * 16 / 50, 50.0 * 51200 / 2**14 * 16 / 50  # whole periods in the record
    a = np.stack([3.0 * np.sin(2 * np.pi * f_y * t), 5.0 * np.sin(2 * np.pi * f_z * t)], axis=1)
    nc = len(housing["mesh"].raceway_psi)
    r = fem.response_reduced(ops, base, np.zeros((n, nc)), np.zeros((n, nc)), a, h)
    settled = t > 0.05  # the modes' start transient (static start, q' = 0) has decayed
    sensor = acc.AccelerometerSettings()
    for i, p in enumerate(base.probes):
        expected = base.probe_base[i] @ a.T
        got = r["acceleration_m_per_s2"][i]
        assert np.max(np.abs(got - expected)[settled]) < 2e-3 * np.max(np.abs(expected)), p.position
        v = acc.transduce(expected, h, sensor)
        f0 = f_z if p.normal[2] else f_y
        assert abs(lock_in(v, t, f0)) == pytest.approx(abs(sensor.transfer(f0)) * (5.0 if p.normal[2] else 3.0),
                                                       rel=1e-6)
    # the housing's own inertia on the sensor: its static share times a_z
    np.testing.assert_allclose(r["force_N"][settled], (a @ base.static_sensor)[settled],
                               atol=1e-3 * np.max(np.abs(a @ base.static_sensor)))


def test_sensor_force_follows_the_shafts_inertial_load(housing, paper_config):
    """The LPM under a slow ground tone: the sensor force's component at the tone is the sensor's share of the
    radial load, dF_s/dF_r (from two radial loads, the ground at rest), times m_s a, plus the housing's own
    inertia on the sensor (its static share times a)."""
    b = _short_bearing(paper_config)
    model, base = housing["model"], housing["base"]
    ops = housing["ops"]
    f_tone, amp = 30.0, 20.0

    def quasi_static(run):
        wy, wz = model.column_loads(run["load_N"], run["angle_rad"])
        return wy @ ops.static_y + wz @ ops.static_z

    mean, rest = {}, None
    for load in (500.0, 520.0):
        g = quasi_static(st.run_lpm({**b, "radial_load_N": load}, False))
        rest = g if rest is None else rest
        mean[load] = float(np.mean(g))
    share = (mean[520.0] - mean[500.0]) / 20.0

    def tone(t):
        return np.stack([np.zeros_like(t), amp * np.sin(2 * np.pi * f_tone * t)], axis=1)

    run = st.run_lpm(b, False, base_motion=tone)
    t = run["time_s"]
    a = run["base_acceleration_m_per_s2"]
    # the change from the ground at rest (the roller passage's ripple at BPFO would leak into the tone's bin)
    force = quasi_static(run) - rest + a @ base.static_sensor
    got = lock_in(force, t, f_tone)
    expected = lock_in(share * b["shaft_mass_kg"] * a[:, 1] + a @ base.static_sensor, t, f_tone)
    assert abs(got / expected - 1) < 0.02


@pytest.mark.slow
def test_surface_accelerations_reduced_against_direct(housing):
    """Broadband base motion to 10 kHz at the comparison's model rate: the reduced modal model (modes to
    33 kHz, 2.6 x the 12.8 kHz Nyquist frequency of a 25.6 kHz DAQ) against sfepy's generalized-alpha solve of
    the full system, 8 solver steps a sample (its period error ~(omega h)^2 / 12)."""
    h, base, ops, model = 1 / RATE_HZ, housing["base"], housing["ops"], housing["model"]
    s = bm.BaseMotionSettings(level=1.0, psd_frequencies_Hz=(10.0, 10000.0), psd_m2_per_s4_per_Hz=(1.0, 1.0))
    n = 200
    a = bm.realisation(s, seed=1)(h * np.arange(n))
    nc = len(housing["mesh"].raceway_psi)
    zero = np.zeros((n, nc))
    r = fem.response_reduced(ops, base, zero, zero, a, h)
    d = fem.sensor_force_direct(model, zero, zero, h, housing["alpha"], housing["beta"], 0.9, base=base,
                                base_acceleration=a, substeps=8)
    for i, p in enumerate(base.probes):
        x, y = r["acceleration_m_per_s2"][i], d["probe_acceleration_m_per_s2"][i]
        assert np.sqrt(np.mean((x - y) ** 2)) < 0.08 * np.sqrt(np.mean(y**2)), p.position
    assert np.sqrt(np.mean((r["force_N"] - d["force_N"]) ** 2)) < 0.08 * np.std(d["force_N"])


# --------------------------------------------------------------------------- the accelerometer


def test_accelerometer_noise_follows_its_datasheet_density():
    s = acc.AccelerometerSettings()
    h, n = 1 / 25600.0, 2**18
    v = acc.transducer_noise_V(n, h, s, np.random.default_rng(1))
    f = np.fft.rfftfreq(n, h)
    expected = np.sum((s.noise_density_m_per_s2_per_sqrtHz(f[1:-1]) * s.sensitivity_V_per_m_per_s2) ** 2) / (n * h)
    assert np.mean(v**2) == pytest.approx(expected, rel=0.02)
    # the spectral points over 1 Hz-10 kHz (flat beyond them) give the datasheet's broadband resolution,
    # 150 ug rms, within 10 % (164 ug)
    band = (f >= 1) & (f <= 10000)
    rms_ug = np.sqrt(np.sum(s.noise_density_m_per_s2_per_sqrtHz(f[band]) ** 2) / (n * h)) / acc.G_N * 1e6
    assert rms_ug == pytest.approx(150.0, rel=0.1)


def test_accelerometer_gain_resonance_and_range():
    s = acc.AccelerometerSettings()
    assert abs(s.transfer(1000.0)) == pytest.approx(0.1 / acc.G_N, rel=1e-3)  # 100 mV/g in its flat band
    assert abs(s.transfer(s.resonance_Hz)) == pytest.approx(0.1 / acc.G_N / (2 * s.resonance_damping_ratio), rel=1e-6)
    assert abs(s.transfer(s.highpass_Hz)) == pytest.approx(0.1 / acc.G_N / np.sqrt(2), rel=1e-3)
    v, n = acc.saturate(np.array([0.0, 4.0, 6.0, -7.0]), s)
    assert n == 2 and v.max() == pytest.approx(5.0) and v.min() == pytest.approx(-5.0)
