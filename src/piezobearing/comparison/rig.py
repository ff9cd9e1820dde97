"""The embedded sensor against a housing accelerometer: one simulated rig observed by both.

One run of the rig at the comparison's model step (``sensor_comparison.time_step_s``):

1. the surroundings: one realisation of the base motion (:mod:`piezobearing.housing.base_motion`);
2. the LPM under it (the radial load, and each mass's inertial load -m a_b(t) in ground-relative
   coordinates: :func:`piezobearing.bearing.lpm.simulate_lpm`), its roller loads at the model step;
3. the housing FEM's reduced modal model (modes to ``mode_cutoff_ratio`` times the accelerometer DAQ's
   Nyquist frequency) under the roller loads and the base's inertia -M r a_b: the sensor force and the
   absolute acceleration at the accelerometer's mounting place
   (:func:`piezobearing.housing.fem.response_projected`).

The housing's inertia is counted once. The LPM's pedestal (outer ring and housing as one mass on a spring,
``bearing.pedestal_*``) sets how the rollers' deflection responds; its inertial load under base motion goes
to its own spring, to the ground, and reaches the housing FEM only through the roller loads it changes. The
housing FEM's loads are the roller loads and its own distributed inertia -M r a_b: the housing's mass loads
the sensor and the accelerometer once, through the FEM.

Then each sensor's chain:

* the PZT: the sensor force through the calibrated RC model (and the sensor FEM's correction) as the
  sensor_voltage rule does (:func:`piezobearing.chain.signals.sensor_voltage`), its DAQ at
  ``pzt_sample_rate_Hz`` with the absolute noise of ``signals.noise`` in volts (density, mains pick-up, ADC);
* the accelerometer: its transfer function (sensitivity, mounted resonance, high-pass), the first
  ``signals.skip_s`` dropped as for the PZT, its DAQ's anti-alias filter and sampling at
  ``accelerometer.daq.sample_rate_Hz``, its own noise (the datasheet's density) and range, its DAQ's noise
  in volts and ADC.

Both records go to the same detector (:func:`piezobearing.signals.detectors.detect`, method ``envelope``) at
the same false-alarm probability (``signals.false_alarm_probability``). Absolute noise per channel, not the
relative-SNR model: a relative SNR would cancel each sensor's gain and hide the question.
"""

from __future__ import annotations

import copy
import sys
from dataclasses import dataclass, replace

import numpy as np

from ..bearing import surface
from ..bearing.geometry import kinematic_frequencies
from ..chain import signals as signal_outputs
from ..housing import base_motion, transient
from ..housing import fem as housing_fem
from ..housing.reduced import Housing, build_housing
from ..signals import daq, detectors
from ..signals.detectors import envelope as envelope_detector
from . import accelerometer

SENSORS = ("pzt", "accelerometer")
#: Stream indices of the DAQs' noise draws: default_rng([seed, NOISE_STREAM, sensor, case, replicate]).
NOISE_STREAM = 30


@dataclass(frozen=True)
class ComparisonSettings:
    """The comparison's model step, DAQ rates and seeds (config ``sensor_comparison``, ``accelerometer``).

    Parameters
    ----------
    time_step_s : float
        Model step of the LPM's output and the housing FEM [s].
    substeps : int
        LPM steps per model step [-].
    pzt_sample_rate_Hz, accelerometer_sample_rate_Hz : float
        The two DAQs' rates [Hz].
    mode_cutoff_ratio : float
        Housing modes up to this multiple of the accelerometer DAQ's Nyquist frequency [-].
    n_seeds : int
        Realisations per case [-].
    band_rule : str
        The envelope detector's band rule for both sensors.
    position : str
        The accelerometer's mounting place.
    """

    time_step_s: float
    substeps: int
    pzt_sample_rate_Hz: float
    accelerometer_sample_rate_Hz: float
    mode_cutoff_ratio: float
    n_seeds: int
    band_rule: str
    position: str

    @classmethod
    def from_config(cls, config: dict) -> ComparisonSettings:
        c, a = config["sensor_comparison"], config["accelerometer"]
        out = cls(c["time_step_s"], c["substeps"], c["pzt_sample_rate_Hz"], a["daq"]["sample_rate_Hz"],
                  c["mode_cutoff_ratio"], c["n_seeds"], c["band_rule"], a["position"])
        top = max(out.pzt_sample_rate_Hz, out.accelerometer_sample_rate_Hz)
        if out.time_step_s * top > 1.0 + 1e-9:
            raise ValueError(
                f"config sensor_comparison.time_step_s = {out.time_step_s:g} s is coarser than the faster DAQ "
                f"({top:g} Hz); set it to at most 1/{top:g} s"
            )
        return out

    @property
    def nyquist_Hz(self) -> float:
        """The accelerometer DAQ's Nyquist frequency [Hz]."""
        return 0.5 * self.accelerometer_sample_rate_Hz


