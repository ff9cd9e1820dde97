"""piezobearing: a PZT force sensor in a bearing housing, from calibration to fault detection.

All physics, numerics and I/O live in this package; the Snakemake workflow
only calls it. Units are SI throughout.

The public API (:mod:`piezobearing.api`):

- :func:`read_record`: a calibration or running-bearing record of any supported format;
- :func:`calibrate`: the sensor's sensitivity and circuit resistance from force and voltage;
- :func:`simulate`: the running bearing and its sensor for a config;
- :func:`detect`: a fault of any rolling bearing in a record (a :class:`Detection`);
- :func:`diagnose`: what the model misses in a calibration or running-bearing record.

``import piezobearing`` loads none of them: each public name and each subpackage is imported on its first use
(a module ``__getattr__``, SPEC 1, as scipy does), so a command or a workflow job pays only for what it calls.
"""

import importlib

__version__ = "0.1.0"

#: Each public name and the module that defines it, imported on first access.
_EXPORTS = {
    "Calibration": "piezobearing.api",
    "Diagnosis": "piezobearing.api",
    "Simulation": "piezobearing.api",
    "calibrate": "piezobearing.api",
    "detect": "piezobearing.api",
    "diagnose": "piezobearing.api",
    "read_record": "piezobearing.api",
    "simulate": "piezobearing.api",
    "Kinematics": "piezobearing.bearing.kinematics",
    "RollingBearing": "piezobearing.bearing.kinematics",
    "Detection": "piezobearing.signals.detectors",
    "Record": "piezobearing.io.records",
}

#: The subpackages and modules reachable as attributes (``piezobearing.signals``), imported on first access.
_SUBMODULES = frozenset({
    "api", "bearing", "chain", "cli", "comparison", "config", "diagnosis", "fitting", "housing", "io", "numerics",
    "plotting", "scorecard", "sensor", "signals", "stages", "workflow",
})

__all__ = ["__version__", *sorted(_EXPORTS)]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value  # the next access is a plain attribute
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS, *_SUBMODULES})
