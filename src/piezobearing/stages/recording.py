"""Fault detection on a user's recording: a record file, what the rig's user knows, and the envelope detector.

:func:`detect_recording` reads one channel of a record as a DAQ wrote it
(:func:`piezobearing.io.vibration.read_vibration_record`), takes the bearing and its speed from the
arguments, the rig file or the record itself, and runs the envelope detector
(:mod:`piezobearing.signals.detectors.envelope`); :func:`write_detection` writes ``detection.json``,
``report.md`` and its figure. ``piezobearing detect`` is the command over both.

The rig file is YAML with the keys the rig's user knows (every key optional; arguments override it)::

    bearing:                       # a designation of the table, or the geometry
      designation: SKF 6203-2RS JEM
      n_rolling_elements: 8
      rolling_element_diameter_m: 0.0067462
      pitch_diameter_m: 0.0284988
      contact_angle_deg: 0.0
    shaft_speed_rpm: 1730.0
    sample_rate_Hz: 12000.0
    channel: X700_FE_time
    tachometer: tacho_V            # a pulse channel of the record (order tracking), with
    pulses_per_rev: 1              #   its pulses per shaft revolution
    speed_channel: speed_rpm       # or a channel of the shaft speed [rpm], sample by sample

A rate or a speed the record holds in a field is named by the field's path in the file: ``sample_rate_Hz:
bearing.sr``; the speed's key names the field's unit, ``shaft_speed_Hz: bearing.rate`` (revolutions per
second) or ``shaft_speed_rpm: bearing.rpm``.

A record with a tachometer (``tachometer``, ``--tachometer``) or a speed channel (``speed_channel``,
``--speed-channel``, or a channel named ``speed_rpm``) is order-tracked before the envelope analysis
(:func:`piezobearing.signals.order.detect_tracked`): resampled at uniform shaft angles, so that a fault's lines
stay sharp while the speed changes; its frequencies are then orders (cycles per shaft revolution).

A batch (:func:`detect_records`) writes its table with pandas, which loads there (0.2-0.25 s of CPU to
import): one record's detection goes without it.
"""

from __future__ import annotations

import math
import re
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import yaml

from ..bearing.kinematics import BearingError, Kinematics, RollingBearing
from ..io import MeasurementError, write_json
from ..io.archive import rig_beside
from ..io.record_formats import RECORD_FORMATS
from ..io.vibration import VibrationRecord, numeric_samples, pick_channel, read_vibration_record
from ..plotting import save
from ..plotting.detection import detection_figure, save_detection, trend_figure
from ..signals.detectors import UNKNOWN, Detection
from ..signals.detectors import envelope as envelope_detector

if TYPE_CHECKING:
    import pandas as pd

#: The keys of a rig file.
RIG_KEYS = ("bearing", "shaft_speed_rpm", "shaft_speed_Hz", "sample_rate_Hz", "channel", "tachometer",
            "pulses_per_rev", "speed_channel")
#: The name of a speed channel [rpm] that order-tracks a record without being named.
SPEED_COLUMN = "speed_rpm"
#: The fewest tachometer pulses that track a record, and the largest ratio of two successive pulse intervals
#: (a speed that doubles from one pulse to the next is a noisy or wrong channel, not a shaft).
MIN_PULSES = 4
MAX_INTERVAL_JUMP = 2.0
#: A speed's unit by its key, as a factor to rpm.
SPEED_UNITS = {"shaft_speed_rpm": 1.0, "shaft_speed_Hz": 60.0}


class RigError(ValueError):
    """A rig file or an argument that cannot be used (one line naming the key and the fix)."""


@dataclass(frozen=True)
class Rig:
    """What the rig's user knows about a record (None: not given).

    Attributes
    ----------
    bearing : RollingBearing or None
    shaft_speed_rpm : float or str or None
        [rpm], or the path of the record's field that holds it in rpm.
    sample_rate_Hz : float or str or None
        [Hz], or the path of the record's field that holds it.
    channel : str or None
    source : str
        The rig file, or "" where none was given.
    shaft_speed_Hz : float or str or None
        [Hz] (revolutions per second), or the path of the record's field that holds it in Hz.
    tachometer : str or None
        The record's pulse channel (order tracking).
    pulses_per_rev : int or None
        The tachometer's pulses per shaft revolution (default 1).
    speed_channel : str or None
        The record's channel of the shaft speed [rpm] (order tracking).
    """

    bearing: RollingBearing | None = None
    shaft_speed_rpm: float | str | None = None
    sample_rate_Hz: float | str | None = None
    channel: str | None = None
    source: str = ""
    shaft_speed_Hz: float | str | None = None
    tachometer: str | None = None
    pulses_per_rev: int | None = None
    speed_channel: str | None = None


