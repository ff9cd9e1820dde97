"""Reports in the units their names say: values in the unit of a "shown in" column, intervals with the digits
that show their width, shares as percentages defined in the report and left out where they mean nothing, delta
BIC named as what it is (positive or negative), one unit for the noise floor and the rms of a record."""

from piezobearing.diagnosis.bearing import report as bearing_report
from piezobearing.diagnosis.report import sections


def _rows(lines: list[str]) -> dict[str, list[str]]:
    """A Markdown table's rows by their first cell (backticks removed)."""
    out = {}
    for line in lines:
        if line.startswith("| `"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            out[cells[0].strip("`")] = cells[1:]
    return out


def test_parameters_are_shown_in_the_unit_their_column_names():
    rows = _rows(sections.param_table(
        {"start_phase_rad": 0.12222, "width_m": 0.9e-3, "resistance_ohm": 5.0e7, "dc_offset_V": -0.0177},
        {"width_m": [0.85e-3, 0.95e-3]},
    ))
    assert rows["start_phase_rad"][:2] == ["rad", "0.1222"]  # in radians, as the name says
    assert rows["width_m"] == ["mm", "0.9", "[0.85, 0.95]"]  # in mm, and the column says so
    assert rows["resistance_ohm"][:2] == ["MOhm", "50"]
    assert rows["dc_offset_V"][:2] == ["mV", "-17.7"]


def test_an_interval_has_the_digits_to_show_its_width():
    rows = _rows(sections.param_table({"resistance_ohm": 50.0000e6}, {"resistance_ohm": [49.99951e6, 50.00049e6]}))
    value, interval = rows["resistance_ohm"][1:]
    assert interval == "[49.9995, 50.0005]" and value == "50"  # [50, 50] at four digits
    lo, hi = interval.strip("[]").split(", ")
    assert lo != hi
    assert sections.ci("resistance_ohm", [49.9e6, 50.1e6]) == "[49.9, 50.1]"  # four digits where they suffice


def _entry(**kw) -> dict:
    return {"effect": "x", "delta_bic": 25.0, "excess_explained": 0.8, "nrmse": 0.02, "nrmse_before": 0.05,
            "noise_floor_nrmse": 0.019, "white": True, "summary": "", **kw}


def test_share_explained_only_where_the_effect_helped_a_model_above_its_floor():
    assert sections.share(_entry()) == "80.00%"
    assert sections.share(_entry(delta_bic=-5.1, excess_explained=1.0)) == "-"  # did not help
    assert sections.share(_entry(nrmse_before=0.0317, noise_floor_nrmse=0.0323)) == "-"  # nothing to explain
    assert sections.nrmse_after(_entry()) == "2.00%"
    worse = sections.nrmse_after(_entry(nrmse=1.2533, nrmse_before=0.0318, delta_bic=-7.6e6))
    assert worse.startswith("125.33% (above 3.18% without it")


def _diagnosis(ranking: list[dict]) -> dict:
    return {"configured": {"effects": []}, "ranking": ranking, "winner": None, "dropped_steps": [],
            "settings": {"min_delta_bic": 10.0, "min_share": 0.2, "min_share_if_unexplained": 0.05}}


def test_the_ranking_defines_its_columns_and_calls_delta_bic_by_its_name():
    d = _diagnosis([_entry(effect="cage_slip", delta_bic=-7.6e6, nrmse=1.2533, nrmse_before=0.0318),
                    _entry(effect="radial_load", delta_bic=-5.05, excess_explained=1.0, nrmse_before=0.0317,
                           noise_floor_nrmse=0.0323)])
    text = "\n".join(sections.ranking(d, sections.Figures()))
    assert "BIC drop" not in text and "drop of the Bayesian" not in text
    assert "delta BIC = BIC of the model without the effect minus BIC with it" in text
    assert "Share explained = " in text and "NRMSE = rms(residual) / rms(measured)" in text
    assert "100.00%" not in text  # neither effect helped: no share printed
    assert "share explained: -, 20% needed" in text  # a fraction setting as a percentage
    method = "\n".join(sections.method(d, "- fit", "- tests"))
    assert "delta BIC exceeds 10" in method and "at least 20% of the misfit" in method and "0.2 " not in method


def test_the_bearing_record_states_its_rms_and_noise_floor_in_one_unit():
    d = {"n_samples": 5100, "sample_rate_Hz": 2550.0, "duration_s": 2.0, "n_passages": 70, "voltage_rms_V": 35.88,
         "noise_floor": {"method": "whitened residual", "voltage_noise_V": 1.16},
         "baseline": {"noise_floor_nrmse": 0.0323}}
    text = "\n".join(bearing_report.measurement(d))
    assert "voltage rms 35.88 V" in text and "1.16 V rms" in text and "mV" not in text


def test_no_fault_says_why_where_the_statement_gives_a_reason():
    """Where no fault is named the report gives the statement's reason (a comb at the shaft's orders, lines without
    energy above the floor); a plain "no fault" says the healthy bearing explains the record only where it does."""
    comb = bearing_report.no_fault({"statement": "no fault named: 7xBPFO (30.1 Hz) 12.0 dB above the floor lie on a "
                                                 "comb"}, "unexplained")
    assert comb == "**No fault named**: 7xBPFO (30.1 Hz) 12.0 dB above the floor lie on a comb."
    floor = bearing_report.no_fault({"statement": "no fault: 14xBPFO (991.7 Hz) 9.1 dB above the floor stand above "
                                                  "the floor"}, "unexplained")
    assert floor.startswith("**No fault**: 14xBPFO (991.7 Hz)")
    explained = bearing_report.no_fault({"statement": "no fault"}, "explained")
    assert "the healthy bearing explains the record" in explained
    left = bearing_report.no_fault({"statement": "no fault"}, "unexplained")
    assert "explains the record" not in left and "no fault family's lines" in left
