"""The sensor FEM stages' error, in a module of its own: the scorecard's sensor rows raise it on a bad results file
without importing the finite elements (sfepy)."""

from __future__ import annotations


class SensorFemError(ValueError):
    """A bad input file or config value of the sensor FEM stages."""
