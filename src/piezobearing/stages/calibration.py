"""Stage functions of the calibration chain (Sec. II, III-B/C; Fig. 5, 6, 8a)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..diagnosis.calibration.record import read_record
from ..diagnosis.least_squares import nrmse
from ..io import Measurement, read_json, write_json, write_measurement
from ..sensor import calibration as cal
from ..sensor.lowfreq import asymptote_onset_Hz, lowfreq_sensitivity
from ..synthesis import PressProtocol, synthesize


def nominal_circuit(config: dict, resistance_ohm: float | None = None) -> cal.SensorCircuit:
    """The sensor circuit of the config, with R from the synthesis truth unless given."""
    r = config["synthesis"]["resistance_ohm"] if resistance_ohm is None else resistance_ohm
    return cal.SensorCircuit.from_config(config["sensor"], r)


def synthesize_calibration(config: dict, out_csv: str) -> None:
    """Write the synthetic calibration record (results/calibration/measurement.csv)."""
    syn = config["synthesis"]
    m = synthesize(
        PressProtocol.from_config(syn), nominal_circuit(config), config["seed"], syn["hidden_effects"]
    )
    write_measurement(m, out_csv)


def load_record(path: str, config: dict) -> tuple[Measurement, list[cal.Impulse]]:
    """Read and check a calibration record and detect its impulses (the calibration subject's reader,
    :func:`piezobearing.diagnosis.calibration.record.read_record`)."""
    return read_record(path, config)


def _checks_digest(path: str, config: dict) -> str:
    """What a record's check depends on: its content, the settings the checks read, the checking code."""
    import hashlib
    import json
    from pathlib import Path

    from .. import io
    from ..diagnosis.calibration import record
    from ..sensor import calibration as sensor_cal

    h = hashlib.sha256(io.file_digest(path).encode())
    h.update(
        json.dumps({k: config[k] for k in ("calibration", "sensor")}, sort_keys=True, default=str).encode()
    )
    for mod in (io, record, sensor_cal):
        h.update(Path(mod.__file__).read_bytes())
    h.update(Path(__file__).read_bytes())
    return h.hexdigest()


def check_record_once(path: str, config: dict, cache_dir: str) -> dict:
    """:func:`load_record`'s checks, done once per record content and settings.

    The workflow checks the user's record at every start (even ``-n``); a
    record that passed is remembered in ``cache_dir``/<digest>.json, keyed by
    the SHA-256 of the file's content, the calibration and sensor settings
    and the checking code, so an unchanged 200 MB record costs one hash per
    start, not a parse. Failures are not cached. Returns the summary.
    """
    import json
    from pathlib import Path

    from ..io import check_readable

    check_readable(Path(path), text=False)  # a folder or unreadable file: one line before hashing
    key = _checks_digest(path, config)
    memo = Path(cache_dir) / f"{key}.json"
    if memo.is_file():
        try:
            return json.loads(memo.read_text())
        except (OSError, json.JSONDecodeError):
            pass
    m, imps = load_record(path, config)
    summary = {
        "measurement": str(path),
        "rows": int(m.time_s.size),
        "sample_rate_Hz": m.sample_rate_Hz,
        "impulses": len(imps),
    }
    try:
        write_json(summary, memo)
    except OSError:
        pass  # a read-only results/ only costs the next start another check
    return summary


def extract_sensitivity(measurement_csv: str, out_json: str, config: dict) -> None:
    """Peak voltage over peak force per impulse → results/calibration/sensitivity.json."""
    m, imps = load_record(measurement_csv, config)
    out = cal.sensitivity_summary(imps, m.time_s)
    for d, imp in zip(out["impulses"], imps, strict=True):
        d.update(
            time_voltage_peak_s=float(m.time_s[imp.voltage_peak_index]),
            window_s=[float(m.time_s[imp.start]), float(m.time_s[imp.stop - 1])],
        )
    out.update(
        source=m.source, sample_rate_Hz=m.sample_rate_Hz, config={"calibration": config["calibration"]}
    )
    write_json(out, out_json)


def fit_resistance(measurement_csv: str, out_json: str, out_csv: str, config: dict) -> None:
    """Fit R of Eq. 6 → resistance.json and the simulated voltage (fit.csv)."""
    m, _ = load_record(measurement_csv, config)
    circuit = nominal_circuit(config)
    res = cal.fit_resistance(
        m.force_N, m.voltage_V, m.dt_s, circuit, config["calibration"]["initial_resistance_ohm"]
    )
    r = res.values["resistance_ohm"]
    fitted = circuit.with_resistance(r)
    sim = cal.circuit_voltage(m.force_N, m.dt_s, fitted)
    write_json(
        {
            "resistance_ohm": r,
            "resistance_ci95_ohm": res.ci95["resistance_ohm"],
            "resistance_stderr_ohm": res.stderr["resistance_ohm"],
            "nrmse": nrmse(res.residual, m.voltage_V),
            "residual_rms_V": float(np.sqrt(np.mean(res.residual**2))),
            "pzt_capacitance_F": fitted.pzt_capacitance_F,
            "cable_capacitance_F": fitted.cable_capacitance_F,
            "capacitance_F": fitted.capacitance_F,
            "tau_s": fitted.tau_s,
            "open_circuit_gain_V_per_N": fitted.open_circuit_gain_V_per_N,
            "fit": res.report(),
            "source": m.source,
            "config": {"sensor": config["sensor"], "calibration": config["calibration"]},
        },
        out_json,
    )
    pd.DataFrame(
        {"time_s": m.time_s, "force_N": m.force_N, "voltage_V": m.voltage_V, "simulated_voltage_V": sim}
    ).to_csv(out_csv, index=False, float_format="%.9g")


def lowfreq(resistance_json: str, out_json: str, out_csv: str, config: dict) -> None:
    """Sensitivity against frequency from the fitted model → results/sensor/lowfreq.{json,csv}."""
    r = read_json(resistance_json)["resistance_ohm"]
    circuit = nominal_circuit(config, r)
    thr = config["lowfreq"]["deviation_threshold"]
    lf = lowfreq_sensitivity(config["lowfreq"]["frequencies_Hz"], circuit, thr)
    write_json(
        {
            "linear_from_Hz": lf.linear_from_Hz,
            "reference_sensitivity_V_per_N": lf.reference_sensitivity_V_per_N,
            "open_circuit_sensitivity_V_per_N": lf.asymptote_V_per_N,
            "asymptote_within_threshold_from_Hz": asymptote_onset_Hz(circuit, thr),
            "deviation_threshold": thr,
            "resistance_ohm": r,
            "tau_s": circuit.tau_s,
            "config": {"sensor": config["sensor"], "lowfreq": config["lowfreq"]},
        },
        out_json,
    )
    pd.DataFrame(
        {
            "frequency_Hz": lf.frequency_Hz,
            "sensitivity_V_per_N": lf.sensitivity_V_per_N,
            "deviation_next": lf.deviation_next,
            "deviation_asymptote": lf.deviation_asymptote,
        }
    ).to_csv(out_csv, index=False, float_format="%.9g")
