"""The model-versus-measurement loop on synthetic records with known hidden effects.

The record is the CI configuration's synthetic calibration (``config/ci.yaml``: 12 s at 500 Hz, 6 presses,
seed 7, R = 50 MOhm, 5 mN force noise, 2 mV voltage noise) with effects injected through
``synthesis.hidden_effects``; three tests keep the paper's default record (25 s at 1 kHz, 13 presses), each
saying why. Each hidden value is a plausible size for the experiment of Sec. III-B, chosen before looking
at the diagnosis and stated with its reason below; detection must come from the evidence (BIC with the
measured noise), with the same settings for every effect. The hidden sizes and every assertion are those
of the paper's record (docs/validation/hide_and_find.md), run on the CI record (about a quarter of the CPU): on
the CI record each effect is still ranked first and selected, its value within 2.1% (clock drift; the
others within 0.3%) and inside its interval.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import cont2discrete, lfilter

from piezobearing.diagnosis.calibration.effects import CATALOGUE, ForceRecord
from piezobearing.diagnosis.calibration.presses import PressProtocol, press_force, synthesize
from piezobearing.diagnosis.calibration.subject import diagnose_record
from piezobearing.diagnosis.fit import fd_weighted, whiten
from piezobearing.diagnosis.noise import estimate_noise_floor
from piezobearing.diagnosis.residual_tests import residual_tests
from piezobearing.diagnosis.settings import DiagnosticsSettings
from piezobearing.diagnosis.verdict import findings
from piezobearing.sensor.calibration import circuit_voltage, detect_impulses
from piezobearing.stages.calibration import nominal_circuit

#: Hidden effects: (specs, name of the main parameter, its true value). The hidden sizes are each effect's
#: ``example`` (its module states why that size is plausible: the one home of the values the tests, the
#: error-rate study and ``piezobearing hide-and-find`` hide).
MAIN_PARAM = {
    "channel_delay": "delay_s",
    "ac_coupling": "corner_Hz",
    "reference_lag": "lag_tau_s",
    "d33_nonlinearity": "beta_per_N",
    "mains_pickup": "mains_h1_sin_V",
    "baseline_drift": "drift_p1_V",
    "extra_capacitance": "extra_capacitance_F",
}
HIDDEN = {
    name: ([{"name": name, "params": dict(CATALOGUE[name].example)}], p, CATALOGUE[name].example[p])
    for name, p in MAIN_PARAM.items()
}

_CACHE: dict = {}


def run(config: dict, hidden: list[dict], effects: tuple = (), seed: int | None = None, record=None) -> dict:
    """Synthesize (or take ``record`` = (time, force, voltage)) and diagnose; cached by key."""
    key = (id(config), repr(hidden), effects, seed, None if record is None else id(record))
    if key not in _CACHE:
        c = config
        if record is None:
            m = synthesize(
                PressProtocol.from_config(c["synthesis"]),
                nominal_circuit(c),
                c["seed"] if seed is None else seed,
                hidden,
            )
            t, f, v = m.time_s, m.force_N, m.voltage_V
        else:
            t, f, v = record
        imps = detect_impulses(f, v, t[1] - t[0], 0.2, 0.8)
        _, _CACHE[key] = diagnose_record(
            ForceRecord(t, f),
            v,
            nominal_circuit(c, c["calibration"]["initial_resistance_ohm"]),
            list(effects),
            DiagnosticsSettings.from_config(c["diagnostics"]),
            imps,
        )
    return _CACHE[key]


# --------------------------------------------------------------------------- pieces


def test_fd_weighting_is_parseval():
    """For a flat floor sigma^2, the weighted residual's sum of squares is sum r^2 / sigma^2."""
    rng = np.random.default_rng(0)
    for n in (1000, 1001):
        r = rng.normal(0, 0.3, n)
        z = fd_weighted(r, np.full(n // 2 + 1, 0.09))
        assert z.size == n
        assert z @ z == pytest.approx(r @ r / 0.09, rel=1e-12)
        np.testing.assert_allclose(whiten(r, np.full(n // 2 + 1, 0.09)), r / 0.3, atol=1e-12)


def test_noise_floor_is_measured_in_quiet_stretches(paper_config):
    """Both channels' white-noise levels within 3% of the truth, also with strong mains lines in the voltage.

    The paper's record (no diagnosis here, 0.04 s): its quiet stretches (over 8 s) hold the 3%; the CI
    record's (fewer, shorter) give the force's level 4.7% low."""
    c = paper_config
    for hidden in ([], HIDDEN["mains_pickup"][0]):
        m = synthesize(PressProtocol.from_config(c["synthesis"]), nominal_circuit(c), c["seed"], hidden)
        fl = estimate_noise_floor(
            ForceRecord(m.time_s, m.force_N), m.voltage_V, DiagnosticsSettings(), 5 * 0.013
        )
        assert fl.voltage_noise_V == pytest.approx(0.002, rel=0.03)
        assert fl.input_noise == pytest.approx(0.005, rel=0.03)
        assert fl.quiet_s > 8.0 and fl.n_stretches >= 10


def test_residual_tests_pass_white_noise_and_name_a_tone():
    """White noise passes all four tests; a tone 3x the noise amplitude shows as a narrowband peak at its frequency."""
    rng = np.random.default_rng(11)
    dt, n = 1e-3, 25000
    st = DiagnosticsSettings()
    passed = [
        residual_tests(rng.normal(size=n), rng.normal(size=n).cumsum(), dt, st).passed for _ in range(5)
    ]
    assert all(passed)
    t = np.arange(n) * dt
    e = rng.normal(size=n) + 0.3 * np.sin(2 * np.pi * 73.2 * t)
    tests = residual_tests(e, rng.normal(size=n).cumsum(), dt, st)
    assert not tests.passed
    f = findings(tests)
    spec = [x for x in f if x["test"] == "spectrum"]
    assert spec and spec[0]["kind"] == "narrowband" and abs(spec[0]["frequency_Hz"] - 73.2) < 0.1


# --------------------------------------------------------------------------- the loop


def test_clean_measurement_selects_nothing(ci_config):
    """The baseline already fits to the noise floor: no false discovery, verdict explained."""
    d = run(ci_config, [])
    assert d["selected"] == []
    assert d["winner"] is None
    assert d["verdict"] == "explained" and d["unexplained"] == []
    assert d["baseline"]["nrmse"] < 1.1 * d["noise_floor_nrmse"]
    assert d["baseline"]["params"]["resistance_ohm"] == pytest.approx(50e6, rel=0.01)
    assert all(r["delta_bic"] < ci_config["diagnostics"]["min_delta_bic"] for r in d["ranking"])


@pytest.mark.parametrize("seed", [1, 2])
def test_clean_measurement_selects_nothing_other_seeds(ci_config, seed):
    d = run(ci_config, [], seed=seed)
    assert d["selected"] == [] and d["verdict"] == "explained"


@pytest.mark.parametrize("name", list(HIDDEN))
def test_hidden_effect_is_ranked_first_selected_and_explains_the_misfit(ci_config, name):
    hidden, pname, truth = HIDDEN[name]
    d = run(ci_config, hidden)
    assert d["ranking"][0]["effect"] == name
    assert d["selected"] == [name]
    assert d["winner"]["effect"] == name and d["winner"]["physics"]
    assert d["verdict"] == "explained"
    base, final = d["baseline"], d["final"]
    assert final["nrmse"] <= 1.5 * final["noise_floor_nrmse"]
    if base["nrmse"] > 3 * base["noise_floor_nrmse"]:
        assert final["nrmse"] <= 0.5 * base["nrmse"]
    assert final["nrmse"] < base["nrmse"]
    # the fitted parameter recovers the hidden one, its 95% interval holding it (5% slack on the interval)
    est = final["params"][pname]
    assert est == pytest.approx(truth, rel=0.05)
    lo, hi = final["ci95"][pname]
    span = abs(truth) * 0.05
    assert lo - span <= truth <= hi + span
    assert final["params"]["resistance_ohm"] == pytest.approx(50e6, rel=0.02)


def test_two_hidden_effects_are_both_found(ci_config):
    """A clock offset and a ground loop together (two acquisition devices)."""
    hidden = HIDDEN["channel_delay"][0] + HIDDEN["mains_pickup"][0]
    d = run(ci_config, hidden)
    assert set(d["selected"]) == {"channel_delay", "mains_pickup"}
    assert d["verdict"] == "explained"
    assert d["final"]["nrmse"] <= 1.5 * d["final"]["noise_floor_nrmse"]
    assert [s["nrmse"] for s in d["steps"]] == sorted((s["nrmse"] for s in d["steps"]), reverse=True)


def test_configured_effect_is_fitted_beside_the_baseline(ci_config):
    """model.effects = [channel_delay] on a record with that delay: the configured model is at the floor."""
    d = run(ci_config, HIDDEN["channel_delay"][0], effects=("channel_delay",))
    assert d["configured"]["effects"] == ["channel_delay"]
    assert d["configured"]["nrmse"] <= 1.5 * d["configured"]["noise_floor_nrmse"] < d["baseline"]["nrmse"]
    assert "channel_delay" not in [r["effect"] for r in d["ranking"]]
    assert d["selected"] == [] and d["verdict"] == "explained"
    assert d["steps"][0]["effects"] == ["channel_delay"]


def ringing_record(config: dict, f_n: float = 35.0, zeta: float = 0.03):
    """A reference sensor on a fixture with a mode outside the catalogue.

    The PZT sits on a 0.2 kg holder on a rubber pad (k = 1e4 N/m, 3% damping) above the reference
    sensor: the reference reads the force through the holder's mode at sqrt(k/m)/2pi = 35 Hz, the PZT
    without it. Force channel: F through the second-order low-pass; voltage: Eq. 6 of F.
    """
    p = PressProtocol.from_config(config["synthesis"])
    rng = np.random.default_rng(config["seed"])
    t, f = press_force(p, rng)
    dt = t[1] - t[0]
    w = 2 * np.pi * f_n
    b, a, _ = cont2discrete(([w**2], [1, 2 * zeta * w, w**2]), dt, method="bilinear")
    f_ref = lfilter(b.ravel(), a, f)
    v = circuit_voltage(f, dt, nominal_circuit(config))
    return t, f_ref + rng.normal(0, p.force_noise_N, t.size), v + rng.normal(0, p.voltage_noise_V, t.size)


_RING: dict = {}


def test_effect_outside_the_catalogue_is_unexplained_at_its_frequency(paper_config):
    """The paper's 25 s record: its spectrum resolves the 35 Hz mode to the "35." the report is asserted to
    name; on the CI record (12 s, 6 spectral segments) the peak reads 34.19 Hz."""
    rec = _RING.setdefault("r", ringing_record(paper_config))
    d = run(paper_config, [], record=rec)
    assert d["verdict"] == "unexplained"
    peaks = [f for f in d["unexplained"] if f["test"] == "spectrum" and f["kind"] == "narrowband"]
    assert peaks and min(abs(f["frequency_Hz"] - 35.0) for f in peaks) < 1.0
    assert "35." in " ".join(f["where"] for f in d["unexplained"])
    # where in time: at the presses (windows inside impulses)
    assert any(f["test"] == "time_window" and f.get("impulse") for f in d["unexplained"])
    assert "reference_lag" not in d["selected"] or d["verdict"] == "unexplained"


def test_diagnosis_json_interface(ci_config):
    d = run(ci_config, HIDDEN["mains_pickup"][0])
    assert {"nrmse", "params"} <= set(d["baseline"])
    assert d["noise_floor_nrmse"] > 0
    for r in d["ranking"]:
        assert {"effect", "delta_bic", "nrmse", "params"} <= set(r)
    # best first; within a BIC tie (< 2) an effect may follow the one it declares itself equivalent to
    # (d33_scale after extra_capacitance: the same record, see selection.yield_ties)
    rk = d["ranking"]
    for ra, rb in zip(rk[:-1], rk[1:], strict=True):
        a, b = ra["delta_bic"], rb["delta_bic"]
        assert a >= b or (b - a < 2.0 and {ra["effect"], rb["effect"]} == {"d33_scale", "extra_capacitance"})
    for s in d["steps"]:
        assert {"effects", "nrmse", "bic"} <= set(s)
    assert d["verdict"] in ("explained", "unexplained") and isinstance(d["unexplained"], list)
    assert isinstance(d["selected"], list)
    # every free parameter of the final fit has an interval whose Jacobian form was checked (or profiled)
    iv = d["identifiability"]["intervals"]
    assert "resistance_ohm" in iv and "mains_h1_sin_V" in iv and set(iv) <= set(d["final"]["params"])
    for name, i in iv.items():
        assert i["method"] in ("jacobian (checked)", "profile", "jacobian (not honest; not profiled)")
        assert i["ci"][0] <= d["final"]["params"][name] <= i["ci"][1]
        assert d["final"]["ci95"][name] == i["ci"]


# --------------------------------------------------------------------------- the subject interface


def test_calibration_is_a_subject_whose_synthesiser_hides_what_the_engine_finds(ci_config):
    """The calibration subject end to end through its interface: synthesise with a hidden 15 ms
    channel delay, build the problem, run the engine, and the answer names the delay."""
    from piezobearing.diagnosis.calibration.subject import SUBJECT
    from piezobearing.diagnosis.subject import Problem, Subject

    assert isinstance(SUBJECT, Subject)
    obs = SUBJECT.synthesise(ci_config, ci_config["seed"], HIDDEN["channel_delay"][0])
    p = SUBJECT.problem(obs, ci_config)
    assert isinstance(p, Problem) and len(p.segments) == len(obs[1]) >= 2
    assert [q.name for q in p.baseline.params(p.record)] == ["resistance_ohm"]
    _, d = SUBJECT.diagnose(obs, ci_config)
    assert d["winner"]["effect"] == "channel_delay"
    assert d["winner"]["params"]["delay_s"] == pytest.approx(0.015, abs=5e-4)
    assert len(d["per_impulse"]["final"]) == len(obs[1])
    assert "Most likely missing: `channel_delay`" in SUBJECT.report(d, {})


def test_residual_tests_without_a_measured_input():
    """A subject without a measured input (a running bearing): the input-correlation test passes empty,
    the others still find a tone, and the report's test line leaves the correlation out."""
    from piezobearing.diagnosis.report.sections import tests_line

    rng = np.random.default_rng(5)
    dt, n = 1e-3, 20000
    t = np.arange(n) * dt
    e = rng.normal(size=n) + 0.3 * np.sin(2 * np.pi * 41.0 * t)
    tests = residual_tests(e, None, dt, DiagnosticsSettings())
    assert tests.uncorrelated and tests.xcf.size == 0 and not tests.passed
    f = findings(tests)
    assert f[0]["test"] == "spectrum" and abs(f[0]["frequency_Hz"] - 41.0) < 0.1
    assert "input_correlation" not in {x["test"] for x in f}
    line = tests_line(tests.summary())
    assert "correlation" not in line and "1 spectral region(s)" in line


# --------------------------------------------------------------------------- identifiability


def test_strength_follows_kass_and_raftery():
    from piezobearing.diagnosis.selection import strength

    assert [strength(x) for x in (0.5, 2.5, 7.0, 16.0, 5000.0)] == [
        "weak",
        "positive",
        "strong",
        "decisive",
        "decisive",
    ]
    assert strength(-3.0) == "weak" and strength(None) is None


def test_every_step_names_its_runner_up_and_margin(ci_config):
    """Hidden 100 pF: the step that adds it names the second-best candidate and the margin over it,
    the margin is the difference of the two BIC drops of the first ranking, and the final fit's
    correlations come from the Jacobian (symmetric, unit diagonal, R and C strongly tied)."""
    from piezobearing.diagnosis.calibration.report import render

    d = run(ci_config, HIDDEN["extra_capacitance"][0])
    idf = d["identifiability"]
    st = idf["steps"][0]
    assert st["added"] == "extra_capacitance" and st["runner_up"] == d["ranking"][1]["effect"]
    assert st["margin_bic"] == pytest.approx(d["ranking"][0]["delta_bic"] - d["ranking"][1]["delta_bic"])
    assert st["strength"] == "decisive" and st["margin_strength"] in ("decisive", "strong", "positive", "weak")
    corr = idf["correlation"]
    assert set(corr) == {"resistance_ohm", "extra_capacitance_F"}
    for a in corr:
        assert corr[a][a] == pytest.approx(1.0)
        for b in corr:
            assert corr[a][b] == pytest.approx(corr[b][a]) and abs(corr[a][b]) <= 1 + 1e-9
    assert idf["stop"]["best"] != "extra_capacitance" and idf["stop"]["delta_bic"] < 10
    text = render(d)
    assert "How firmly the record decides" in text and f"`{st['runner_up']}`" in text


def test_clean_record_says_how_strongly_it_speaks_against_the_best_candidate(ci_config):
    d = run(ci_config, [])
    idf = d["identifiability"]
    assert idf["steps"] == []
    assert idf["stop"]["best"] == d["ranking"][0]["effect"]
    assert idf["stop"]["strength"] in ("weak", "positive")
    assert list(idf["correlation"]) == ["resistance_ohm"] and idf["correlated_pairs"] == []


def test_d33_scale_is_found_as_the_same_record_as_extra_capacitance(ci_config):
    """d33 15% below the datasheet (batch tolerance, ageing): the record cannot tell it from 46 pF of
    extra capacitance (C (1/k - 1) at C = 261 pF), so the two tie at the top of the ranking, the
    diagnosis states the exact equivalence, and both fitted values map onto the hidden k."""
    from piezobearing.diagnosis.calibration.report import render

    k = CATALOGUE["d33_scale"].example["d33_scale_ratio"]  # 0.85
    d = run(ci_config, [{"name": "d33_scale", "params": {"d33_scale_ratio": k}}])
    top = {r["effect"]: r for r in d["ranking"][:2]}
    assert set(top) == {"d33_scale", "extra_capacitance"}
    assert abs(top["d33_scale"]["delta_bic"] - top["extra_capacitance"]["delta_bic"]) < 2.0
    assert d["ranking"][0]["effect"] == "extra_capacitance"  # the declaring effect yields the tie
    assert d["identifiability"]["steps"][0]["margin_strength"] == "weak"
    assert d["verdict"] == "explained" and len(d["selected"]) == 1
    fit_k = top["d33_scale"]["params"]["d33_scale_ratio"]
    lo, hi = top["d33_scale"]["ci95"]["d33_scale_ratio"]
    assert fit_k == pytest.approx(k, rel=0.01) and lo <= k <= hi
    c0 = nominal_circuit(ci_config).capacitance_F
    assert top["extra_capacitance"]["params"]["extra_capacitance_F"] == pytest.approx(c0 * (1 / k - 1), rel=0.03)
    eq = d["identifiability"]["equivalences"]
    assert eq and set(eq[0]["effects"]) == {"d33_scale", "extra_capacitance"}
    assert "R d33 and d33/C" in eq[0]["statement"] and "R d33 and d33/C" in render(d)


def test_clock_drift_is_found_first_with_the_hidden_rate(ci_config):
    """Two DAQ quartz clocks 100 ppm apart (+-50 ppm each): the offset grows to 1.2 ms over the 12 s record
    (2.5 ms over the paper's 25 s). Measured on the CI record: 97.9 ppm, interval -6% / +1.8% of the truth."""
    ppm = CATALOGUE["clock_drift"].example["clock_drift_ppm"]  # 100 ppm
    d = run(ci_config, [{"name": "clock_drift", "params": {"clock_drift_ppm": ppm}}])
    assert d["ranking"][0]["effect"] == "clock_drift" and d["selected"][0] == "clock_drift"
    assert d["verdict"] == "explained"
    est = d["final"]["params"]["clock_drift_ppm"]
    lo, hi = d["final"]["ci95"]["clock_drift_ppm"]
    assert est == pytest.approx(ppm, rel=0.05) and lo - 5 <= ppm <= hi + 5
    assert d["identifiability"]["steps"][0]["runner_up"] is not None


def test_sensitivity_drift_is_found_first_with_the_hidden_slope(ci_config):
    """A gain rising by 2e-3 /s: 2.4% over the 12 s record (5% over the paper's 25 s; a size chosen to be
    detectable at this noise on the paper's record, larger than a typical thermal drift: say so, not tuned to
    pass). Measured on the CI record: +1.4% off the truth, interval -1.3% / +4.1%."""
    slope = CATALOGUE["sensitivity_drift"].example["sensitivity_slope_per_s"]  # 2e-3 /s
    d = run(ci_config, [{"name": "sensitivity_drift", "params": {"sensitivity_slope_per_s": slope}}])
    assert d["ranking"][0]["effect"] == "sensitivity_drift" and d["selected"][0] == "sensitivity_drift"
    assert d["verdict"] == "explained"
    est = d["final"]["params"]["sensitivity_slope_per_s"]
    lo, hi = d["final"]["ci95"]["sensitivity_slope_per_s"]
    assert est == pytest.approx(slope, rel=0.05) and lo - 1e-4 <= slope <= hi + 1e-4


def test_noise_follows_the_signal_through_the_fitted_nonlinear_path(paper_config):
    """beta = 5e-3 1/N hidden (+10% sensitivity at 10 N, seed 3): the correct model carries the force noise with
    the gain 1 + 2 beta F(t), so the residual is louder at the press peaks. Whitened with a stationary floor its
    energy in one window on a press's flank is 1.8x the floor and the window test fails (the correct model would
    be `unexplained`); with the model's noise envelope h(t) (rms 1, largest at the peaks) every test passes.
    The paper's record (one fit, 0.1 s): on the CI record the stationary floor's windows pass too, so the
    record would not show the envelope's point."""
    from piezobearing.diagnosis.calibration.effects import CATALOGUE
    from piezobearing.diagnosis.calibration.subject import calibration_problem
    from piezobearing.diagnosis.fit import finish, fit_model

    c = paper_config
    beta = 5e-3
    m = synthesize(
        PressProtocol.from_config(c["synthesis"]),
        nominal_circuit(c),
        3,
        [{"name": "d33_nonlinearity", "params": {"beta_per_N": beta}}],
    )
    rec, v = ForceRecord(m.time_s, m.force_N), m.voltage_V
    settings = DiagnosticsSettings.from_config(c["diagnostics"])
    imps = detect_impulses(m.force_N, v, rec.dt_s, 0.2, 0.8)
    p = calibration_problem(rec, v, nominal_circuit(c, c["calibration"]["initial_resistance_ohm"]), [], settings, imps)
    model = p.baseline.with_effect(CATALOGUE["d33_nonlinearity"])
    f = fit_model(model, rec, v, p.floor, start={"beta_per_N": beta}, max_nfev=settings.max_nfev, ftol=settings.ftol)
    assert f.values["beta_per_N"] == pytest.approx(beta, rel=0.02)
    h = f.scale
    assert h is not None and np.mean(h**2) == pytest.approx(1.0, rel=1e-9)
    peak = max(imps, key=lambda i: i.force_peak_N).force_peak_index
    assert h[peak] > 1.05 > 0.98 > h[np.argmin(m.force_N)]  # louder at the highest press than at rest
    assert f.result.log_det < 0  # sum ln h^2 <= 0 for mean h^2 = 1 (Jensen)

    def tests_of(whitened):
        return residual_tests(whitened, rec.force_N, rec.dt_s, settings, p.segments, rec.time_s)

    stationary = finish(model, rec, v, p.floor, f.result)  # the same fit, the noise assumed stationary
    assert not tests_of(stationary.whitened).windows_ok
    assert tests_of(f.whitened).passed