def rig_config(config: dict, settings: ComparisonSettings) -> dict:
    """The config with the bearing on the comparison's model step, the healthy bearing's floor
    (``sensor_comparison.bearing_floor`` over ``bearing``: roughness, waviness, unbalance) and the envelope
    detector's band rule."""
    cfg = copy.deepcopy(config)
    cfg["bearing"].update(time_step_s=settings.time_step_s, substeps=settings.substeps)
    cfg["bearing"].update(copy.deepcopy(config["sensor_comparison"]["bearing_floor"]))
    cfg["signals"]["band_rule"] = settings.band_rule
    return cfg


def pzt_noise_settings(config: dict) -> daq.NoiseSettings:
    """The PZT DAQ's noise: ``signals.noise`` in volts (model absolute, whatever the workflow's model), its
    input range ``sensor_comparison.pzt_range_V``."""
    n = daq.NoiseSettings.from_config(config["signals"])
    return replace(n, model="absolute", range_V=config["sensor_comparison"]["pzt_range_V"])


def accelerometer_daq_settings(config: dict) -> daq.NoiseSettings:
    """The accelerometer DAQ's noise and ADC (``accelerometer.daq``): white input noise, no pick-up lines."""
    d = config["accelerometer"]["daq"]
    return daq.NoiseSettings(model="absolute", noise_density_V_per_sqrtHz=d["noise_density_V_per_sqrtHz"],
                             adc_bits=d["adc_bits"], range_V=d["range_V"])


# --------------------------------------------------------------------------- one run of the rig


def run_rig(config: dict, housing: Housing, faulty: bool, surroundings: base_motion.BaseMotionSettings,
            replicate: int) -> dict:
    """One realisation of the surroundings through the LPM and the housing (``config``: :func:`rig_config`'s).

    Returns ``time_s``, ``force_N`` (the sensor force), ``acceleration_m_per_s2`` (at the probe, along its
    axis), ``base_m_per_s2`` (n, 2) at the model step, the base's RMS over the record
    ``disturbance_rms_m_per_s2``, and the kinematics.
    """
    b = config["bearing"]
    motion = base_motion.realisation(surroundings, config["seed"], replicate) if surroundings.active else None
    run = transient.run_lpm(b, faulty, "compiled", config["seed"], base_motion=motion, realisation=replicate)
    t = run["time_s"]
    a = run.get("base_acceleration_m_per_s2", np.zeros((t.size, 2)))
    g, f = housing_fem.project_roller_loads(housing.columns, housing.ops, run["load_N"], run["angle_rad"])
    res = housing_fem.response_projected(housing.ops, housing.base, g, f, a, b["time_step_s"])
    return {
        "time_s": t,
        "force_N": res["force_N"],
        "acceleration_m_per_s2": res["acceleration_m_per_s2"][0],
        "base_m_per_s2": a,
        "disturbance_rms_m_per_s2": base_motion.rms_m_per_s2(a),
        "kinematics": kinematic_frequencies(run["params"].geometry, run["params"].shaft_speed_Hz),
    }


def skip_samples(config: dict) -> int:
    """Samples of the model step dropped at the start (``signals.skip_s``): the RC circuit's and the
    housing modes' start from the static state."""
    return int(round(config["signals"]["skip_s"] / config["bearing"]["time_step_s"]))


