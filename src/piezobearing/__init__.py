"""piezobearing: a PZT force sensor in a bearing housing, from calibration to fault detection.

All physics, numerics and I/O live in this package; the Snakemake workflow
only calls it. Units are SI throughout.

The public API (:mod:`piezobearing.api`):

- :func:`read_record`: a calibration or running-bearing record of any supported format;
- :func:`calibrate`: the sensor's sensitivity and circuit resistance from force and voltage;
- :func:`simulate`: the running bearing and its sensor for a config;
- :func:`detect`: a fault of any rolling bearing in a record (a :class:`Detection`);
- :func:`diagnose`: what the model misses in a calibration or running-bearing record.
"""

from .api import Calibration, Diagnosis, Simulation, calibrate, detect, diagnose, read_record, simulate
from .bearing.kinematics import Kinematics, RollingBearing
from .signals.detectors import Detection

__version__ = "0.1.0"

__all__ = ["Calibration", "Detection", "Diagnosis", "Kinematics", "RollingBearing", "Simulation", "__version__",
           "calibrate", "detect", "diagnose", "read_record", "simulate"]
