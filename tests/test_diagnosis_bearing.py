"""The running bearing as the diagnosis engine's second subject: hide each catalogue effect in a
synthetic running-bearing record and find it first, its value inside the 95% interval; a healthy
record selects nothing; a loose part striking once per shaft turn stays unexplained, its frequency named, and is
not a fault.

Records of 0.5 s at 2550 Hz (the paper's clock), default geometry, the housing's influence line of the
CI mesh; the first ranking is what "found first" needs (diagnostics.max_steps = 1).
"""

import copy
import os

import numpy as np
import pytest

from piezobearing.diagnosis.bearing.effects import CATALOGUE, RUNGS
from piezobearing.diagnosis.bearing.subject import SUBJECT, synthesise
from piezobearing.io import BearingRecord, MeasurementError

#: Each effect's plausible size, its ``example`` (the one home of the hidden values; its module says why); the
#: rungs are not ranked by the search (tests/test_diagnosis_bearing_dynamics.py hides them).
HIDDEN = {name: dict(e.example) for name, e in CATALOGUE.items() if name not in RUNGS}


#: The 95% interval's half-width to the 99.9% one (normal quantiles 3.29 / 1.96).
WIDEN = 3.2905 / 1.9600


@pytest.fixture(scope="module")
def setup(ci_config, ci_influence):
    c = copy.deepcopy(ci_config)
    c["bearing_diagnosis"].update(synthetic_duration_s=0.5, synthetic_sample_rate_Hz=2550.0)
    c["diagnostics"]["max_steps"] = 1
    return c, ci_influence


def run(c, influence, hidden, snr_dB, seed=11, tach=False, extra=None):
    c = copy.deepcopy(c)
    c["bearing_diagnosis"].update(synthetic_snr_dB=snr_dB, synthetic_tachometer=tach)
    rec = synthesise(c, seed, hidden, influence)
    if extra is not None:
        rec = BearingRecord(rec.time_s, rec.voltage_V + extra(rec.time_s), rec.speed_rpm, "synthetic", (), rec.clipped)
    return SUBJECT.diagnose((rec, influence), c)[1]


#: The 10 dB cases that run in every test run: where the evidence or the intervals are closest to failing at
#: 10 dB (radial_load over load_share by a BIC margin of 12, load_share over clearance by 24; clearance and
#: mains_pickup with profile-likelihood intervals, mains over the profile budget; the groove's angle the
#: draw that misses by 2.2 half-widths): 18 s of CPU for the five (benchmarks/bench_diagnosis_bearing.py
#: --verify-only). The other five (35 s of CPU for all ten) run with PIEZOBEARING_TEST_10DB=1.
TEN_DB_ALWAYS = ("outer_race_defect", "radial_load", "clearance", "load_share", "mains_pickup")


def cases():
    out = []
    for name in HIDDEN:
        out.append(pytest.param(name, 30.0, id=f"{name}-30dB"))
        skip = name not in TEN_DB_ALWAYS and not os.environ.get("PIEZOBEARING_TEST_10DB")
        marks = pytest.mark.skipif(skip, reason="10 dB case: set PIEZOBEARING_TEST_10DB=1") if skip else ()
        out.append(pytest.param(name, 10.0, id=f"{name}-10dB", marks=marks))
    return out


def misses(d: dict, name: str) -> list[str]:
    """What the hide-and-find check finds wrong in diagnosis ``d`` of a record with ``name`` hidden (empty: passes).

    ``name`` must be ranked first and be the only effect selected, each hidden value inside the 95% interval
    widened to 99.9% (20 such checks at 95% would miss about one by chance; docs/validation/bearing_diagnosis.md
    gives each 95% interval as it is), a defect's fault type named. The benchmark's --verify table uses it too.
    """
    first, out = d["ranking"][0], []
    if first["effect"] != name:
        return [f"ranked first: {[(r['effect'], r['delta_bic']) for r in d['ranking'][:3]]}"]
    if d["selected"] != [name]:
        out.append(f"selected {d['selected']}")
    for k, v in HIDDEN[name].items():
        if k == "roller_defect_index":
            if first["params"][k] != v:
                out.append(f"{k} {first['params'][k]} != {v}")
            continue
        lo, hi = first["ci95"][k]
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * WIDEN
        if not mid - half <= v <= mid + half:
            out.append(f"{k}: hidden {v}, found {first['params'][k]} [{lo}, {hi}] (95%)")
    if name in ("outer_race_defect", "inner_race_defect", "rolling_element_defect"):
        if d["fault"]["type"] != name.replace("_defect", ""):
            out.append(f"fault type {d['fault']['type']}")
    return out


