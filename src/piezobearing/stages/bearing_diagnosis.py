"""Stages of the running bearing held against its model (rules ``synthesize_bearing_record``,
``diagnose_bearing``; CLI ``piezobearing diagnose-bearing``).

The record is the user's (``bearing.measurement``) or a synthetic one with
``bearing.hidden_effects``; the housing's influence line is the workflow's
(``results/bearing/influence_line_healthy.csv``) or, from the CLI, solved
from the config's housing. Writes into one folder ``diagnosis.json``,
``diagnosis.npz``, ``figures/*.png`` and ``report.md``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from ..bearing.surrogate import InfluenceLine
from ..diagnosis import engine
from ..diagnosis.bearing.subject import SUBJECT, synthesise
from ..housing import transient as bearing_transient
from ..housing.mesh import build_housing_mesh
from ..io import (
    MeasurementError,
    ResultFileError,
    read_harmonic,
    record_rpm,
    write_bearing_record,
)
from ..plotting.bearing_diagnosis import all_figures
from .diagnosis_files import write_diagnosis

#: Config sections a bearing diagnosis depends on (copied into diagnosis.json).
CONFIG_KEYS = ("sensor", "bearing", "housing", "bearing_diagnosis", "diagnostics")


def read_influence(path: str | Path) -> InfluenceLine:
    """The housing's influence line (angle_rad, sensor_per_radial_load) written by housing_transient."""
    p = Path(path)
    if not p.exists():
        raise ResultFileError(f"{p}: file not found; run the rule housing_transient_healthy")
    df = pd.read_csv(p)
    for c in ("angle_rad", "sensor_per_radial_load"):
        if c not in df.columns:
            raise ResultFileError(f"{p}: column '{c}' missing; rerun the rule housing_transient_healthy")
    return InfluenceLine(df["angle_rad"].to_numpy(), df["sensor_per_radial_load"].to_numpy())


def influence_from_config(config: dict) -> InfluenceLine:
    """Solve the config's healthy housing once for its influence line (mesh, assembly, one solve)."""
    mesh = build_housing_mesh(bearing_transient.housing_geometry(config), False, config["housing"]["mesh_level"])
    _, _, radial = bearing_transient.make_model(mesh, config).influence_line()
    return InfluenceLine(mesh.raceway_psi, radial)


def harmonic_of(path: str | Path | None):
    """The sensor FEM's (frequency [Hz], |V/F| [V/N], the file) from ``path`` (results/sensor/harmonic.csv), or
    None; the sensor model names the file it took its correction from."""
    return (*read_harmonic(path), str(path)) if path else None


def synthesize_bearing_record(influence_csv: str, out_csv: str, config: dict, harmonic_csv: str | None = None) -> None:
    """Write the synthetic running-bearing record with ``bearing.hidden_effects`` (seeded by ``seed``); the sensor
    model with the FEM response ``harmonic_csv`` (the workflow's), else the paper sensor's."""
    rec = synthesise(config, config["seed"], config["bearing"]["hidden_effects"], read_influence(influence_csv),
                     harmonic_of(harmonic_csv))
    write_bearing_record(rec, out_csv)


def shaft_speed_given(record_path: str | Path, config: dict, rpm: float | None = None,
                      config_sets_speed: bool = True) -> dict:
    """The nominal shaft speed the diagnosis starts from [rpm], and where it comes from.

    In order: ``rpm`` (``--rpm``); the config's ``bearing.shaft_speed_rpm`` where the user's config sets it
    (``config_sets_speed``: the rig file of the command, the workflow's config); the record's own scalar
    ``*RPM`` variable (a ``.mat`` file, :func:`piezobearing.io.record_rpm`, as ``piezobearing detect`` reads
    it); else the default config's. The shaft speed is then fitted within
    ``bearing_diagnosis.speed_tolerance_ratio`` of it (or taken from a ``speed_rpm`` column).

    Returns ``{"rpm", "source", "record_rpm", "record_rpm_variable"}`` (the last two None for a record
    that states no speed).
    """
    stated = record_rpm(record_path)
    if stated is not None and not stated[0] > 0:
        raise MeasurementError(f"{record_path}: variable {stated[1]} states a shaft speed of {stated[0]:g} rpm; "
                               "give a positive speed (or --rpm R)")
    if rpm is not None:
        used, source = float(rpm), "--rpm"
    elif config_sets_speed or stated is None:
        used = float(config["bearing"]["shaft_speed_rpm"])
        source = "bearing.shaft_speed_rpm of the " + ("config" if config_sets_speed else "default config")
    else:
        used, source = stated[0], f"the record's {stated[1]} variable"
    return {"rpm": used, "source": source, "record_rpm": None if stated is None else stated[0],
            "record_rpm_variable": None if stated is None else stated[1]}


