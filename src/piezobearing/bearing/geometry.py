"""The geometry of a cylindrical roller bearing from the config, and its kinematic frequencies.

The lumped-parameter model (:mod:`piezobearing.bearing.lpm`), the quasi-static surrogate and the signal chain
share it; it needs numpy alone, so a rule that only needs the bearing's frequencies loads no model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinematics import Kinematics, RollingBearing


@dataclass(frozen=True)
class BearingGeometry:
    """Geometry of a cylindrical roller bearing.

    Parameters
    ----------
    n_rollers : int
        Number of rollers Z [-].
    roller_diameter_m : float
        Roller diameter D_r [m].
    pitch_diameter_m : float
        Pitch (cage) diameter D_p [m].
    roller_length_m : float
        Effective contact length l of a roller [m].
    radial_clearance_m : float
        Radial internal clearance P_d [m]: the total radial play of one ring
        against the other (ISO 5753-1; Harris's diametral clearance). Each
        roller sees the gap P_d / 2 when the rings are concentric.
    outer_diameter_m : float
        Outer diameter of the outer ring D [m].
    width_m : float
        Width of the bearing B [m].
    contact_angle_deg : float
        Contact angle alpha [deg]; 0 for a cylindrical roller bearing.
    """

    n_rollers: int
    roller_diameter_m: float
    pitch_diameter_m: float
    roller_length_m: float
    radial_clearance_m: float
    outer_diameter_m: float
    width_m: float
    contact_angle_deg: float = 0.0

    @classmethod
    def from_config(cls, bearing: dict) -> BearingGeometry:
        """From the ``bearing`` section of the config."""
        keys = (
            "n_rollers roller_diameter_m pitch_diameter_m roller_length_m radial_clearance_m "
            "outer_diameter_m width_m contact_angle_deg"
        ).split()
        geo = cls(**{k: bearing[k] for k in keys})
        if geo.outer_raceway_radius_m >= geo.outer_diameter_m / 2:
            raise ValueError(
                "config bearing: pitch_diameter_m + roller_diameter_m must be smaller than outer_diameter_m "
                "(the outer raceway must lie inside the outer ring)"
            )
        return geo

    @property
    def rolling_bearing(self) -> RollingBearing:
        """The geometry the kinematics need (:class:`piezobearing.bearing.kinematics.RollingBearing`)."""
        return RollingBearing(self.n_rollers, self.roller_diameter_m, self.pitch_diameter_m, self.contact_angle_deg)

    @property
    def diameter_ratio(self) -> float:
        """D_r cos(alpha) / D_p [-]."""
        return float(
            self.roller_diameter_m * np.cos(np.radians(self.contact_angle_deg)) / self.pitch_diameter_m
        )

    @property
    def outer_raceway_radius_m(self) -> float:
        """Radius of the outer raceway, (D_p + D_r) / 2 [m]."""
        return 0.5 * (self.pitch_diameter_m + self.roller_diameter_m)

    @property
    def inner_raceway_radius_m(self) -> float:
        """Radius of the inner raceway, (D_p - D_r) / 2 [m]."""
        return 0.5 * (self.pitch_diameter_m - self.roller_diameter_m)

    def relative_radius_m(self, race: str) -> float:
        """Relative radius of curvature of a roller against a raceway [m].

        ``outer`` (concave raceway): 1 / (1/r - 1/R_o); ``inner`` (convex):
        1 / (1/r + 1/R_i), with r = D_r / 2. A chord of width w across a
        defect lets the roller sink w^2 / (8 R_rel) to first order: for the
        N 305 (r = 5 mm, R_o = 27 mm, R_i = 17 mm) R_rel is 6.14 mm outside,
        3.86 mm inside (26.3 um for that groove).
        """
        r = 0.5 * self.roller_diameter_m
        if race == "outer":
            return 1.0 / (1.0 / r - 1.0 / self.outer_raceway_radius_m)
        if race == "inner":
            return 1.0 / (1.0 / r + 1.0 / self.inner_raceway_radius_m)
        raise ValueError(f"race must be 'outer' or 'inner', got {race!r}")

    @property
    def spin_per_cage_angle(self) -> float:
        """Roller spin angle (relative to the cage) per cage angle, BSF / FTF = (D_p / D_r)(1 + D_r cos a / D_p) [-]."""
        return float(self.pitch_diameter_m / self.roller_diameter_m * (1 + self.diameter_ratio))

    @property
    def roller_pitch_rad(self) -> float:
        """Angle between neighbouring rollers, 2 pi / Z [rad]."""
        return 2 * np.pi / self.n_rollers


def kinematic_frequencies(geometry: BearingGeometry, shaft_speed_Hz: float, cage_slip: float = 0.0) -> Kinematics:
    """Kinematic frequencies of the model's bearing with the outer ring fixed and the cage slipping by the
    fraction s (:meth:`piezobearing.bearing.kinematics.Kinematics.from_geometry`, the one formula).

    Parameters
    ----------
    geometry : BearingGeometry
    shaft_speed_Hz : float
        Rotation frequency of the shaft and inner ring [Hz].
    cage_slip : float
        Mean cage slip s [-]; 0 for rolling without slip.

    Returns
    -------
    Kinematics
        shaft, FTF (cage), BPFO, BPFI and BSF [Hz]. For the N 305 ECP at
        1000 rpm (Z = 11, D_r / D_p = 10 / 44) the BPFO is 70.83 Hz.
    """
    return Kinematics.from_geometry(geometry.rolling_bearing, shaft_speed_Hz, cage_slip)