def pzt_clean(run: dict, circuit, harmonic, config: dict, settings: ComparisonSettings) -> daq.Sampled:
    """The PZT's noiseless voltage on its DAQ clock: the sensor_voltage rule's RC model, then the DAQ's filter."""
    dt = config["bearing"]["time_step_s"]
    table, _ = signal_outputs.sensor_voltage(run["time_s"], run["force_N"], dt, circuit, harmonic, config)
    return daq.sample(table["voltage_V"].to_numpy(), dt, settings.pzt_sample_rate_Hz)


def accelerometer_clean(run: dict, sensor: accelerometer.AccelerometerSettings, config: dict,
                        settings: ComparisonSettings) -> daq.Sampled:
    """The accelerometer's noiseless voltage on its DAQ clock: its transfer function, the skip, the DAQ's filter."""
    dt = config["bearing"]["time_step_s"]
    v = accelerometer.transduce(run["acceleration_m_per_s2"], dt, sensor)[skip_samples(config):]
    return daq.sample(v, dt, settings.accelerometer_sample_rate_Hz)


def noise_rng(seed: int, sensor: str, faulty: bool, replicate: int) -> np.random.Generator:
    """The DAQ noise of one record: independent streams per sensor, case and replicate."""
    return np.random.default_rng([int(seed), NOISE_STREAM, SENSORS.index(sensor), int(faulty), int(replicate)])


def pzt_record(clean: daq.Sampled, noise: daq.NoiseSettings, rng: np.random.Generator) -> daq.Acquired:
    """The PZT's DAQ record: its absolute noise, pick-up and ADC on the sampled voltage."""
    return daq.add_noise(clean.voltage_V, clean.dt_s, noise, rng)


def accelerometer_record(clean: daq.Sampled, sensor: accelerometer.AccelerometerSettings, noise: daq.NoiseSettings,
                         rng: np.random.Generator) -> tuple[daq.Acquired, int]:
    """The accelerometer's DAQ record: its own noise (datasheet density), its range, its DAQ's noise and ADC.

    Returns the record and the samples the transducer's range clipped.
    """
    v = clean.voltage_V + accelerometer.transducer_noise_V(clean.voltage_V.size, clean.dt_s, sensor, rng)
    v, n_sat = accelerometer.saturate(v, sensor)
    return daq.add_noise(v, clean.dt_s, noise, rng), n_sat


def judge(samples: np.ndarray, dt_s: float, kinematics, config: dict) -> detectors.Detection:
    """The envelope detector on one record, with the config's settings (``signals``)."""
    settings = envelope_detector.Settings.from_config(config["signals"])
    return detectors.detect(samples, 1.0 / dt_s, kinematics, "envelope", settings)


def true_type(config: dict) -> str:
    """The faulty case's fault type (the first defect's)."""
    return config["bearing"]["defects"][0]["type"] if config["bearing"]["defects"] else "none"


@dataclass(frozen=True)
class Rig:
    """What every realisation of one comparison case shares (:func:`prepare`)."""

    config: dict
    settings: ComparisonSettings
    surroundings: base_motion.BaseMotionSettings
    sensor: accelerometer.AccelerometerSettings
    pzt_noise: daq.NoiseSettings
    accelerometer_noise: daq.NoiseSettings
    fault: str
    redraw: bool
    housings: dict
    circuit: object
    harmonic: object


def prepare(config: dict, circuit, harmonic, housings: dict | None = None) -> Rig:
    """One case's rig: the comparison's config (:func:`rig_config`), its settings, the housings at the
    accelerometer's place (built when not given), and whether each seed is a new rig run (``redraw``: the
    bearing's floor or the surroundings random)."""
    settings = ComparisonSettings.from_config(config)
    cfg = rig_config(config, settings)
    surroundings = base_motion.BaseMotionSettings.from_config(cfg["base_motion"])
    if housings is None:
        housings = {faulty: build_housing(cfg, faulty) for faulty in (False, True)}
    return Rig(cfg, settings, surroundings, accelerometer.AccelerometerSettings.from_config(cfg["accelerometer"]),
               pzt_noise_settings(cfg), accelerometer_daq_settings(cfg), true_type(cfg),
               surroundings.active or surface.SurfaceSettings.from_config(cfg["bearing"]).active,
               {faulty: h.at(settings.position) for faulty, h in housings.items()}, circuit, harmonic)