def run(
    record_path: str,
    influence: InfluenceLine | Callable[[], InfluenceLine],
    config: dict,
    progress: Callable[[str], None] | None = None,
    harmonic: tuple[np.ndarray, np.ndarray] | None = None,
    rpm: float | None = None,
    config_sets_speed: bool = True,
) -> tuple[dict, dict]:
    """Diagnose one running-bearing record; returns (JSON-ready dict, arrays).

    ``influence`` may be a function that gives the line: it is called after the config and the record
    were checked, so a bad record or key is reported before the housing is solved (seconds of FEM).
    ``harmonic``: the sensor FEM's response of this configuration (else the paper sensor's); the dict's
    ``sensor_model`` says which model turned force into voltage. ``rpm``, ``config_sets_speed``: the nominal
    shaft speed (:func:`shaft_speed_given`; the dict's ``shaft_speed``)."""
    SUBJECT.check_config(config)
    speed = shaft_speed_given(record_path, config, rpm, config_sets_speed)
    config["bearing"]["shaft_speed_rpm"] = speed["rpm"]
    rec = SUBJECT.read(record_path, config)
    warnings = list(rec.warnings)
    tol = config["bearing_diagnosis"]["speed_tolerance_ratio"]
    if speed["record_rpm"] is not None and abs(speed["record_rpm"] / speed["rpm"] - 1) > tol:
        warnings.append(
            f"{record_path}: variable {speed['record_rpm_variable']} states {speed['record_rpm']:g} rpm, the "
            f"diagnosis starts from {speed['rpm']:g} rpm ({speed['source']}), more than the speed tolerance "
            f"({100 * tol:g} %) apart; give the speed the rig ran at (--rpm R)"
        )
    if not isinstance(influence, InfluenceLine):
        influence = influence()
    d, diag = SUBJECT.diagnose((rec, influence, harmonic), config, progress)
    out = {"source": rec.source, "record_warnings": warnings, "shaft_speed": speed,
           "sensor_model": d.record.rig.sensor.to_dict(), **diag}
    used = {k: config[k] for k in CONFIG_KEYS if k in config}
    if not config["bearing"].get("measurement"):
        used["seed"] = config["seed"]
    out["config"] = used
    arrays = engine.arrays(d)
    return out, arrays


def diagnose_bearing(
    record_path: str,
    out_dir: str | Path,
    config: dict,
    influence_csv: str | None = None,
    progress: Callable[[str], None] | None = None,
    harmonic_csv: str | None = None,
    rpm: float | None = None,
    config_sets_speed: bool = True,
) -> dict:
    """Write diagnosis.json, diagnosis.npz, figures/ and report.md into ``out_dir``; returns the dict.
    ``harmonic_csv``: the sensor FEM's response (results/sensor/harmonic.csv), else the paper sensor's;
    ``rpm``, ``config_sets_speed``: the nominal shaft speed (:func:`shaft_speed_given`)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    influence = read_influence(influence_csv) if influence_csv else (lambda: influence_from_config(config))
    diag, arrays = run(record_path, influence, config, progress, harmonic_of(harmonic_csv), rpm, config_sets_speed)
    write_diagnosis(out_dir, diag, arrays, all_figures, SUBJECT.report)
    return diag
