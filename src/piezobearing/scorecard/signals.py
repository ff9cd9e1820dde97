"""Scorecard rows of the fault detection (Sec. IV): the paper's numbers (:mod:`piezobearing.config.paper`) beside the
indicator's and the SNR study's."""

from __future__ import annotations

from ..config.paper import DETECTION, KINEMATICS, TABLE
from . import Row


def _nan(x) -> float:
    return float("nan") if x is None else float(x)


def rows(ind: dict, st: dict, kin: dict) -> list[Row]:
    """The rows from fault_indicator.json, snr_study.json and the kinematic frequencies [Hz]."""
    snr = st["snr_dB"]
    h, f = ind["healthy"], ind["faulty"]
    n = st["n_seeds"]
    rollers = round(kin["bpfo_Hz"] / kin["ftf_Hz"])  # BPFO = Z x FTF
    return [
        Row("IV", f"BPFO ({rollers} rollers, {60 * kin['shaft_Hz']:g} rpm)", TABLE["bpfo_Hz"].value, kin["bpfo_Hz"],
            "Hz", "from the bearing's kinematics (bearing/kinematics.json)", KINEMATICS),
        Row("IV", "SNR of the added white noise", TABLE["snr"].value, snr, "dB",
            "the paper's 'SNR of 10' read as a power ratio of 10 = 10 dB (as an amplitude ratio it would be "
            "20 dB: also detected, see the study); SNR = mean square of the whole noiseless voltage record over "
            "the noise variance", ("signals.snr_dB",)),
        Row("IV", "outer-ring fault detected, faulty bearing (1 = yes)", 1.0, float(f["detected"]), "-",
            f"envelope-spectrum indicator {f['indicator']:.1f} against threshold {f['threshold']:.1f} "
            f"(pfa {f['false_alarm_probability']:g}), band {f['band_Hz'][0]:.0f}-{f['band_Hz'][1]:.0f} Hz", DETECTION),
        Row("IV", "outer-ring fault detected, healthy bearing (1 = yes)", 0.0, float(h["detected"]), "-",
            f"indicator {h['indicator']:.1f} against threshold {h['threshold']:.1f}",
            tuple(k for k in DETECTION if k != "bearing.defects")),
        Row("IV", f"detection rate, faulty, {n} noise seeds at the SNR", None,
            st["faulty"]["detection_rate_at_snr"], "-", "the paper shows one noise realisation"),
        Row("IV", f"false-alarm rate, healthy, {n} noise seeds at the SNR", None,
            st["healthy"]["detection_rate_at_snr"], "-", ""),
        Row("IV", "lowest SNR with reliable detection (faulty)", None, _nan(st["faulty"]["detection_limit_dB"]), "dB",
            f"detection rate >= {st['required_detection_rate']:g} at this and every higher grid SNR; "
            f"50% detection at {st['faulty']['snr_50pct_dB']:.1f} dB; not studied in the paper"),
        Row("IV", "lowest SNR with healthy false alarms above 5%", None,
            _nan(st["healthy"]["first_snr_rate_above_dB"]), "dB",
            f"band rule {st['band_rule']}; the healthy voltage is BPFO-periodic and keeps a weak in-band part "
            f"({h['in_band_snr_dB']:.0f} dB re the noise at {snr:g} dB), which shows once the noise is low enough; "
            f"with the {st['other_band_rule']['band_rule']} rule false alarms begin at "
            f"{_nan(st['other_band_rule']['healthy']['first_snr_rate_above_dB'])} dB"),
    ]
