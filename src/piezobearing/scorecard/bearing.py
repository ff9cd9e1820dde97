"""Scorecard rows of the bearing and its housing (Sec. III-A, IV): the paper's numbers (:mod:`piezobearing.config.paper`)
beside the LPM's, the housing model's and the verification studies'."""

from __future__ import annotations

from ..config.paper import KINEMATICS, RUNNING, TABLE
from . import Row


def rows(kin: dict, lpm: dict, tr: dict, conv: dict, samp: dict, b: dict) -> list[Row]:
    """The rows from kinematics.json, lpm.json, the transient records by case, mesh_convergence.json,
    sampling_phase.json and the config's ``bearing`` section."""
    # longer than 80 lines: a table, one Row literal a paper number, read top to bottom like the scorecard
    chk = tr["healthy"]["direct_check"] or {}
    groove = next((d for d in b["defects"] if d["type"] == "outer_race"), None)  # the paper's defect
    per_period = 1 / (kin["bpfo_Hz"] * b["time_step_s"])  # FEM steps per roller passage (BPFO period)
    return [
        Row(
            "IV",
            f"BPFO at {b['shaft_speed_rpm']:g} rpm",
            TABLE["bpfo_Hz"].value,
            kin["bpfo_Hz"],
            "Hz",
            f"{b['n_rollers']} rollers, D_r/D_p = {b['roller_diameter_m'] * 1e3:g}/{b['pitch_diameter_m'] * 1e3:g} mm "
            "(the paper's BPFO fixes 10/44; docs/theory/bearing_housing.md); FTF x Z",
            KINEMATICS,
        ),
        Row("IV", "rollers", TABLE["n_rollers"].value, float(b["n_rollers"]), "-", "config bearing.n_rollers",
            ("bearing.n_rollers",)),
        Row(
            "IV",
            "radial load",
            TABLE["radial_load_N"].value,
            b["radial_load_N"],
            "N",
            f"mean vertical roller load over the healthy record {lpm['healthy']['mean_vertical_load_N']:.2f} N",
            ("bearing.radial_load_N",),
        ),
        Row("IV", "shaft speed", TABLE["shaft_speed_rpm"].value, b["shaft_speed_rpm"], "rpm", "",
            ("bearing.shaft_speed_rpm",)),
        Row(
            "III-A",
            "FEM time step",
            TABLE["time_step_s"].value,
            b["time_step_s"],
            "s",
            f"1/(36 BPFO) = {1 / (36 * kin['bpfo_Hz']):.7g} s at this run's BPFO of {kin['bpfo_Hz']:.4g} Hz; the "
            f"configured step gives {per_period:.4g} steps per roller passage"
            + (
                ": every sample at the same phase of the passage"
                if abs(per_period - round(per_period)) < 1e-3
                else ": the sampling phase drifts from passage to passage"
            ),
            ("bearing.time_step_s",),
        ),
        Row(
            "III-A",
            "defect width",
            TABLE["defect_width_m"].value,
            groove["width_m"] if groove else None,
            "m",
            (
                f"a roller sinks at most {lpm['faulty']['defect_max_drop_m'] * 1e6:.1f} um against the concave "
                f"raceway ({lpm['faulty']['defects'][0]['max_drop_flat_raceway_m'] * 1e6:.1f} um on a flat one), "
                "not the 1 mm depth"
                if groove
                else "no outer-race defect configured"
            ),
            ("bearing.defects",),
        ),
        Row(
            "III-A",
            "defect depth (removed material)",
            TABLE["defect_depth_m"].value,
            groove["depth_m"] if groove else None,
            "m",
            "",
            ("bearing.defects",),
        ),
        Row(
            "IV",
            "defect impact frequency (LPM)",
            TABLE["bpfo_Hz"].value,
            lpm["faulty"].get("impact_frequency_Hz"),
            "Hz",
            f"{lpm['faulty']['n_impacts']} impacts; paper's BPFO for comparison"
            if "n_impacts" in lpm["faulty"]
            else "the first configured defect is not on the outer race",
            RUNNING,
        ),
        Row(
            "III-A",
            "Harris discrete load distribution vs LPM (max rel. diff.)",
            None,
            max(
                lpm["healthy"]["harris_roller_at_bottom"]["max_rel_diff"],
                lpm["healthy"]["harris_rollers_straddling"]["max_rel_diff"],
            ),
            "-",
            f"radial clearance {b['radial_clearance_m'] * 1e6:.0f} um",
        ),
        Row(
            "III-A",
            "housing model: first natural frequency",
            None,
            tr["healthy"]["first_natural_frequency_Hz"],
            "Hz",
            f"{'above' if tr['healthy']['first_natural_frequency_Hz'] > 0.5 / b['time_step_s'] else 'below'} the "
            f"{0.5 / b['time_step_s']:.0f} Hz Nyquist frequency of the FEM time step",
        ),
        Row(
            "IV",
            "sensor force, healthy: mean",
            None,
            tr["healthy"]["sensor_force_mean_N"],
            "N",
            "the paper shows voltage only (Fig. 9)",
        ),
        Row(
            "IV",
            "sensor force, healthy: peak-to-peak",
            None,
            tr["healthy"]["sensor_force_max_N"] - tr["healthy"]["sensor_force_min_N"],
            "N",
            "",
        ),
        Row(
            "IV",
            "sensor force, faulty: peak-to-peak",
            None,
            tr["faulty"]["sensor_force_max_N"] - tr["faulty"]["sensor_force_min_N"],
            "N",
            "",
        ),
        Row(
            "III-A",
            "reduced vs direct FEM, healthy (RMS rel. diff.)",
            None,
            chk.get("rms_rel_diff", float("nan")),
            "-",
            f"over {chk.get('duration_s', float('nan')):.3g} s; sfepy generalized-alpha reference",
        ),
        Row(
            "III-A",
            "mesh convergence: peak-to-peak change to finest level",
            None,
            float(conv["levels"][1]["peak_to_peak_N"] / conv["levels"][2]["peak_to_peak_N"] - 1),
            "-",
            f"levels {[r['level'] for r in conv['levels']]}, {[r['n_dofs'] for r in conv['levels']]} DOFs",
        ),
        Row(
            "III-A",
            "sampling phase: spread of the faulty BPFO amplitude, point sampling",
            None,
            samp["sample"]["bpfo_amplitude_spread"],
            "-",
            "max/min - 1 over the 36 phases of a step",
        ),
        Row(
            "III-A",
            "sampling phase: spread of the faulty BPFO amplitude, step averaging",
            None,
            samp["average"]["bpfo_amplitude_spread"],
            "-",
            "what the workflow uses (bearing.resample)",
        ),
    ]