def read_rig(path: str | Path) -> Rig:
    """Read a rig file (the module docstring's keys)."""
    path = Path(path)
    if not path.is_file():
        raise RigError(f"{path}: rig file not found; give the YAML file with bearing, shaft_speed_rpm, sample_rate_Hz, "
                       "channel")
    try:
        d = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    except yaml.YAMLError as e:
        raise RigError(f"{path}: not valid YAML ({str(e).splitlines()[0]}); fix the file") from None
    if not isinstance(d, dict):
        raise RigError(f"{path}: a rig file is a mapping of {', '.join(RIG_KEYS)}")
    unknown = sorted(set(d) - set(RIG_KEYS))
    if unknown:
        raise RigError(f"{path}: key '{unknown[0]}' unknown; a rig file holds {', '.join(RIG_KEYS)}")
    try:
        bearing = RollingBearing.from_config(d["bearing"], str(path)) if d.get("bearing") is not None else None
    except BearingError as e:
        raise RigError(str(e)) from None
    if d.get("shaft_speed_rpm") is not None and d.get("shaft_speed_Hz") is not None:
        raise RigError(f"{path}: both shaft_speed_rpm and shaft_speed_Hz given; keep the one in the unit you know")
    if d.get("tachometer") is not None and d.get("speed_channel") is not None:
        raise RigError(f"{path}: both tachometer and speed_channel given; keep the one the record has")
    return Rig(bearing, number_or_field(d.get("shaft_speed_rpm"), f"{path}: shaft_speed_rpm"),
               number_or_field(d.get("sample_rate_Hz"), f"{path}: sample_rate_Hz"),
               None if d.get("channel") is None else str(d["channel"]), str(path),
               number_or_field(d.get("shaft_speed_Hz"), f"{path}: shaft_speed_Hz"),
               None if d.get("tachometer") is None else str(d["tachometer"]),
               check_pulses(d.get("pulses_per_rev"), f"{path}: pulses_per_rev"),
               None if d.get("speed_channel") is None else str(d["speed_channel"]))


def check_pulses(value, where: str) -> int | None:
    """A tachometer's pulses per revolution: a positive whole number (``where`` names the key or option)."""
    if value is None:
        return None
    try:
        n = float(value)
    except (TypeError, ValueError):
        raise RigError(f"{where} = {value!r} is not a number; give the tachometer's pulses per revolution (1 for "
                       "a once-per-revolution mark)") from None
    if isinstance(value, bool) or n != int(n) or n < 1:
        raise RigError(f"{where} = {value!r}; give the tachometer's pulses per revolution, a whole number of 1 or more")
    return int(n)


def number_or_field(value, where: str) -> float | str | None:
    """A positive number, or the path of a field of the record (a text that does not read as a number);
    ``where`` names the key or option in the one-line error."""
    if value is None:
        return None
    if isinstance(value, str):
        text = value.strip()
        try:
            value = float(text)
        except ValueError:
            if not text or any(c.isspace() for c in text):
                raise RigError(f"{where} = {value!r} is neither a number nor a field's path; give the value or "
                               "the path of the record's field (bearing.sr)") from None
            return text
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RigError(f"{where} = {value!r} is not a number; give the value or the path of the record's field")
    if not value > 0 or not math.isfinite(value):
        raise RigError(f"{where} = {value:g}; give a positive number")
    return float(value)