def realise(rig: Rig, faulty: bool, replicate: int) -> tuple[dict, dict]:
    """One realisation of the rig (:func:`run_rig`) and both sensors' noiseless DAQ voltages."""
    run = run_rig(rig.config, rig.housings[faulty], faulty, rig.surroundings, replicate)
    clean = {"pzt": pzt_clean(run, rig.circuit, rig.harmonic, rig.config, rig.settings),
             "accelerometer": accelerometer_clean(run, rig.sensor, rig.config, rig.settings)}
    return run, clean


def observe(rig: Rig, run: dict, clean: dict, faulty: bool, replicate: int) -> tuple[dict, dict]:
    """Both sensors' DAQ records of one realisation (their noise drawn for ``replicate``) through the detector.

    Returns per sensor ``called`` (the detector's call), ``margin_dB`` (the true family's margin; the call's
    where there is no fault), ``clipped`` and ``detection``; and the DAQ records.
    """
    cfg, fault = rig.config, rig.fault
    out = {"pzt": pzt_record(clean["pzt"], rig.pzt_noise, noise_rng(cfg["seed"], "pzt", faulty, replicate))}
    out["accelerometer"], n_sat = accelerometer_record(
        clean["accelerometer"], rig.sensor, rig.accelerometer_noise,
        noise_rng(cfg["seed"], "accelerometer", faulty, replicate))
    seen = {}
    for s in SENSORS:
        d = judge(out[s].voltage_V, clean[s].dt_s, run["kinematics"], cfg)
        family = d.families.get(fault) if fault != "none" else None
        seen[s] = {"called": d.fault_type, "margin_dB": family.margin_dB if family is not None else d.margin_dB,
                   "clipped": out[s].n_clipped + (n_sat if s == "accelerometer" else 0), "detection": d}
    return seen, out


# --------------------------------------------------------------------------- a case over seeds


