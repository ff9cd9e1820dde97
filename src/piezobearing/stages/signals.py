"""Stage functions from the sensor force to fault detection (Sec. IV; Fig. 9, 10).

sensor_voltage (force -> voltage through the calibrated RC model, optionally
scaled to the sensor FEM), noisy (the DAQ: sampling, noise), envelope (band,
envelope spectrum), indicator (fault_indicator.json: the paper's indicator and
the configured detector, :mod:`piezobearing.signals.detectors`), classification,
snr_study (detection against SNR over noise seeds) and defect_events (Fig. 9
markers). Each reads its files, calls one function (the chain's are in
:mod:`piezobearing.chain.signals`, which the parameter studies call too) and
writes what it returns.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ..chain import signals as outputs
from ..chain.signals import true_fault_type  # noqa: F401 (the stage's name for it)
from ..io import (
    SERIES_UNIFORM_RTOL,
    SignalFileError,
    read_harmonic,
    read_json,
    read_kinematics,
    read_series,
    table_series,
    write_csv,
    write_json,
)
from ..sensor.calibration import SensorCircuit
from ..signals import detection
from ..signals.analysis import band_rules, snr_grid, snr_study_record, snr_summary
from ..signals.envelope import EnvelopeSettings

#: Largest relative deviation of a time step from the mean step of a record.
UNIFORM_RTOL = SERIES_UNIFORM_RTOL
kinematics = read_kinematics


# --------------------------------------------------------------------------- sensor voltage


def sensor_circuit(config: dict, resistance_json: str) -> tuple[SensorCircuit, dict]:
    """The calibrated sensor circuit (R from the fit) and the resistance record."""
    res = read_json(resistance_json)
    return outputs.sensor_circuit(config, res, resistance_json), res


def sensor_voltage(
    force_csv: str, resistance_json: str, harmonic_csv: str | None, out_csv: str, out_json: str, config: dict
) -> None:
    """Sensor force through the calibrated sensor model → voltage_{case}.{csv,json}
    (:func:`piezobearing.chain.signals.sensor_voltage`; the FEM's response where ``harmonic_csv``)."""
    t, force, dt = read_series(force_csv, "force_N")
    circuit, _ = sensor_circuit(config, resistance_json)
    harmonic = read_harmonic(harmonic_csv) if harmonic_csv else None
    table, record = outputs.sensor_voltage(t, force, dt, circuit, harmonic, config, str(force_csv))
    write_csv(table, out_csv)
    write_json({**record, "source": str(force_csv), "config": {"sensor": config["sensor"], "signals": config["signals"]}},
               out_json)


# --------------------------------------------------------------------------- noise


def noisy(voltage_csv: str, case: str, out_csv: str, out_json: str, config: dict) -> None:
    """The DAQ: sampling at signals.sample_rate_Hz and noise → noisy_{case}.{csv,json}
    (:func:`piezobearing.chain.signals.noisy`)."""
    table, record = outputs.noisy(*read_series(voltage_csv, "voltage_V"), case, config)
    write_csv(table, out_csv)
    write_json(record, out_json)


# --------------------------------------------------------------------------- envelope


def envelope(
    noisy_csv: str, voltage_csv: str, kinematics_json: str, out_csv: str, out_json: str, config: dict
) -> None:
    """Band (kurtogram or fixed), envelope spectrum → envelope_{case}.{csv,json}
    (:func:`piezobearing.chain.signals.envelope`)."""
    df = pd.read_csv(noisy_csv)
    _, y, dt = table_series(df, "voltage_V", noisy_csv)
    _, v, _ = table_series(df, "noiseless_V", noisy_csv)  # the sampled noiseless record, on the DAQ clock
    table, record = outputs.envelope(y, v, dt, kinematics(kinematics_json), config)
    write_csv(table, out_csv)
    write_json(record, out_json)


def indicator(envelope_jsons: dict, kinematics_json: str, noisy_csvs: dict, noisy_jsons: dict, out_json: str,
              config: dict) -> None:
    """The paper's indicator and the configured detector on each case's noisy record → fault_indicator.json
    (:func:`piezobearing.chain.signals.fault_indicator`).

    ``envelope_jsons``, ``noisy_csvs`` and ``noisy_jsons`` map each case to its envelope record, its noisy
    table (voltage_V, noiseless_V) and its noisy record.
    """
    records = {}
    for case, csv in noisy_csvs.items():
        df = pd.read_csv(csv)
        _, y, dt = table_series(df, "voltage_V", csv)
        _, v, _ = table_series(df, "noiseless_V", csv)
        records[case] = (y, v, dt, read_json(noisy_jsons[case]))
    envelopes = {case: read_json(js) for case, js in envelope_jsons.items()}
    write_json(outputs.fault_indicator(envelopes, kinematics(kinematics_json), records, config), out_json)


# --------------------------------------------------------------------------- SNR study


def snr_study(voltages: dict, kinematics_json: str, out_csv: str, out_summary: str, out_json: str, config: dict):
    """Detection against SNR over noise seeds, healthy and faulty → snr_study{,_summary}.csv, snr_study.json.

    Runs the configured band rule and, for comparison, the other one
    (kurtogram vs fixed band) on the same noise records.
    """
    s = config["signals"]
    f0 = kinematics(kinematics_json)["bpfo_Hz"]
    ins = detection.IndicatorSettings.from_config(s)
    grid = snr_grid(s)
    rows = []
    for rule in band_rules(s):
        es = EnvelopeSettings.from_config(dict(s, band_rule=rule))
        for case, path in voltages.items():
            _, v, dt = read_series(path, "voltage_V")
            print(f"snr_study: {rule}, {case}, {len(grid)} SNRs x {s['study_n_seeds']} seeds", file=sys.stderr,
                  flush=True)
            rows += [dict(r, band_rule=rule)
                     for r in detection.snr_sweep(v, dt, f0, case, grid, s["study_n_seeds"], config["seed"], es, ins)]
    df = pd.DataFrame(rows)
    write_csv(df, out_csv)
    summ = snr_summary(df)
    write_csv(summ, out_summary)
    out = snr_study_record(df, summ, list(voltages), grid, s)
    out["config"] = {"seed": config["seed"], "signals": s}
    write_json(out, out_json)


def snr_study_figure(summary_csv: str, study_json: str, out_png: str) -> None:
    """Plot the detection rate against SNR → results/figures/snr_study.png."""
    # matplotlib's import (2 s) only in the job that plots
    from ..plotting import save, use_style
    from ..plotting.signals import snr_study as plot

    use_style()
    save(plot(pd.read_csv(summary_csv), read_json(study_json)), out_png)


# --------------------------------------------------------------------------- events and scorecard


def defect_events(healthy_csv: str, faulty_csv: str, kinematics_json: str, out_csv: str) -> None:
    """Times of the defect impulses (largest |faulty - healthy| per BPFO period) → defect_events.csv."""
    th, vh, dt = read_series(healthy_csv, "voltage_V")
    tf, vf, _ = read_series(faulty_csv, "voltage_V")
    if th.size != tf.size or abs(th[0] - tf[0]) > UNIFORM_RTOL * dt:
        raise SignalFileError(f"{faulty_csv}: time base differs from {healthy_csv}; simulate both cases alike")
    f0 = kinematics(kinematics_json)["bpfo_Hz"]
    times = detection.defect_event_times(vf, vh, dt, f0, th[0])
    idx = np.round((times - th[0]) / dt).astype(int)
    write_csv(pd.DataFrame({"time_s": times, "voltage_V": vf[idx], "difference_V": vf[idx] - vh[idx]}), out_csv)


# --------------------------------------------------------------------------- fault-type classification


def classification(voltages: dict, kinematics_json: str, out_json: str, out_csv: str, out_roc_csv: str,
                   config: dict, type_voltages: list[str] | None = None) -> None:
    """Fault type over noise seeds and ROC across SNR → classification.json, classification.csv, roc.csv
    (:func:`piezobearing.chain.signals.fault_classification`; ``voltages``: healthy and faulty voltage CSVs;
    ``type_voltages``: rule fault_type_voltage's CSVs, ``voltage_{type}.csv``)."""
    series = {case: read_series(path, "voltage_V")[1:] for case, path in voltages.items()}
    types = {Path(p).stem.removeprefix("voltage_"): read_series(p, "voltage_V")[1:] for p in type_voltages or []}
    record, rows, roc = outputs.fault_classification(series, kinematics(kinematics_json), config, types)
    write_csv(rows, out_csv)
    write_csv(roc, out_roc_csv)
    write_json(record, out_json)
