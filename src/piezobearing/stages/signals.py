"""Stage functions from the sensor force to fault detection (Sec. IV; Fig. 9, 10).

sensor_voltage (force -> voltage through the calibrated RC model, optionally
scaled to the sensor FEM), noisy (white noise at the configured SNR),
envelope (band, envelope spectrum), indicator (fault_indicator.json),
snr_study (detection against SNR over noise seeds), defect_events (Fig. 9
markers) and the scorecard rows.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ..io import (
    SERIES_UNIFORM_RTOL,
    SignalFileError,
    read_harmonic,
    read_json,
    read_kinematics,
    read_series,
    write_csv,
    write_json,
)
from ..sensor.calibration import SensorCircuit, circuit_voltage, design_resistance_ohm, frequency_response
from ..signals import classification as sclass
from ..signals import daq
from ..signals import detection as sig
from ..signals import detector as sdet
from ..signals.analysis import (
    INDICATOR_DEFINITION,
    band_rules,
    envelope_analysis,
    snr_grid,
    snr_study_record,
    snr_summary,
)

#: Largest relative deviation of a time step from the mean step of a record.
UNIFORM_RTOL = SERIES_UNIFORM_RTOL
kinematics = read_kinematics


# --------------------------------------------------------------------------- sensor voltage


def sensor_circuit(config: dict, resistance_json: str) -> tuple[SensorCircuit, dict]:
    """The calibrated sensor circuit (R from the fit) and the resistance record."""
    res = read_json(resistance_json)
    if "resistance_ohm" not in res:
        raise SignalFileError(f"{resistance_json}: key 'resistance_ohm' missing; rerun rule fit_resistance")
    r = design_resistance_ohm(config["sensor"], res["resistance_ohm"])  # sensor.daq_resistance_ohm, or the fitted R
    return SensorCircuit.from_config(config["sensor"], r), res


def sensor_voltage(
    force_csv: str, resistance_json: str, harmonic_csv: str | None, out_csv: str, out_json: str, config: dict
) -> None:
    """Sensor force through the calibrated sensor model → voltage_{case}.{csv,json}.

    The RC model of Eq. 6 with the fitted R and the cable (exact for a
    piecewise-linear force). The circuit starts at rest with the force at its
    first value, so the first ``signals.skip_s`` of the voltage (its settling,
    time constant tau = RC) are dropped; a warning goes to the log when
    skip_s < 5 tau. With ``signals.sensor_fem_correction`` the voltage
    is scaled by the median |H_FEM| / |H_RC| below the Nyquist frequency
    (the FEM is flat there: its first resonance is near 100 kHz).
    """
    s = config["signals"]
    t, force, dt = read_series(force_csv, "force_N")
    skip = int(round(s["skip_s"] / dt))
    if skip >= t.size - 8:
        raise SignalFileError(f"{force_csv}: signals.skip_s = {s['skip_s']} s leaves no record; lower it")
    print(f"sensor_voltage: {t.size} samples, dt = {dt:.6g} s, {skip} dropped", file=sys.stderr)
    circuit, res = sensor_circuit(config, resistance_json)
    v = circuit_voltage(force, dt, circuit)  # starts at rest: drop its settling (about 5 tau) by skip_s
    t, force, v = t[skip:], force[skip:], v[skip:]
    if s["skip_s"] < 5 * circuit.tau_s:
        print(f"sensor_voltage: warning: skip_s = {s['skip_s']} s < 5 tau = {5 * circuit.tau_s:.3g} s; "
              "the circuit's settling stays in the record", file=sys.stderr)
    corr = None
    if harmonic_csv:
        f_fem, h_fem = read_harmonic(harmonic_csv)
        corr = sig.fem_correction(f_fem, h_fem, np.abs(frequency_response(f_fem, circuit)), 0.5 / dt)
        v = v * corr["factor"]
    write_csv(pd.DataFrame({"time_s": t, "force_N": force, "voltage_V": v}), out_csv)
    write_json(
        {
            "dt_s": dt,
            "sample_rate_Hz": 1.0 / dt,
            "n_samples": int(t.size),
            "duration_s": float(t.size * dt),
            "skipped_s": skip * dt,
            "resistance_ohm": circuit.resistance_ohm,
            "capacitance_F": circuit.capacitance_F,
            "tau_s": circuit.tau_s,
            "open_circuit_gain_V_per_N": circuit.open_circuit_gain_V_per_N,
            "fem_correction": corr,
            "voltage_rms_V": float(np.sqrt(np.mean(v**2))),
            "voltage_peak_to_peak_V": float(np.ptp(v)),
            "force_mean_N": float(force.mean()),
            "force_peak_to_peak_N": float(np.ptp(force)),
            "source": str(force_csv),
            "config": {"sensor": config["sensor"], "signals": s},
        },
        out_json,
    )


# --------------------------------------------------------------------------- noise


def noisy(voltage_csv: str, case: str, out_csv: str, out_json: str, config: dict) -> None:
    """The DAQ: anti-alias filter and sampling at signals.sample_rate_Hz, noise → noisy_{case}.{csv,json}.

    ``signals.noise.model`` relative: white noise at signals.snr_dB,
    SNR = 10 log10(P_s / sigma^2), P_s the mean square of the whole sampled
    noiseless record (the paper). absolute: the DAQ's input noise density,
    mains and drive lines and its ADC; clipped samples are counted in the JSON
    and named in the log. The CSV keeps the sampled noiseless record beside
    the noisy one (column noiseless_V).
    """
    s = config["signals"]
    t, v, dt = read_series(voltage_csv, "voltage_V")
    ns = daq.NoiseSettings.from_config(s)
    smp = daq.sample(v, dt, s["sample_rate_Hz"])
    vs, dts = smp.voltage_V, smp.dt_s
    acq = daq.add_noise(vs, dts, ns, sig.noise_rng(config["seed"], case, 0))
    y = acq.voltage_V
    if acq.n_clipped:
        print(f"noisy: warning: {case}: {acq.n_clipped} of {y.size} samples ({100 * acq.clipped_fraction:.2g}%) "
              f"clipped at +-{ns.range_V} V; raise signals.noise.range_V", file=sys.stderr)
    n = y - vs
    write_csv(pd.DataFrame({"time_s": t[0] + np.arange(y.size) * dts, "voltage_V": y, "noiseless_V": vs}), out_csv)
    write_json(
        {
            "case": case,
            "snr_dB": s["snr_dB"],
            "snr_definition": "10 log10(mean(v^2) / sigma^2) over the whole noiseless record",
            "noise_model": ns.model,
            "sample_rate_Hz": 1.0 / dts,
            "model_sample_rate_Hz": 1.0 / dt,
            "anti_alias": smp.anti_alias,
            "daq": acq.report(),
            "signal_power_V2": sig.signal_power_V2(vs),
            "noise_std_V": acq.noise_std_V,
            "realised_snr_dB": float(10 * np.log10(sig.signal_power_V2(vs) / np.mean(n**2))),
            "seed": [config["seed"], 6, sig.CASE_CODES[case], 0],
            "config": {"seed": config["seed"], "signals": s},
        },
        out_json,
    )


# --------------------------------------------------------------------------- envelope


def envelope(
    noisy_csv: str, voltage_csv: str, kinematics_json: str, out_csv: str, out_json: str, config: dict
) -> None:
    """Band (kurtogram or fixed), envelope spectrum → envelope_{case}.{csv,json}.

    The CSV holds the envelope spectrum of the noisy record and, for
    reference, of the noiseless one in the same band.
    """
    s = config["signals"]
    f0 = kinematics(kinematics_json)["bpfo_Hz"]
    _, y, dt = read_series(noisy_csv, "voltage_V")
    _, v, _ = read_series(noisy_csv, "noiseless_V")  # the sampled noiseless record, on the DAQ clock
    table, record = envelope_analysis(y, v, dt, f0, s)
    write_csv(table, out_csv)
    write_json({**record, "config": {"signals": s}}, out_json)


def read_spectrum(csv: str, json_path: str, column: str = "amplitude_V") -> sig.EnvelopeSpectrum:
    df = pd.read_csv(csv)
    meta = read_json(json_path)
    return sig.EnvelopeSpectrum(
        df["frequency_Hz"].to_numpy(float), df[column].to_numpy(float), tuple(meta["band_Hz"]), meta["n_samples"]
    )


def indicator(envelopes: dict, kinematics_json: str, noisy_jsons: dict, out_json: str, config: dict,
              noisy_csvs: dict | None = None) -> None:
    """Envelope amplitudes at k BPFO over the local floor, indicator, threshold → fault_indicator.json.

    ``envelopes`` maps each case to its (csv, json) pair. Per case also the
    search detector (:mod:`..signals.detector`) on the noisy record
    (``noisy_csvs``, default beside ``noisy_jsons``) in the envelope's band:
    ``fault_type`` (the classification) and ``fault_types``, per type its
    indicator, threshold and ``detected``.
    """
    s = config["signals"]
    kin = kinematics(kinematics_json)
    ins = sig.IndicatorSettings.from_config(s)
    ds = sdet.DetectorSettings.from_config(s)
    out = {}
    for case, (csv, js) in envelopes.items():
        ncsv = noisy_csvs[case] if noisy_csvs else str(Path(noisy_jsons[case]).with_suffix(".csv"))
        _, y, dt = read_series(ncsv, "voltage_V")
        band = read_json(js)["band_Hz"]
        es = sig.EnvelopeSettings(band_rule="fixed", band_Hz=tuple(band), filter_order=s["filter_order"])
        found = sdet.analyse_record(y, dt, kin, es, ds)[1].to_dict()
        r = sig.fault_indicator(read_spectrum(csv, js), kin["bpfo_Hz"], ins)
        r["noiseless"] = sig.fault_indicator(read_spectrum(csv, js, "noiseless_amplitude_V"), kin["bpfo_Hz"], ins)
        r["snr_dB"] = read_json(noisy_jsons[case])["snr_dB"]
        meta = read_json(js)
        r["in_band_snr_dB"] = meta["in_band_snr_dB"]
        r["raw_spectrum_test"] = meta["raw_spectrum_test"]
        r["daq"] = read_json(noisy_jsons[case]).get("daq")
        r["fault_type"] = found["fault_type"]
        r["fault_types"] = {t: dict(v, lines=found["lines"][t]) for t, v in found["per_type"].items()}
        out[case] = r
    out["definition"] = INDICATOR_DEFINITION + "; " + sdet.DEFINITION
    out["kinematics"] = kin
    out["config"] = {"seed": config["seed"], "signals": s}
    write_json(out, out_json)


# --------------------------------------------------------------------------- SNR study


def snr_study(voltages: dict, kinematics_json: str, out_csv: str, out_summary: str, out_json: str, config: dict):
    """Detection against SNR over noise seeds, healthy and faulty → snr_study{,_summary}.csv, snr_study.json.

    Runs the configured band rule and, for comparison, the other one
    (kurtogram vs fixed band) on the same noise records.
    """
    s = config["signals"]
    f0 = kinematics(kinematics_json)["bpfo_Hz"]
    ins = sig.IndicatorSettings.from_config(s)
    grid = snr_grid(s)
    rows = []
    for rule in band_rules(s):
        es = sig.EnvelopeSettings.from_config(dict(s, band_rule=rule))
        for case, path in voltages.items():
            _, v, dt = read_series(path, "voltage_V")
            print(f"snr_study: {rule}, {case}, {len(grid)} SNRs x {s['study_n_seeds']} seeds", file=sys.stderr,
                  flush=True)
            rows += [dict(r, band_rule=rule)
                     for r in sig.snr_sweep(v, dt, f0, case, grid, s["study_n_seeds"], config["seed"], es, ins)]
    df = pd.DataFrame(rows)
    write_csv(df, out_csv)
    summ = snr_summary(df)
    write_csv(summ, out_summary)
    out = snr_study_record(df, summ, list(voltages), grid, s)
    out["config"] = {"seed": config["seed"], "signals": s}
    write_json(out, out_json)


def snr_study_figure(summary_csv: str, study_json: str, out_png: str) -> None:
    """Plot the detection rate against SNR → results/figures/snr_study.png."""
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
    times = sig.defect_event_times(vf, vh, dt, f0, th[0])
    idx = np.round((times - th[0]) / dt).astype(int)
    write_csv(pd.DataFrame({"time_s": times, "voltage_V": vf[idx], "difference_V": vf[idx] - vh[idx]}), out_csv)


# --------------------------------------------------------------------------- fault-type classification


def true_fault_type(bearing: dict) -> str:
    """The faulty case's fault type from the bearing config: ``bearing.defects`` (its single type) or,
    in the configs before the defect list, the outer-race defect."""
    defects = bearing.get("defects")
    if defects is None:
        return "outer_race"
    types = sorted({d["type"] for d in defects})
    if len(types) != 1:
        raise ValueError(f"bearing.defects: {len(types)} fault types ({', '.join(types) or 'none'}); the "
                         "classification needs exactly one true type in the faulty case")
    return types[0]


def classification(voltages: dict, kinematics_json: str, out_json: str, out_csv: str, out_roc_csv: str,
                   config: dict) -> None:
    """Fault type over noise seeds and ROC across SNR → classification.json, classification.csv, roc.csv.

    ``voltages`` maps healthy and faulty to their voltage CSVs (model clock);
    each is sampled at signals.sample_rate_Hz, then replicate j adds the
    configured DAQ noise from noise_rng(seed, case, j) (replicate 0 is the
    noisy stage's record). Rows of the confusion matrix: true type (healthy:
    none), columns: classified type.
    """
    s = config["signals"]
    kin = kinematics(kinematics_json)
    truth = {"healthy": "none", "faulty": true_fault_type(config["bearing"])}
    records = {}
    for case, path in voltages.items():
        _, v, dt = read_series(path, "voltage_V")
        smp = daq.sample(v, dt, s["sample_rate_Hz"])
        records[case] = (truth[case], smp.voltage_V, smp.dt_s)
    es, ds, ns = sig.EnvelopeSettings.from_config(s), sdet.DetectorSettings.from_config(s), daq.NoiseSettings.from_config(s)
    n = s["study_n_seeds"]
    rng = lambda case, j: sig.noise_rng(config["seed"], case, j)  # noqa: E731
    print(f"classification: {len(records)} cases x {n} seeds", file=sys.stderr, flush=True)
    cm, rows = sclass.classify_seeds(records, kin, es, ds, ns, rng, n)
    write_csv(pd.DataFrame(rows), out_csv)
    roc = []
    if truth["faulty"] != "none":
        print(f"classification: ROC at {len(s['detector']['roc_snr_dB'])} SNRs", file=sys.stderr, flush=True)
        roc = sclass.roc_over_snr((truth["faulty"], records["faulty"][1]), records["healthy"][1],
                                  records["faulty"][2], kin, es, ds, s["detector"]["roc_snr_dB"], rng, n)
    write_csv(pd.DataFrame([{"snr_dB": r["snr_dB"], "pfa": p, "pd": d} for r in roc
                            for p, d in zip(r["pfa"], r["pd"], strict=True)]), out_roc_csv)
    write_json(
        {
            **cm,
            "n_seeds": n,
            "noise_model": ns.model,
            "snr_dB": s["snr_dB"] if ns.model == "relative" else None,
            "sample_rate_Hz": 1.0 / records["faulty"][2],
            "false_alarm_probability": ds.false_alarm_probability,
            "true_types": truth,
            "roc": [{k: r[k] for k in ("snr_dB", "fault_type", "auc", "detection_rate", "false_alarm_rate")}
                    for r in roc],
            "roc_definition": "per SNR (relative noise), the true type's score I/threshold, faulty against "
                              "healthy, over the same seeds; detection_rate/false_alarm_rate at score > 1",
            "config": {"seed": config["seed"], "signals": s},
        },
        out_json,
    )