@dataclass(frozen=True)
class RecordingDetection:
    """A detection on a recording and what it was computed from.

    Attributes
    ----------
    detection : Detection
        The envelope detector's answer.
    record : VibrationRecord
        The channel analysed.
    bearing : RollingBearing
    speed_rpm : float
        The shaft speed given [rpm] (the detector refines it: ``detection.shaft_rate_Hz``).
    speed_source : str
        Where the speed came from (``--rpm``, the rig file, the record's RPM variable).
    kinematics : Kinematics
        At the given speed, no slip [Hz].
    tracking : dict or None
        Order tracking (the record had a tachometer or a speed channel): which channel, its kind
        (``tachometer``, ``speed channel``), the pulses per revolution; None at a fixed speed. The
        detection's frequencies are then orders (``detection.details["order_tracking"]``).
    """

    detection: Detection
    record: VibrationRecord
    bearing: RollingBearing
    speed_rpm: float
    speed_source: str
    kinematics: Kinematics
    tracking: dict | None = None

    def to_dict(self) -> dict:
        """``detection.json``: the call, per family its evidence, the band, the shaft speed found, the call's
        false-alarm probability, and what the record and the bearing were."""
        d = self.detection.to_dict()
        details = {k: v for k, v in d["details"].items() if k not in ("spectrum", "kurtogram")}
        tracked = d["details"].get("order_tracking")
        # order-tracked: the detector's shaft rate is in orders (1 where the tachometer's rate holds); the mean's rpm
        scale = 1.0 if tracked is None else tracked["mean_speed_rpm"] / 60.0
        return {
            "fault_type": d["fault_type"],
            "summary": summary(self.detection),
            "false_alarm_probability": d["false_alarm_probability"],
            "margin_dB": d["margin_dB"],
            "band_Hz": d["band_Hz"],
            "shaft_speed_found_rpm": 60.0 * d["shaft_rate_Hz"] * scale,
            "shaft_speed_given_rpm": self.speed_rpm,
            "shaft_speed_source": self.speed_source,
            "families": d["families"],
            "record": {"file": self.record.source, "channel": self.record.channel, "rate_Hz": self.record.sample_rate_Hz,
                       "duration_s": self.record.duration_s, "channels_in_file": list(self.record.channels)},
            "bearing": {"designation": self.bearing.designation, "n_rolling_elements": self.bearing.n_rolling_elements,
                        "rolling_element_diameter_m": self.bearing.rolling_element_diameter_m,
                        "pitch_diameter_m": self.bearing.pitch_diameter_m,
                        "contact_angle_deg": self.bearing.contact_angle_deg,
                        "multiples_of_shaft_rate": self.bearing.multiples()},
            "kinematics_at_given_speed_Hz": self.kinematics.to_dict(),
            "type_call": d["details"].get("type_call"),
            "order_tracking": None if tracked is None else {**self.tracking, **tracked},
            "method": d["method"],
            "details": details,
        }


def _name(family: str) -> str:
    return family.replace("_", " ")


def summary(detection: Detection) -> str:
    """One sentence: the call and its strongest evidence, or that no fault signature was found."""
    pfa = detection.false_alarm_probability
    if detection.fault_type == "none":
        return (f"no fault signature found: no family's lines stand above their threshold at a false-alarm "
                f"probability of {pfa:g} (largest margin {detection.margin_dB:+.1f} dB)")
    typed = detection.details.get("type_call")
    if detection.fault_type == UNKNOWN:
        m = typed["margins_dB"]
        cands = ", ".join(f"{_name(f)} {m[f]:+.1f} dB" for f in typed["candidates"])
        return (f"fault of unknown type: a fault's lines stand above their threshold at a false-alarm probability "
                f"of {pfa:g}, but the families' margins lie within {typed['required_separation_dB']:g} dB of each "
                f"other ({cands}); candidates: {', '.join(_name(f) for f in typed['candidates'])}")
    family = detection.families[detection.fault_type]
    above = [ln.label for ln in family.lines if ln.above]
    text = (f"{_name(detection.fault_type)} fault: {family.margin_dB:+.1f} dB over the threshold at a "
            f"false-alarm probability of {pfa:g}; lines above their own threshold: "
            f"{', '.join(above) or 'none alone (their sum passes)'}")
    if typed is not None and typed["runner_up"] is not None:
        text += (f"; the winning family, {typed['separation_dB']:.1f} dB above the next "
                 f"({_name(typed['runner_up'])})")
    return text


def type_lines(d: dict) -> list[str]:
    """Why the call is what it is, a line per family (the report's and the console's): the winner, and why
    each other family lost (how far below the winner, whether it was detected at all)."""
    typed = d["details"].get("type_call")
    if d["fault_type"] == "none" or typed is None:
        return []
    winner, m = typed["winner"], typed["margins_dB"]
    if d["fault_type"] == UNKNOWN:
        head = (f"unknown type: the largest margin, {_name(winner)} {m[winner]:+.1f} dB, stands "
                f"{typed['separation_dB']:.1f} dB above {_name(typed['runner_up'])}; a type is called only "
                f"{typed['required_separation_dB']:g} dB apart")
    else:
        head = (f"{_name(winner)}: the winning family, {m[winner]:+.1f} dB, at least "
                f"{typed['required_separation_dB']:g} dB above every other family")
    return [head] + [f"{_name(f)}: {m[f]:+.1f} dB, {why}" for f, why in typed["why_not"].items()]


