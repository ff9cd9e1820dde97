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
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import yaml

from ..bearing.kinematics import BearingError, Kinematics, RollingBearing
from ..io import write_json
from ..io.vibration import VibrationRecord, read_vibration_record
from ..plotting import save
from ..plotting.detection import detection_figure
from ..signals.detectors import Detection
from ..signals.detectors import envelope as envelope_detector

#: The keys of a rig file.
RIG_KEYS = ("bearing", "shaft_speed_rpm", "sample_rate_Hz", "channel")


class RigError(ValueError):
    """A rig file or an argument that cannot be used (one line naming the key and the fix)."""


@dataclass(frozen=True)
class Rig:
    """What the rig's user knows about a record (None: not given).

    Attributes
    ----------
    bearing : RollingBearing or None
    shaft_speed_rpm : float or None
        [rpm]
    sample_rate_Hz : float or None
        [Hz]
    channel : str or None
    source : str
        The rig file, or "" where none was given.
    """

    bearing: RollingBearing | None = None
    shaft_speed_rpm: float | None = None
    sample_rate_Hz: float | None = None
    channel: str | None = None
    source: str = ""


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
    return Rig(bearing, _number(d, "shaft_speed_rpm", path), _number(d, "sample_rate_Hz", path),
               None if d.get("channel") is None else str(d["channel"]), str(path))


def _number(d: dict, key: str, path: Path) -> float | None:
    if d.get(key) is None:
        return None
    try:
        value = float(d[key])
    except (TypeError, ValueError):
        raise RigError(f"{path}: {key} = {d[key]!r} is not a number; give it in {key.rsplit('_', 1)[-1]}") from None
    if not value > 0 or not math.isfinite(value):
        raise RigError(f"{path}: {key} = {value:g}; give a positive number")
    return value


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
    """

    detection: Detection
    record: VibrationRecord
    bearing: RollingBearing
    speed_rpm: float
    speed_source: str
    kinematics: Kinematics

    def to_dict(self) -> dict:
        """``detection.json``: the call, per family its evidence, the band, the shaft speed found, the call's
        false-alarm probability, and what the record and the bearing were."""
        d = self.detection.to_dict()
        details = {k: v for k, v in d["details"].items() if k not in ("spectrum", "kurtogram")}
        return {
            "fault_type": d["fault_type"],
            "summary": summary(self.detection),
            "false_alarm_probability": d["false_alarm_probability"],
            "margin_dB": d["margin_dB"],
            "band_Hz": d["band_Hz"],
            "shaft_speed_found_rpm": 60.0 * d["shaft_rate_Hz"],
            "shaft_speed_given_rpm": self.speed_rpm,
            "shaft_speed_source": self.speed_source,
            "families": d["families"],
            "record": {"file": self.record.source, "channel": self.record.channel, "rate_Hz": self.record.rate_Hz,
                       "duration_s": self.record.duration_s, "channels_in_file": list(self.record.channels)},
            "bearing": {"designation": self.bearing.designation, "n_rolling_elements": self.bearing.n_rolling_elements,
                        "rolling_element_diameter_m": self.bearing.rolling_element_diameter_m,
                        "pitch_diameter_m": self.bearing.pitch_diameter_m,
                        "contact_angle_deg": self.bearing.contact_angle_deg,
                        "multiples_of_shaft_rate": self.bearing.multiples()},
            "kinematics_at_given_speed_Hz": self.kinematics.to_dict(),
            "method": d["method"],
            "details": details,
        }


def summary(detection: Detection) -> str:
    """One sentence: the call and its strongest evidence, or that no fault signature was found."""
    if detection.fault_type == "none":
        return (f"no fault signature found: no family's lines stand above their threshold at a false-alarm "
                f"probability of {detection.false_alarm_probability:g} (largest margin {detection.margin_dB:+.1f} dB)")
    family = detection.families[detection.fault_type]
    above = [ln.label for ln in family.lines if ln.above]
    return (f"{detection.fault_type.replace('_', ' ')} fault: {family.margin_dB:+.1f} dB over the threshold at a "
            f"false-alarm probability of {detection.false_alarm_probability:g}; lines above their own threshold: "
            f"{', '.join(above) or 'none alone (their sum passes)'}")


def detect_recording(record: str | Path, rig: str | Path | Rig | None = None, bearing: str | RollingBearing | None = None,
                     rpm: float | None = None, fs: float | None = None, channel: str | None = None,
                     settings: envelope_detector.Settings | None = None) -> RecordingDetection:
    """Detect a bearing fault in a recording.

    Parameters
    ----------
    record : path
        The record file (.mat v5/v7.3, .csv, .wav, .uff/.unv, .tdms).
    rig : path or Rig, optional
        The rig file (module docstring); the other arguments override it.
    bearing : str or RollingBearing, optional
        A designation of the table (``"SKF 6205"``) or a bearing.
    rpm : float, optional
        The shaft speed [rpm]; else the rig file's, else the record's own ``*RPM`` variable.
    fs : float, optional
        The sampling rate [Hz] where the file has no time axis; else the rig file's.
    channel : str, optional
        The channel's name or a unique suffix (``_DE_time``); else the rig file's.
    settings : envelope detector Settings, optional
        Default: ``Settings()`` (pre-whitening, fast kurtogram and whole band, pfa 1e-3).

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
    rec = read_vibration_record(record, channel if channel is not None else rig.channel,
                                fs if fs is not None else rig.sample_rate_Hz)
    for value, source in ((rpm, "--rpm"), (rig.shaft_speed_rpm, f"rig file {rig.source}"),
                          (rec.speed_rpm, f"the record's RPM variable ({rec.source})")):
        if value is not None:
            speed, speed_source = float(value), source
            break
    else:
        raise RigError(f"{record}: no shaft speed given and none in the record; give --rpm R (or shaft_speed_rpm in "
                       "the rig file)")
    if not speed > 0:
        raise RigError(f"{speed_source}: shaft speed {speed:g} rpm; give a positive speed in rpm")
    kinematics = bearing.kinematics(speed / 60.0)
    settings = settings or envelope_detector.Settings()
    try:
        detection = envelope_detector.detect(rec.samples, rec.rate_Hz, kinematics.to_dict(), settings)
    except ValueError as e:
        raise RigError(f"{record}: {e}") from None
    return RecordingDetection(detection, rec, bearing, speed, speed_source, kinematics)


def write_detection(result: RecordingDetection, out: str | Path) -> dict[str, Path]:
    """Write ``detection.json``, ``report.md`` and ``detection.png`` into ``out``; returns their paths."""
    out = Path(out)
    paths = {"json": out / "detection.json", "report": out / "report.md", "figure": out / "detection.png"}
    d = result.to_dict()
    write_json(d, paths["json"])
    save(detection_figure(result.detection.to_dict(), Path(result.record.source).name), paths["figure"])
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
        "| family | statistic | threshold | margin [dB] | detected | lines above their threshold |",
        "|---|---:|---:|---:|---|---|",
    ]
    for name, f in d["families"].items():
        above = ", ".join(f"{ln['label']} ({ln['frequency_Hz']:.2f} Hz, {ln['level_dB']:.1f} dB)"
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