def compare(config: dict, circuit, harmonic, housings: dict | None = None, keep_records: bool = False,
            log=sys.stderr, n_seeds: tuple[int, int] | None = None, floor_per_seed: bool = True) -> dict:
    """Both sensors on the healthy and the faulty bearing over ``sensor_comparison.n_seeds`` realisations each
    (``n_seeds``: healthy and faulty realisations instead, as the calibrated test draws them).

    ``floor_per_seed=False`` (the workflow's own comparison, kept light): with the frame at rest the rig runs once
    per case, on the first seed's floor, and the seeds draw the DAQs' noise on it; under base motion every seed is
    a new realisation as always.

    ``config``: the workflow's (the comparison's step is applied here). ``circuit``: the PZT's measuring circuit
    (:func:`piezobearing.chain.signals.sensor_circuit`); ``harmonic``: the sensor FEM's response where
    ``signals.sensor_fem_correction``, else None. ``housings``: the healthy and faulty :class:`Housing` when
    already built. Every seed is a new realisation of the rig where anything in it is random: the bearing's
    floor (``sensor_comparison.bearing_floor``: its surfaces and unbalance phase, drawn per case and seed) and
    the surroundings (the k-th healthy and faulty seeds share the k-th base motion); with both off (the frame
    at rest, an ideal bearing) the rig runs once per case and the seeds draw the DAQs' noise only.

    Returns the per-sensor summary (``sensors``), the disturbance's RMS, the housing's records, and with
    ``keep_records`` the first replicate's DAQ records (``records``: per sensor and case the samples and
    their step). Per sensor:

    * ``detection_rate``: share of seeds on the faulty bearing the envelope detector calls the true fault
      type; ``false_alarm_rate``: share of seeds on the healthy bearing it calls any fault (of a type, or
      ``unknown``). Its threshold holds its false-alarm probability for records without lines at the fault
      frequencies; the roller passage puts lines at BPFO into both sensors' healthy records, so the healthy
      rig's calls are given.
    * ``margin_dB``: median over seeds of the true family's margin on the faulty bearing;
      ``margin_over_healthy_dB``: median of that margin minus the largest margin of the same family on the
      healthy bearing under the same surroundings (seed for seed the same base motion);
      ``detection_rate_over_healthy``: share of seeds where it is positive: the healthy rig as the
      reference, a false-alarm probability of at most 1 / (n_seeds + 1) for both sensors alike.
    """
    rig = prepare(config, circuit, harmonic, housings)
    cfg, settings, fault = rig.config, rig.settings, rig.fault
    n_healthy, n_faulty = n_seeds if n_seeds is not None else (settings.n_seeds, settings.n_seeds)
    housings = rig.housings
    rows = {s: {"faulty": [], "healthy": []} for s in SENSORS}
    records, levels, rms = {}, {s: {} for s in SENSORS}, []
    for faulty in (False, True):
        case = "faulty" if faulty else "healthy"
        run = clean = None
        for rep in range(n_faulty if faulty else n_healthy):
            if run is None or (rig.redraw if floor_per_seed else rig.surroundings.active):
                run, clean = realise(rig, faulty, rep)
                rms.append(run["disturbance_rms_m_per_s2"])
                print(f"sensor_comparison: {case} replicate {rep}: base motion "
                      f"{run['disturbance_rms_m_per_s2']:.3g} m/s^2 rms", file=log)
            seen, out = observe(rig, run, clean, faulty, rep)
            for s in SENSORS:
                rows[s][case].append({**seen[s], "detection": seen[s]["detection"] if rep == 0 else None})
                if rep == 0:
                    v = clean[s].voltage_V
                    levels[s][case] = {"clean_rms_V": float(np.sqrt(np.mean(v * v))),
                                       "clean_peak_V": float(np.max(np.abs(v))),
                                       "noise_std_V": out[s].noise_std_V, "sample_rate_Hz": 1.0 / clean[s].dt_s}
                    if keep_records:
                        records.setdefault(s, {})[case] = (out[s].voltage_V, clean[s].dt_s)
    sensors = {}
    for s in SENSORS:
        f, h = rows[s]["faulty"], rows[s]["healthy"]
        healthy_top = max(r["margin_dB"] for r in h)
        over = [r["margin_dB"] - healthy_top for r in f]
        sensors[s] = {
            "detection_rate": float(np.mean([r["called"] == fault for r in f])),
            "false_alarm_rate": float(np.mean([detectors.is_alarm(r["called"]) for r in h])),
            "margin_dB": float(np.median([r["margin_dB"] for r in f])),
            "margin_dB_per_seed": [float(r["margin_dB"]) for r in f],
            "healthy_margin_dB_per_seed": [float(r["margin_dB"]) for r in h],
            "margin_over_healthy_dB": float(np.median(over)),
            "detection_rate_over_healthy": float(np.mean([m > 0 for m in over])),
            "called_faulty": [r["called"] for r in f],
            "called_healthy": [r["called"] for r in h],
            "clipped_samples": int(sum(r["clipped"] for r in f + h)),
            "detection": f[0]["detection"].to_dict(),
            "detection_healthy": h[0]["detection"].to_dict(),
            "levels": levels[s],
        }
    out = {
        "fault_type": fault,
        "n_seeds": n_faulty,
        "n_healthy_seeds": n_healthy,
        "n_faulty_seeds": n_faulty,
        "disturbance_rms_m_per_s2": float(np.mean(rms)),
        "false_alarm_probability": cfg["signals"]["false_alarm_probability"],
        "accelerometer_position": settings.position,
        "sensors": sensors,
        "housing": {("faulty" if k else "healthy"): v.record() for k, v in housings.items()},
    }
    if keep_records:
        out["records"] = records
    return out
