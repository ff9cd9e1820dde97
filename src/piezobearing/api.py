"""The public API: read a record, calibrate, simulate, detect, diagnose (re-exported by :mod:`piezobearing`).

Each function takes arrays, paths or frozen dataclasses and returns a frozen
dataclass; the config, where one is needed, is the package's default
(``config/config.yaml``) unless given (a dict as :func:`piezobearing.config.load`
returns it). Units are SI with the unit in every name.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import config as configuration
from .bearing.kinematics import Kinematics, RollingBearing
from .chain import calibration as sensor_outputs
from .diagnosis.calibration.record import check_record
from .io import Measurement, Record, read_bearing_record, read_measurement
from .io.vibration import read_vibration_record
from .signals import detectors
from .signals.detectors import Detection

#: The record kinds :func:`read_record` knows (:func:`diagnose`: calibration and bearing).
RECORD_KINDS = ("vibration", "bearing", "calibration")


def _config(config: dict | None) -> dict:
    return configuration.load() if config is None else config


def read_record(path: str | Path, channel: str | None = None, sample_rate_Hz: float | None = None, kind: str = "vibration",
                channels: dict | None = None) -> Record:
    """Read a record file of any supported format (CSV, MATLAB .mat v5/v7.3, UFF58, TDMS, WAV).

    Parameters
    ----------
    path : str or Path
        The record file.
    channel : str, optional
        ``kind="vibration"``: the channel's name or a unique suffix of it (``"DE_time"``); None for a file
        with one channel.
    sample_rate_Hz : float, optional
        ``kind="vibration"``: the sampling rate [Hz] where the file has no time axis (a DAQ's .mat file).
    kind : {"vibration", "bearing", "calibration"}
        One channel of any recording (:func:`piezobearing.io.vibration.read_vibration_record`; a scalar
        ``*RPM`` variable is read as the speed); this project's running-bearing record (``time_s``,
        ``voltage_V``, optional ``speed_rpm``); or its calibration record (``time_s``, ``force_N``,
        ``voltage_V``), each checked as the workflow checks it.
    channels : dict, optional
        ``bearing``, ``calibration``: record column -> the file's channel or column name.

    Returns
    -------
    Record
        The samples with their rate ``sample_rate_Hz`` [Hz], time axis ``time_s`` [s] and columns by name
        ``data``, whatever the kind (a ``VibrationRecord``, a ``BearingRecord`` or a ``Measurement``, each with its own
        columns as attributes too: ``samples``; ``voltage_V``, ``speed_rpm``; ``force_N``, ``voltage_V``).

    Examples
    --------
    >>> import numpy as np, pandas as pd, tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "run.csv"
    >>> t = np.arange(12000) / 4000.0
    >>> pd.DataFrame({"time_s": t, "accel_g": np.sin(2 * np.pi * 70.8 * t)}).to_csv(path, index=False)
    >>> record = read_record(path, channel="accel_g")
    >>> record.sample_rate_Hz, record.samples.size, record.channel
    (4000.0, 12000, 'accel_g')
    """
    if kind == "vibration":
        return read_vibration_record(path, channel, sample_rate_Hz)
    if kind == "bearing":
        return read_bearing_record(path, channels)
    if kind == "calibration":
        return read_measurement(path, channels=channels)
    raise ValueError(f"kind '{kind}' unknown; use one of {', '.join(RECORD_KINDS)}")


@dataclass(frozen=True)
class Calibration:
    """The sensor's calibration from one record.

    Attributes
    ----------
    sensitivity_V_per_N : float
        Peak voltage over peak force of the impulses (median) [V/N].
    n_impulses : int
        Impulses the sensitivity is taken from [-].
    resistance_ohm : float
        The circuit's resistance R fitted to the whole record (Eq. 6) [ohm].
    resistance_ci95_ohm : tuple of float
        Its 95 % confidence interval [ohm].
    tau_s : float
        The circuit's time constant R C [s].
    nrmse : float
        Normalised rms misfit of the fitted voltage [-].
    sensitivity : dict
        The sensitivity record as the workflow writes it (sensitivity.json).
    resistance : dict
        The fit's record as the workflow writes it (resistance.json).
    """

    sensitivity_V_per_N: float
    n_impulses: int
    resistance_ohm: float
    resistance_ci95_ohm: tuple[float, float]
    tau_s: float
    nrmse: float
    sensitivity: dict
    resistance: dict


def calibrate(force_N, voltage_V, sample_rate_Hz: float, config: dict | None = None) -> Calibration:
    """Sensitivity and resistance of the sensor from a calibration record's force and voltage.

    The workflow's calibration rules (extract_sensitivity, fit_resistance) on the arrays, after the checks the
    record reader makes (no dead or clipped channel, at least two impulses, the sensor's polarity).

    Parameters
    ----------
    force_N, voltage_V : array_like
        The press's force [N] and the sensor's voltage [V], sample by sample.
    sample_rate_Hz : float
        Sampling rate [Hz].
    config : dict, optional
        The config (its ``sensor``, ``calibration`` and ``diagnostics`` sections); the package's default if None.

    Returns
    -------
    Calibration

    Examples
    --------
    >>> from piezobearing import config
    >>> from piezobearing.chain.calibration import synthesize_calibration
    >>> record = synthesize_calibration(config.load())          # the default synthetic press record
    >>> c = calibrate(record.force_N, record.voltage_V, record.sample_rate_Hz)
    >>> bool(0.05 < c.sensitivity_V_per_N < 0.5), bool(1e7 < c.resistance_ohm < 1e10)
    (True, True)
    """
    cfg = _config(config)
    force, voltage = np.asarray(force_N, dtype=float), np.asarray(voltage_V, dtype=float)
    if force.shape != voltage.shape or force.ndim != 1:
        raise ValueError(f"force_N {force.shape} and voltage_V {voltage.shape}: give two 1-D arrays of one length")
    if not sample_rate_Hz > 0:
        raise ValueError(f"sample_rate_Hz = {sample_rate_Hz!r}: give the sampling rate in Hz (> 0)")
    m = Measurement(np.arange(force.size) / float(sample_rate_Hz), force, voltage, "arrays")
    impulses = check_record(m, cfg, "the arrays")
    s = sensor_outputs.extract_sensitivity(m, impulses, cfg)
    r, _ = sensor_outputs.fit_resistance(m, cfg)
    return Calibration(float(s["sensitivity_V_per_N"]), int(s["n_impulses"]), float(r["resistance_ohm"]),
                       tuple(float(v) for v in r["resistance_ci95_ohm"]), float(r["tau_s"]), float(r["nrmse"]), s, r)


@dataclass(frozen=True)
class Simulation:
    """The simulated running bearing: the workflow's chain from the bearing to the fault indicator.

    Attributes
    ----------
    kinematics : Kinematics
        The bearing's kinematic frequencies [Hz].
    sample_rate_Hz : float
        The DAQ's sampling rate of ``noisy`` and ``noiseless`` [Hz].
    noisy, noiseless : dict
        Case (``healthy``, ``faulty``) -> the DAQ's record with and without its noise [V].
    voltage : dict
        Case -> (time [s], sensor voltage on the model's step [V], step [s]).
    indicator : dict
        The fault indicator and the configured detector's call per case (fault_indicator.json).
    """

    kinematics: Kinematics
    sample_rate_Hz: float
    noisy: dict
    noiseless: dict
    voltage: dict
    indicator: dict


def simulate(config: dict | None = None, resistance_ohm: float | None = None) -> Simulation:
    """Simulate the running bearing and its sensor for a config: the workflow's chain, in memory.

    The lumped-parameter bearing, the housing's reduced solve, the sensor voltage, the DAQ's sampling and
    noise, the envelope and the fault indicator, for the healthy and the faulty case
    (:func:`piezobearing.stages.studies.workflow_chain`; the sensor FEM's correction is not applied).

    Parameters
    ----------
    config : dict, optional
        The config; the package's default if None. Minutes for the paper's 1.8 s record; ``bearing.duration_s``
        sets the length.
    resistance_ohm : float, optional
        The sensor circuit's R [ohm] where ``sensor.daq_resistance_ohm`` is null (the calibration's fit);
        default: the calibration's initial value ``calibration.initial_resistance_ohm``.

    Returns
    -------
    Simulation

    Examples
    --------
    >>> from piezobearing import config
    >>> cfg = config.load()
    >>> cfg["bearing"]["duration_s"] = 0.3                       # a short record: 21 roller passages
    >>> sim = simulate(cfg)                                      # doctest: +ELLIPSIS
    >>> round(sim.kinematics.bpfo_Hz, 2), sorted(sim.noisy)
    (70.83, ['faulty', 'healthy'])
    """
    cfg = _config(config)
    cfg = {**cfg, "signals": {**cfg["signals"], "sensor_fem_correction": False},
           "housing": {**cfg["housing"], "method": "reduced", "direct_check_s": 0.0}}
    r = cfg["calibration"]["initial_resistance_ohm"] if resistance_ohm is None else float(resistance_ohm)
    # the study chain runs the housing's FEM and the whole signals stage (sfepy, numba, pandas: seconds to import),
    # which read_record, calibrate and detect never need
    from .stages import studies

    run = studies.workflow_chain(cfg, {"resistance_ohm": r}, None, "simulate(resistance_ohm)")
    noisy = {c: y for c, (y, _, _, _) in run["noisy"].items()}
    noiseless = {c: v for c, (_, v, _, _) in run["noisy"].items()}
    dt = next(iter(run["noisy"].values()))[2]
    return Simulation(Kinematics.from_dict(run["kinematics"]), 1.0 / dt, noisy, noiseless, run["voltage"],
                      run["indicator"])


def detect(samples, sample_rate_Hz: float, bearing: RollingBearing | str, shaft_speed_rpm: float, method: str = "envelope",
           settings=None, reference=None) -> Detection:
    """Detect a fault of any rolling bearing in a record.

    Parameters
    ----------
    samples : array_like
        One channel of the record (an accelerometer's or this sensor's; any unit).
    sample_rate_Hz : float
        Its sampling rate [Hz].
    bearing : RollingBearing or str
        The bearing's geometry, or a designation of the table (``"SKF 6205"``).
    shaft_speed_rpm : float
        The shaft speed [rpm] (nominal: the envelope method refines it from the record).
    method : str
        ``"envelope"`` (any recording), ``"baseline"`` (against a healthy ``reference``) or ``"paper"``
        (the paper's exact-bin test); see :mod:`piezobearing.signals.detectors`.
    settings : optional
        The method's ``Settings``; None: ``envelope`` its defaults for real recordings, the others the
        package's default config.
    reference : array_like, optional
        The healthy record at ``sample_rate_Hz`` (``baseline`` only).

    Returns
    -------
    Detection
        ``fault_type`` (``none``, ``outer_race``, ``inner_race``, ``rolling_element``, or ``unknown`` where
        the envelope detector finds a fault whose families do not separate), the evidence per family, the
        band, the shaft rate found and the call's false-alarm probability.

    Examples
    --------
    An outer-race defect of an SKF 6205 at 1797 rpm: impacts at BPFO (107 Hz, 1 % jitter) ringing a 3 kHz
    resonance, in noise, 2 s at 12 kHz (outer race 8.6 dB over its threshold, the others below theirs).

    >>> import numpy as np
    >>> rng = np.random.default_rng(2)
    >>> fs, bpfo = 12000.0, 3.5848 * 1797 / 60
    >>> t = np.arange(int(2 * fs)) / fs
    >>> x = 0.5 * rng.standard_normal(t.size)
    >>> for t0 in np.cumsum(rng.normal(1 / bpfo, 0.01 / bpfo, int(2 * bpfo))):
    ...     on = t >= t0
    ...     x[on] += 2.0 * np.exp(-(t[on] - t0) / 1e-3) * np.sin(2 * np.pi * 3000.0 * (t[on] - t0))
    >>> d = detect(x, fs, "SKF 6205", 1797.0)
    >>> d.fault_type, d.families["outer_race"].margin_dB > 0
    ('outer_race', True)
    """
    geometry = bearing if isinstance(bearing, RollingBearing) else RollingBearing.from_designation(str(bearing))
    if not shaft_speed_rpm > 0:
        raise ValueError(f"shaft_speed_rpm = {shaft_speed_rpm!r}: give the shaft speed in rpm (> 0)")
    kinematics = geometry.kinematics(float(shaft_speed_rpm) / 60.0)
    if settings is None and method == "envelope":
        settings = detectors.envelope.Settings()
    return detectors.detect(samples, sample_rate_Hz, kinematics, method, settings, reference)


@dataclass(frozen=True)
class Diagnosis:
    """A record's diagnosis: which physical effects the model misses, and for a running bearing its fault.

    Attributes
    ----------
    kind : str
        ``calibration`` or ``bearing``.
    verdict : str
        The diagnosis in one line.
    selected : tuple of str
        The effects the model needs, in the order they were added.
    baseline_nrmse, final_nrmse, noise_floor_nrmse : float
        The misfit of the configured model, of the model with the selected effects, and the noise's floor [-].
    fault : dict or None
        Running bearing: the fault found (type, parameters, their 95 % intervals).
    record : dict
        Everything the diagnosis found (what ``piezobearing diagnose`` writes to diagnosis.json).
    """

    kind: str
    verdict: str
    selected: tuple[str, ...]
    baseline_nrmse: float
    final_nrmse: float
    noise_floor_nrmse: float
    fault: dict | None
    record: dict


def diagnose(path: str | Path, kind: str = "calibration", config: dict | None = None) -> Diagnosis:
    """Diagnose a calibration or running-bearing record against the model: what is missing, and by how much.

    The engine of ``piezobearing diagnose`` and ``diagnose-bearing`` without their report files.

    Parameters
    ----------
    path : str or Path
        The record file (any format of :func:`read_record`).
    kind : {"calibration", "bearing"}
        A calibration record or this project's running-bearing record.
    config : dict, optional
        The config; the package's default if None.

    Returns
    -------
    Diagnosis

    Examples
    --------
    A synthetic press record with a 15 ms delay of the voltage channel hidden in it: the diagnosis finds the
    delay and its misfit falls from 10.8 % to the noise's floor (2.1 %).

    >>> import tempfile, pathlib
    >>> from piezobearing import config
    >>> from piezobearing.io import write_measurement
    >>> from piezobearing.chain.calibration import synthesize_calibration
    >>> cfg = config.load()
    >>> cfg["synthesis"]["hidden_effects"] = [{"name": "channel_delay", "params": {"delay_s": 0.015}}]
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "measurement.csv"
    >>> write_measurement(synthesize_calibration(cfg), path)
    >>> d = diagnose(path)
    >>> d.selected, d.final_nrmse < 1.05 * d.noise_floor_nrmse < d.baseline_nrmse
    (('channel_delay',), True)
    """
    # the diagnosis stages write figures and the bearing's reads the housing's FEM (matplotlib, sfepy: seconds to
    # import), which read_record, calibrate and detect never need
    from .stages import bearing_diagnosis, diagnostics

    cfg = _config(config)
    if kind == "calibration":
        record, _ = diagnostics.run(str(path), cfg)
    elif kind == "bearing":
        cfg = {**cfg, "bearing": {**cfg["bearing"], "measurement": str(path)}}
        influence = bearing_diagnosis.influence_from_config
        record, _ = bearing_diagnosis.run(str(path), lambda: influence(cfg), cfg)
    else:
        raise ValueError(f"kind '{kind}' unknown; use calibration or bearing")
    return Diagnosis(kind, record["verdict"], tuple(record["selected"]), float(record["baseline"]["nrmse"]),
                     float(record["final"]["nrmse"]), float(record["final"]["noise_floor_nrmse"]),
                     record.get("fault"), record)