def detect_recording(record: str | Path, rig: str | Path | Rig | None = None, bearing: str | RollingBearing | None = None,
                     rpm: float | str | None = None, fs: float | str | None = None, channel: str | None = None,
                     settings: envelope_detector.Settings | None = None,
                     shaft_Hz: float | str | None = None, tachometer: str | None = None,
                     pulses_per_rev: int | None = None, speed_channel: str | None = None) -> RecordingDetection:
    """Detect a bearing fault in a recording.

    Parameters
    ----------
    record : path
        The record file (.mat v5/v7.3, .csv, .wav, .uff/.unv, .tdms).
    rig : path or Rig, optional
        The rig file (module docstring); the other arguments override it.
    bearing : str or RollingBearing, optional
        A designation of the table (``"SKF 6205"``) or a bearing.
    rpm : float or str, optional
        The shaft speed [rpm], or the path of the record's field holding it in rpm; else ``shaft_Hz``, else
        the rig file's, else the record's own ``*RPM`` variable.
    fs : float or str, optional
        The sampling rate [Hz] where the file has no time axis, or the path of the record's field holding it;
        else the rig file's.
    channel : str, optional
        The channel's name, path or a unique suffix (``_DE_time``, ``bearing.gs``); else the rig file's.
    settings : envelope detector Settings, optional
        Default: ``Settings()`` (pre-whitening, fast kurtogram and whole band, pfa 1e-3).
    shaft_Hz : float or str, optional
        The shaft speed [Hz] (revolutions per second), or the path of the record's field holding it in Hz.
    tachometer : str, optional
        The record's tachometer channel: the record is order-tracked (module docstring); else the rig file's.
    pulses_per_rev : int, optional
        The tachometer's pulses per revolution; else the rig file's, else 1.
    speed_channel : str, optional
        The record's channel of the shaft speed [rpm]: the record is order-tracked; else the rig file's, else
        a channel named ``speed_rpm``.

    Returns
    -------
    RecordingDetection
    """
    rig = read_rig(rig) if isinstance(rig, (str, Path)) else (rig or Rig())
    if isinstance(bearing, str):
        try:
            bearing = RollingBearing.from_designation(bearing)
        except BearingError as e:
            raise RigError(f"--bearing: {e}") from None
    bearing = bearing or rig.bearing
    if bearing is None:
        raise RigError(f"{record}: no bearing given; give --bearing DESIGNATION (e.g. 'SKF 6205') or the geometry in "
                       "a rig file (--config RIG.yaml, key bearing)")
    rpm, fs, shaft_Hz = (number_or_field(v, k) for v, k in ((rpm, "--rpm"), (fs, "--fs"), (shaft_Hz, "--shaft-hz")))
    rec = read_vibration_record(record, channel if channel is not None else rig.channel,
                                fs if fs is not None else rig.sample_rate_Hz)
    settings = settings or envelope_detector.Settings()
    pulses_per_rev = check_pulses(pulses_per_rev, "--pulses-per-rev")
    tracked = tracking_angle(rec, tachometer if tachometer is not None else rig.tachometer,
                             pulses_per_rev if pulses_per_rev is not None else rig.pulses_per_rev,
                             speed_channel if speed_channel is not None else rig.speed_channel)
    if tracked is not None:
        # A tracked record only: order tracking's splines (scipy.interpolate) cost 0.4-0.6 s of import.
        from ..signals import order

        angle, tracking = tracked
        try:
            detection, track = order.detect_tracked(rec.samples, 1.0 / rec.sample_rate_Hz, angle,
                                                    bearing.kinematics(1.0).to_dict(), settings)
        except ValueError as e:
            raise RigError(f"{record}: {tracking['kind']} {tracking['channel']}: {e}") from None
        speed = 60.0 * track.mean_shaft_Hz
        return RecordingDetection(detection, rec, bearing, speed, f"the {tracking['kind']} {tracking['channel']} "
                                  "(mean over the record)", bearing.kinematics(speed / 60.0), tracking)
    speed, speed_source = shaft_speed(rec, rig, rpm, shaft_Hz)
    kinematics = bearing.kinematics(speed / 60.0)
    try:
        detection = envelope_detector.detect(rec.samples, rec.sample_rate_Hz, kinematics.to_dict(), settings)
    except ValueError as e:
        raise RigError(f"{record}: {e}") from None
    return RecordingDetection(detection, rec, bearing, speed, speed_source, kinematics)


