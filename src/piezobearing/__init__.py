"""piezobearing: a PZT force sensor in a bearing housing, from calibration to fault detection.

All physics, numerics and I/O live in this package; the Snakemake workflow
only calls it. Units are SI throughout.
"""

__version__ = "0.1.0"