@pytest.mark.slow
@pytest.mark.parametrize(("name", "snr_dB"), cases())
def test_hidden_effect_is_found_first_with_its_value_in_the_interval(setup, name, snr_dB):
    c, influence = setup
    d = run(c, influence, [{"name": name, "params": HIDDEN[name]}], snr_dB, tach=(name == "cage_slip"))
    assert not misses(d, name), misses(d, name)
    if snr_dB == 30.0 and name in ("inner_race_defect", "rolling_element_defect"):
        # their lines fill the spectrum and lift the record's floor 3.5x: the pre-pass measures it on the
        # fault's residual, so the engine runs once, and the final model leaves about that floor
        method = d["noise_floor"]["method"]
        assert "pre-pass" in method and "final model's residual" not in method, method
        assert 0.9 < d["final"]["nrmse"] / d["noise_floor_nrmse"] < 1.1
    if name in ("radial_load", "clearance", "load_share"):
        # the load/clearance/share look-alikes: this record's evidence puts the hidden one first, and the
        # report's section 6 says so and how its interval was found
        ns = next(n for n in d["fault"]["non_separable"] if "radial_clearance_m" in n["set"])
        assert max(ns["evidence"], key=ns["evidence"].get) == name
        key = next(iter(HIDDEN[name]))
        assert d["fault"]["ci_method"][key] == d["identifiability"]["intervals"][key]["method"]
        text = SUBJECT.report({**d, "source": "synthetic"}, {})
        assert "### What this record cannot tell apart" in text
        assert f"| `{key}` |" in text.split("### How each interval of the answer was found")[1]


def test_healthy_record_selects_nothing(setup):
    c, influence = setup
    d = run(c, influence, [], 30.0)
    assert d["selected"] == []
    assert d["verdict"] == "explained"
    assert d["fault"]["type"] == "none"
    assert d["baseline"]["nrmse"] < 1.2 * d["baseline"]["noise_floor_nrmse"]
    how = d["fault"]["ci_method"]
    assert how["radial_load_N"] == "nominal, not fitted"
    assert how["shaft_speed_Hz"] == d["identifiability"]["intervals"]["shaft_speed_Hz"]["method"]


def loose_part(t, f_shaft=1000 / 60, amp=25.0, f_ring=600.0, decay_s=4e-3, t0=0.011):
    """A loose part struck once per shaft turn: a decaying 600 Hz ring at every revolution [V]."""
    out = np.zeros_like(t)
    for tk in np.arange(t0, t[-1], 1 / f_shaft):
        dt = t - tk
        on = dt >= 0
        out[on] += amp * np.exp(-dt[on] / decay_s) * np.sin(2 * np.pi * f_ring * dt[on])
    return out


def test_loose_part_is_unexplained_with_its_frequency_named(setup):
    c, influence = setup
    c = copy.deepcopy(c)
    c["diagnostics"]["max_steps"] = 2
    d = run(c, influence, [], 30.0, extra=loose_part)
    assert d["verdict"] == "unexplained"
    shaft = [u for u in d["unexplained"] if "x shaft" in u["where"] or "shaft)" in u["where"]]
    assert shaft, [u["where"] for u in d["unexplained"]]
    orders = d["orders"]["final"]["peaks"]
    assert any(abs(p["shaft_order"] - round(p["shaft_order"])) < 0.02 and "shaft" in p["named"] for p in orders)
    # its ring's comb at the shaft's orders holds 8 x BPFO = 34 x shaft and lines within reach of 7 and 9 x BPFO:
    # set aside, not a fault's lines
    assert d["fault"]["type"] == "none", d["fault"]["statement"]
    aside = {h["line"] for e in d["fault"]["shaft_comb"] for h in e["lines"]}
    assert "8xBPFO" in aside and "comb of lines at the shaft's orders" in d["fault"]["statement"]
    assert "inner-race defect" in d["fault"]["statement"]  # the one bearing fault locked to the shaft
    text = SUBJECT.report({**d, "source": "synthetic"}, {})
    assert "**No fault named**: 7xBPFO" in text and "comb of lines at the shaft's orders" in text