def tracking_angle(rec: VibrationRecord, tachometer: str | None, pulses: int | None,
                   speed_channel: str | None) -> tuple[object, dict] | None:
    """The shaft angle over the record from its tachometer or speed channel (a channel named
    :data:`SPEED_COLUMN` where neither is named), and what it came from; None where the record has neither.

    Raises
    ------
    RigError
        One line naming the channel: both named, a channel of another length or not finite, a tachometer
        without pulses, with too few or irregular ones, a speed that is not positive.
    """
    contents = rec.contents
    if tachometer is None and speed_channel is None:
        if contents is None or SPEED_COLUMN not in contents.channels or rec.channel == SPEED_COLUMN:
            return None
        speed_channel = SPEED_COLUMN
    if tachometer is not None and speed_channel is not None:
        raise RigError(f"{rec.source}: both a tachometer ({tachometer}) and a speed channel ({speed_channel}) given; "
                       "name the one channel the shaft's angle comes from")
    kind, named = ("tachometer", tachometer) if tachometer is not None else ("speed channel", speed_channel)
    option = "--tachometer" if tachometer is not None else "--speed-channel"
    if contents is None:
        raise RigError(f"{rec.source}: {kind} '{named}' asked for, but the file holds one channel; record the "
                       f"{kind} beside the vibration or leave {option} out")
    name = pick_channel(contents, named)
    if name == rec.channel:
        raise RigError(f"{rec.source}: the {kind} {name} is the channel analysed; name the vibration channel with "
                       f"--channel and the {kind} with {option}")
    v = numeric_samples(contents.channels[name])
    where = f"{rec.source}: {kind} {name}"
    if v.size != rec.samples.size:
        raise RigError(f"{where} holds {v.size} samples, the channel analysed {rec.samples.size}; give a {kind} "
                       f"sampled with the vibration ({option})")
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise RigError(f"{where}, sample {int(bad[0]) + 1}: not a finite number; fix the channel or cut the record")
    dt = 1.0 / rec.sample_rate_Hz
    # A tracked record only: order tracking's splines (scipy.interpolate) cost 0.4-0.6 s of import.
    from ..signals import order

    if kind == "speed channel":
        low = np.flatnonzero(v <= 0)
        if low.size:
            raise RigError(f"{where}, sample {int(low[0]) + 1}: {v[low[0]]:g} rpm; order tracking needs a positive "
                           "speed throughout: check the channel (--speed-channel) or cut the record")
        return order.speed_angle(v, dt), {"kind": kind, "channel": name, "pulses_per_rev": None}
    ppr = pulses or 1
    if np.ptp(v) == 0:
        raise RigError(f"{where} is constant ({v[0]:g}): no pulses; check the channel, or name the pulse channel "
                       "with --tachometer")
    times = order.pulse_times(v, dt)
    if times.size < MIN_PULSES:
        raise RigError(f"{where} holds {times.size} pulses; order tracking needs at least {MIN_PULSES}: check the "
                       "channel (--tachometer) or record longer")
    gaps = np.diff(times)
    jump = np.maximum(gaps[1:] / gaps[:-1], gaps[:-1] / gaps[1:])
    if jump.size and jump.max() > MAX_INTERVAL_JUMP:
        i = int(np.argmax(jump))
        raise RigError(f"{where}: the interval after pulse {i + 2} ({gaps[i + 1] * 1e3:.3g} ms) is {jump[i]:.1f} times "
                       f"the one before ({gaps[i] * 1e3:.3g} ms): a noisy or wrong channel, not a shaft; check the "
                       "channel (--tachometer) and its pulses per revolution")
    return order.shaft_angle(times, ppr), {"kind": kind, "channel": name, "pulses_per_rev": ppr}


