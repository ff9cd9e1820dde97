"""The fit machinery shared by the sensor's calibration and the diagnosis: parameters with units and bounds,
least squares, and profile-likelihood intervals."""