def test_unknown_hidden_effect_is_one_line(setup):
    c, influence = setup
    c = copy.deepcopy(c)
    c["bearing"]["hidden_effects"] = [{"name": "outer_race_defekt"}]
    with pytest.raises(Exception) as e:
        SUBJECT.check_config(c)
    assert "outer_race_defekt" in str(e.value) and "\n" not in str(e.value)


def test_cli_bad_record_is_one_line(tmp_path, capsys):
    from piezobearing.cli import main

    p = tmp_path / "rig.csv"
    p.write_text("time_s,volts\n0,1\n")
    assert main(["diagnose-bearing", str(p), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "column 'voltage_V' missing" in err[0]
    assert not isinstance(MeasurementError, type(None))


def test_roller_scatter_sine_pattern_is_invisible(setup):
    """Roller diameter deficits b sin(2 pi k / Z) over the roller index are the inner ring displaced
    perpendicular to roller 0: every roller's gap and load is the same, so is the sensor voltage (why
    roller_scatter holds roller Z-1 as a second reference); a cos(2 pi k / Z) - 1 or a second-harmonic
    pattern of the same size is seen."""
    from piezobearing.diagnosis.bearing import chain
    from piezobearing.diagnosis.bearing.subject import rig_from_config

    c, influence = setup
    rig = rig_from_config(c, influence, np.arange(1275) / 2550.0)
    z = rig.geometry.n_rollers
    base = {"start_phase_rad": 0.1, "shaft_speed_Hz": rig.shaft_speed_Hz, "dc_offset_V": 0.0}
    v0 = chain.voltage(rig, base)

    def change(pattern):
        offsets = {f"roller_{k}_offset_m": 2e-6 * pattern(2 * np.pi * k / z) for k in range(1, z)}
        return float(np.sqrt(np.mean((chain.voltage(rig, {**base, **offsets}) - v0) ** 2)))

    seen = min(change(lambda a: np.cos(a) - 1), change(lambda a: np.sin(2 * a)))
    assert seen > 1.0  # V: 4.5 and 10.7 V rms against a 35 V rms record (measured)
    assert change(np.sin) < 2e-3 * seen  # 0.005 V rms: the surrogate's numerics


def test_intervals_carry_the_correlation_factor_and_white_residuals_leave_them(setup):
    """A groove hidden in the model's own record with white noise: with ``interval_correlation: auto`` (the
    default) each final interval reports its factor for the residual's autocorrelation, near 1 here (the residual
    is white; 1.0-1.5 on seeds 11-13: the HAC estimate's scatter where a column lives on a few of the 1275
    samples, such as the groove's dips; at most 1.6 asked), each checked Jacobian interval is the
    white one's times its square root, and the report's interval table shows it; ``off`` gives the intervals of
    white residuals with no factor, and the same search."""
    c, influence = setup
    hidden = [{"name": "outer_race_defect", "params": HIDDEN["outer_race_defect"]}]
    d = run(c, influence, hidden, 30.0)
    off = copy.deepcopy(c)
    off["bearing_diagnosis"]["interval_correlation"] = "off"
    w = run(off, influence, hidden, 30.0)
    assert d["selected"] == w["selected"] == ["outer_race_defect"]
    iv, ivw = d["identifiability"]["intervals"], w["identifiability"]["intervals"]
    assert set(iv) == set(ivw)
    for k, i in iv.items():
        assert 1.0 <= i["correlation_factor"] <= 1.6, (k, i["correlation_factor"])
        assert "correlation_factor" not in ivw[k]
        assert i["jacobian_ci"] == pytest.approx(ivw[k]["jacobian_ci"], rel=1e-9)
        if i["method"] == ivw[k]["method"] == "jacobian (checked)" and k != "start_phase_rad":
            lo, hi = i["ci"]
            wlo, whi = ivw[k]["ci"]
            assert (hi - lo) / (whi - wlo) == pytest.approx(np.sqrt(i["correlation_factor"]), rel=1e-6)
    text = SUBJECT.report({**d, "source": "synthetic"}, {})
    table = text.split("### How each interval of the answer was found")[1]
    assert "correlation factor |" in table.splitlines()[2]
    assert "correlation factor" not in SUBJECT.report({**w, "source": "synthetic"}, {}).split(
        "### How each interval of the answer was found")[1].splitlines()[2]
