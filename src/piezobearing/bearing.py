"""The bearing: geometry, kinematic frequencies and the 4-DOF lumped-parameter model.

SKF N 305 ECP cylindrical roller bearing (paper Sec. III-A, IV): 11 rollers,
outer ring stationary in the housing, inner ring turning with the shaft.

Angles
------
Roller and defect positions are angles psi [rad] in the bearing's plane,
measured from the direction of the radial load (the bottom of the bearing,
-z) and increasing with the sense of rotation. The outward unit normal of the
outer raceway at psi is ``n(psi) = (sin psi, -cos psi)`` in the (y, z) plane
of the housing model (y horizontal, z up, x along the shaft).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Palmgren's line-contact constant: delta = 3.84e-5 Q^0.9 / l^0.8 with delta,
#: l in mm and Q in N (Harris & Kotzalas, Rolling Bearing Analysis, Eq. 6.41),
#: converted to SI: delta [m] = PALMGREN_SI * Q^0.9 * l^-0.8 with l in m.
PALMGREN_SI = 3.84e-5 * 1e-3 * 1e3**-0.8


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
    def diameter_ratio(self) -> float:
        """D_r cos(alpha) / D_p [-]."""
        return float(self.roller_diameter_m * np.cos(np.radians(self.contact_angle_deg)) / self.pitch_diameter_m)

    @property
    def outer_raceway_radius_m(self) -> float:
        """Radius of the outer raceway, (D_p + D_r) / 2 [m]."""
        return 0.5 * (self.pitch_diameter_m + self.roller_diameter_m)

    @property
    def roller_pitch_rad(self) -> float:
        """Angle between neighbouring rollers, 2 pi / Z [rad]."""
        return 2 * np.pi / self.n_rollers


@dataclass(frozen=True)
class KinematicFrequencies:
    """Kinematic frequencies of a bearing with a stationary outer ring [Hz].

    Attributes
    ----------
    shaft_Hz : float
        Shaft (inner ring) rotation frequency f_r.
    ftf_Hz : float
        Fundamental train (cage) frequency, f_r / 2 (1 - D_r cos a / D_p).
    bpfo_Hz : float
        Ball (roller) pass frequency on the outer race, Z * FTF.
    bpfi_Hz : float
        Roller pass frequency on the inner race, Z (f_r - FTF).
    bsf_Hz : float
        Roller spin frequency, D_p / (2 D_r) f_r (1 - (D_r cos a / D_p)^2).
    """

    shaft_Hz: float
    ftf_Hz: float
    bpfo_Hz: float
    bpfi_Hz: float
    bsf_Hz: float

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")}


def kinematic_frequencies(geometry: BearingGeometry, shaft_speed_Hz: float) -> KinematicFrequencies:
    """Kinematic frequencies for rolling without slip, outer ring fixed.

    Parameters
    ----------
    geometry : BearingGeometry
    shaft_speed_Hz : float
        Rotation frequency of the shaft and inner ring [Hz].

    Returns
    -------
    KinematicFrequencies
        shaft, FTF (cage), BPFO, BPFI and BSF [Hz]. For the N 305 ECP at
        1000 rpm (Z = 11, D_r / D_p = 10 / 44) the BPFO is 70.83 Hz.
    """
    g, z = geometry.diameter_ratio, geometry.n_rollers
    fr = float(shaft_speed_Hz)
    ftf = 0.5 * fr * (1 - g)
    return KinematicFrequencies(
        shaft_Hz=fr,
        ftf_Hz=ftf,
        bpfo_Hz=z * ftf,
        bpfi_Hz=z * (fr - ftf),
        bsf_Hz=0.5 * geometry.pitch_diameter_m / geometry.roller_diameter_m * fr * (1 - g**2),
    )