def shaft_speed(rec: VibrationRecord, rig: Rig, rpm: float | str | None = None,
                shaft_Hz: float | str | None = None) -> tuple[float, str]:
    """The shaft speed [rpm] and where it came from: the options, else the rig file, else the record's own
    ``*RPM`` variable; a value given as a field's path is read from the record in the unit its key names."""
    given = ((rpm, "shaft_speed_rpm", "--rpm"), (shaft_Hz, "shaft_speed_Hz", "--shaft-hz"),
             (rig.shaft_speed_rpm, "shaft_speed_rpm", f"rig file {rig.source}"),
             (rig.shaft_speed_Hz, "shaft_speed_Hz", f"rig file {rig.source}"))
    for value, key, source in given:
        if value is None:
            continue
        if isinstance(value, str):
            unit = "rpm" if key == "shaft_speed_rpm" else "Hz"
            source = f"{source}: the record's field {value} [{unit}]"
            value = rec.field_value(value, f"the shaft speed in {unit}, {key}")
        speed = float(value) * SPEED_UNITS[key]
        if not speed > 0 or not math.isfinite(speed):
            raise RigError(f"{source}: shaft speed {speed:g} rpm; give a positive speed")
        return speed, source
    if rec.speed_rpm is not None:
        return float(rec.speed_rpm), f"the record's RPM variable ({rec.source})"
    raise RigError(f"{rec.source}: no shaft speed given and none in the record; give --rpm R (or shaft_speed_rpm in "
                   "the rig file; either can name a field of the record, shaft_speed_Hz: bearing.rate)")


def write_detection(result: RecordingDetection, out: str | Path) -> dict[str, Path]:
    """Write ``detection.json``, ``report.md`` and ``detection.png`` into ``out``; returns their paths."""
    out = Path(out)
    paths = {"json": out / "detection.json", "report": out / "report.md", "figure": out / "detection.png"}
    d = result.to_dict()
    write_json(d, paths["json"])
    save_detection(detection_figure(result.detection.to_dict(), Path(result.record.source).name), paths["figure"])
    paths["report"].write_text(report_markdown(d, paths["figure"].name), encoding="utf-8")
    return paths


def report_markdown(d: dict, figure: str) -> str:
    """The report of a ``detection.json`` dict."""
    rec, brg = d["record"], d["bearing"]
    lines = [
        f"# Fault detection: {Path(rec['file']).name}",
        "",
        f"**{d['summary']}**",
        "",
        f"- record: `{rec['file']}`, channel `{rec['channel']}`, {rec['rate_Hz']:g} Hz, {rec['duration_s']:.3g} s",
        f"- bearing: {brg['designation'] or 'geometry given'} ({brg['n_rolling_elements']} rolling elements of "
        f"{brg['rolling_element_diameter_m'] * 1e3:.4g} mm on {brg['pitch_diameter_m'] * 1e3:.4g} mm, contact angle "
        f"{brg['contact_angle_deg']:g} deg)",
        f"- shaft speed: {d['shaft_speed_given_rpm']:g} rpm given ({d['shaft_speed_source']}), "
        f"{d['shaft_speed_found_rpm']:.1f} rpm found"
        + ("" if d["details"]["shaft"]["refined"] else " (not refined: its harmonics do not show)"),
        f"- band: {d['band_Hz'][0]:.0f}-{d['band_Hz'][1]:.0f} Hz (pre-whitened, squared envelope spectrum)",
        f"- false-alarm probability of the call: {d['false_alarm_probability']:g}",
        "",
    ]
    tracked = d.get("order_tracking")
    unit = "order" if tracked else "Hz"
    if tracked:
        lines[-1:-1] = [
            f"- order-tracked from the {tracked['kind']} `{tracked['channel']}`: {tracked['min_speed_rpm']:.0f}-"
            f"{tracked['max_speed_rpm']:.0f} rpm, resampled at {tracked['samples_per_rev']} samples per revolution "
            f"({tracked['n_revolutions']:.0f} revolutions); the band is chosen in time, the lines' frequencies "
            "and the spectrum are in orders (cycles per revolution)"]
    why = type_lines(d)
    if why:
        lines += ["## Why this call", "", *[f"- {w}" for w in why], ""]
    lines += [
        "| family | statistic | threshold | margin [dB] | detected | lines above their threshold |",
        "|---|---:|---:|---:|---|---|",
    ]
    for name, f in d["families"].items():
        above = ", ".join(f"{ln['label']} ({ln['frequency_Hz']:.2f} {unit}, {ln['level_dB']:.1f} dB)"
                          for ln in f["lines"] if ln["above"]) or "-"
        lines.append(f"| {name.replace('_', ' ')} | {f['statistic']:.1f} | {f['threshold']:.1f} | "
                     f"{f['margin_dB']:+.1f} | {'yes' if f['detected'] else 'no'} | {above} |")
    lines += [
        "",
        f"![squared envelope spectrum and kurtogram]({figure})",
        "",
        "Top: the squared envelope spectrum of the band used, over its local median; shaded, each family's line "
        "windows (slip and speed tolerance); dotted, the shaft harmonics (left out of the windows). Bottom: the "
        "fast kurtogram; red, the band used.",
        "",
    ]
    return "\n".join(lines)


# --------------------------------------------------------------------------- many records at once

#: The batch table's columns (``detections.csv``), a row per record.
BATCH_COLUMNS = ("order", "file", "status", "error", "call", "outer_race_margin_dB", "inner_race_margin_dB",
                 "rolling_element_margin_dB", "separation_dB", "candidates", "shaft_speed_found_rpm",
                 "band_low_Hz", "band_high_Hz", "time", "x", "out")
#: strftime directives a file-name time pattern may hold, and the digits each matches.
_TIME_DIRECTIVES = {"%Y": r"\d{4}", "%m": r"\d{2}", "%d": r"\d{2}", "%H": r"\d{2}", "%M": r"\d{2}", "%S": r"\d{2}",
                    "%j": r"\d{3}", "%y": r"\d{2}", "%f": r"\d{1,6}"}


def record_files(paths: list[str | Path], pattern: str | None = None) -> list[Path]:
    """The record files named: files as given, a folder's record files (by :data:`RECORD_FORMATS` extension,
    or those matching the glob ``pattern``, in name order; its rig files are not records)."""
    out = []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(f for f in (p.glob(pattern) if pattern else p.iterdir())
                           if f.is_file() and f.suffix.lower() in RECORD_FORMATS)
            if not found:
                looked = f"'{pattern}'" if pattern else ", ".join(RECORD_FORMATS)
                raise RigError(f"{p}: no record files in the folder (looked for {looked}); give the folder that "
                               "holds the records" + (" or another --glob" if pattern else ""))
            out += found
        else:
            out.append(p)
    return out


def check_names(files: list[Path]) -> None:
    """Refuse two records of one name: each record's outputs go to a folder of its name."""
    stems = [f.stem for f in files]
    twice = sorted({s for s in stems if stems.count(s) > 1})
    if twice:
        raise RigError(f"{twice[0]}: two records share this name (each record's outputs go to --out/<name>/); "
                       "rename one or run the folders one at a time")


def time_from_name(name: str, pattern: str) -> datetime:
    """The time a file name states by a strftime ``pattern`` (``%Y%m%d_%H%M%S``), found anywhere in the name."""
    regex = re.escape(pattern)
    for directive, digits in _TIME_DIRECTIVES.items():
        regex = regex.replace(re.escape(directive), digits)
    m = re.search(regex, name)
    if m is None:
        raise RigError(f"{name}: no time matching --time-from-name '{pattern}' in the file name; give the pattern "
                       "the names hold (e.g. %Y%m%d_%H%M%S) or leave it out (the records' order by name)")
    return datetime.strptime(m.group(0), pattern)


def record_time(rec: VibrationRecord, field: str) -> float | datetime:
    """The record's time held in a field: a number as it is (e.g. hours run), a text as a date and time."""
    import pandas as pd  # a batch's (module docstring)

    contents = rec.contents
    if contents is not None and field in contents.texts:
        try:
            return pd.Timestamp(contents.texts[field].strip()).to_pydatetime()
        except ValueError:
            raise MeasurementError(f"{rec.source}: field '{field}' (--time-field) holds '{contents.texts[field]}', "
                                   "not a date and time; name a field with an ISO time or a number") from None
    return rec.field_value(field, "the record's time, --time-field")


def detect_one(job: dict) -> dict:
    """One record of a batch: its detection written into ``job["out"]/<name>/``, and its table row
    (:data:`BATCH_COLUMNS`; the one-line error in the row where the record cannot be read).

    ``job``: ``record`` (the file), ``order`` (its place by name), ``out``, and the options of
    :func:`detect_records` (``rig``, ``bearing``, ``rpm``, ``fs``, ``channel``, ``shaft_Hz``, ``time_field``,
    ``time_pattern``)."""
    path = Path(job["record"])
    row = {c: None for c in BATCH_COLUMNS} | {"order": job["order"], "file": str(path), "status": "ok", "error": ""}
    try:
        result = detect_recording(path, rig_beside(path, job["rig"]), job["bearing"], job["rpm"], job["fs"],
                                  job["channel"], shaft_Hz=job["shaft_Hz"], tachometer=job.get("tachometer"),
                                  pulses_per_rev=job.get("pulses_per_rev"), speed_channel=job.get("speed_channel"))
        if job["time_field"]:
            row["time"] = record_time(result.record, job["time_field"])
        elif job["time_pattern"]:
            row["time"] = time_from_name(path.name, job["time_pattern"])
    except (MeasurementError, RigError, BearingError) as e:
        return row | {"status": "error", "error": str(e)}
    out = Path(job["out"]) / path.stem
    write_detection(result, out)
    d = result.to_dict()
    typed = d["type_call"] or {}
    row.update({
        "call": d["fault_type"],
        **{f"{f}_margin_dB": d["families"][f]["margin_dB"] for f in ("outer_race", "inner_race", "rolling_element")},
        "separation_dB": typed.get("separation_dB"),
        "candidates": " ".join(typed.get("candidates", [])) if d["fault_type"] == UNKNOWN else "",
        "shaft_speed_found_rpm": d["shaft_speed_found_rpm"], "band_low_Hz": d["band_Hz"][0],
        "band_high_Hz": d["band_Hz"][1], "out": str(out),
    })
    return row


def detect_records(records: list[str | Path], out: str | Path, rig: str | Path | None = None,
                   bearing: str | None = None, rpm: float | str | None = None, fs: float | str | None = None,
                   channel: str | None = None, shaft_Hz: float | str | None = None, time_field: str | None = None,
                   time_pattern: str | None = None, jobs: int = 1, progress=None,
                   pattern: str | None = None, tachometer: str | None = None, pulses_per_rev: int | None = None,
                   speed_channel: str | None = None) -> pd.DataFrame:
    """Detect a fault in every record (files, or folders of them), each record's outputs in ``out/<name>/``,
    and write ``out/detections.csv`` (:data:`BATCH_COLUMNS`, a row per record) and ``out/trend.png`` (the
    margins over the records: their time from ``time_field`` or ``time_pattern``, else their order by name).

    A record's own rig file (same name, ``.yaml``) is its; ``rig`` and the options apply to all. A record that
    cannot be read gets its row with the one-line error (``status`` ``error``) and stops nothing.
    ``progress``: called with each finished row. ``jobs``: records detected at once (processes). ``pattern``:
    a folder's records are the files matching this glob (``*.mat``), else every file of a record format.
    ``tachometer``, ``pulses_per_rev``, ``speed_channel``: order tracking (:func:`detect_recording`).
    """
    files = record_files(records, pattern)
    check_names(files)
    out = Path(out)
    base = {"rig": rig, "bearing": bearing, "rpm": rpm, "fs": fs, "channel": channel, "shaft_Hz": shaft_Hz,
            "time_field": time_field, "time_pattern": time_pattern, "out": str(out), "tachometer": tachometer,
            "pulses_per_rev": pulses_per_rev, "speed_channel": speed_channel}
    todo = [base | {"record": str(f), "order": i + 1} for i, f in enumerate(sorted(files, key=lambda f: f.name))]
    rows = []
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            for row in pool.map(detect_one, todo):
                rows.append(row)
                progress and progress(row)
    else:
        for job in todo:
            rows.append(detect_one(job))
            progress and progress(rows[-1])
    return write_batch(rows, out, time_field, time_pattern)


def write_batch(rows: list[dict], out: str | Path, time_field: str | None = None,
                time_pattern: str | None = None) -> pd.DataFrame:
    """The batch's table ``out/detections.csv`` and trend ``out/trend.png`` of its rows (:func:`detect_one`),
    in the records' time where given, else their order by name."""
    import pandas as pd  # a batch's table (module docstring)

    out = Path(out)
    table = pd.DataFrame(rows, columns=list(BATCH_COLUMNS)).sort_values("order", kind="stable")
    if time_field or time_pattern:
        table["x"] = table["time"]
        x_label = "record time" + (f" (field {time_field})" if time_field else "")
        table = table.sort_values("x", kind="stable", na_position="last")
    else:
        table["x"] = table["order"]
        x_label = "record, in order of file name"
    out.mkdir(parents=True, exist_ok=True)
    table.to_csv(out / "detections.csv", index=False, float_format="%.6g")
    save(trend_figure(table, x_label), out / "trend.png")
    return table
