"""Kinematics of any rolling bearing (ball or roller, with a contact angle) with a stationary outer ring.

From the geometry (Z rolling elements of diameter d on a pitch diameter D, contact angle a; g = d cos a / D)
and the shaft rate f_r, with the cage lagging rolling without slip by the fraction s (Randall & Antoni,
MSSP 25 (2011) 485-520, Eq. 1-4):

.. math::

    FTF = (1 - s)\\,\\tfrac{f_r}{2}(1 - g),\\quad BPFO = Z\\,FTF,\\quad BPFI = Z\\,(f_r - FTF),\\quad
    BSF = (1 - s)\\,\\tfrac{D}{2d}\\,f_r\\,(1 - g^2).

A defect on a rolling element strikes both races once per spin each: at 2 BSF. The bearings of
:data:`DESIGNATIONS_CSV` (package data, each row with its source) are reachable by designation
(:meth:`RollingBearing.from_designation`: ``"SKF 6205"``, ``"6205-2RS JEM"``, ``"N305 ECP"``).
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from importlib import resources
from typing import Mapping

#: The bearing designations with published geometry, one row each with its source.
DESIGNATIONS_CSV = "designations.csv"
#: The kinematic frequencies' keys, as the workflow writes them to ``kinematics.json`` [Hz].
KINEMATIC_KEYS = ("shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz")
#: The geometry's keys (a rig file's ``bearing`` section).
GEOMETRY_KEYS = ("n_rolling_elements", "rolling_element_diameter_m", "pitch_diameter_m", "contact_angle_deg")


class BearingError(ValueError):
    """A bearing that cannot be used as given (one line naming the key or designation and the fix)."""


@dataclass(frozen=True)
class RollingBearing:
    """What a rolling bearing's kinematics need.

    Attributes
    ----------
    n_rolling_elements : int
        Balls or rollers Z [-].
    rolling_element_diameter_m : float
        Their diameter d [m].
    pitch_diameter_m : float
        Pitch diameter D [m].
    contact_angle_deg : float
        Contact angle a [deg] (0 for a radial ball or a cylindrical roller bearing).
    designation : str
        Its name (``"SKF 6205"``), or "" where only the geometry is known.
    """

    n_rolling_elements: int
    rolling_element_diameter_m: float
    pitch_diameter_m: float
    contact_angle_deg: float = 0.0
    designation: str = ""

    def __post_init__(self):
        name = f"bearing {self.designation}" if self.designation else "bearing"
        if int(self.n_rolling_elements) != self.n_rolling_elements or self.n_rolling_elements < 3:
            raise BearingError(f"{name}: n_rolling_elements = {self.n_rolling_elements}; give a whole number >= 3")
        if not 0 < self.rolling_element_diameter_m < self.pitch_diameter_m:
            raise BearingError(
                f"{name}: rolling_element_diameter_m = {self.rolling_element_diameter_m:g} and pitch_diameter_m = "
                f"{self.pitch_diameter_m:g}; give both in metres, the element smaller than the pitch diameter"
            )
        if not 0 <= self.contact_angle_deg < 90:
            raise BearingError(f"{name}: contact_angle_deg = {self.contact_angle_deg:g}; give an angle in [0, 90) deg")

    @property
    def diameter_ratio(self) -> float:
        """g = d cos(a) / D [-]."""
        return self.rolling_element_diameter_m * math.cos(math.radians(self.contact_angle_deg)) / self.pitch_diameter_m

    def kinematics(self, shaft_Hz: float, cage_slip: float = 0.0) -> "Kinematics":
        """The kinematic frequencies at shaft rate ``shaft_Hz`` [Hz] and cage slip ``cage_slip`` [-]."""
        return Kinematics.from_geometry(self, shaft_Hz, cage_slip)

    def multiples(self) -> dict[str, float]:
        """The fault frequencies as multiples of the shaft rate, no slip (how bearing tables print them) [-]."""
        k = self.kinematics(1.0)
        return {"bpfi": k.bpfi_Hz, "bpfo": k.bpfo_Hz, "ftf": k.ftf_Hz, "bsf": k.bsf_Hz, "2bsf": 2 * k.bsf_Hz}

    @classmethod
    def from_designation(cls, designation: str) -> "RollingBearing":
        """A bearing of :func:`designations` by its name (case, spaces and hyphens ignored; a seal or cage
        suffix such as ``-2RS JEM`` and the maker's name may be left out or added)."""
        rows = designations()
        want = _key(designation)
        for row in rows:
            key = _key(row.designation)
            bare = re.sub(r"^(SKF|FAG|NSK|NTN|TIMKEN|INA)", "", key)
            if want in (key, bare) or want.startswith(key) or want.startswith(bare):
                return row
        known = "; ".join(r.designation for r in rows)
        raise BearingError(
            f"bearing designation '{designation}' not in the table ({known}); give the geometry instead "
            "(bearing: n_rolling_elements, rolling_element_diameter_m, pitch_diameter_m, contact_angle_deg)"
        )

    @classmethod
    def from_config(cls, bearing: Mapping, source: str = "bearing") -> "RollingBearing":
        """From a rig file's ``bearing`` section: the geometry keys, or only ``designation`` (then from the
        table); ``source`` names the file or section in messages."""
        if not isinstance(bearing, Mapping):
            raise BearingError(f"{source}: 'bearing' must be a mapping of {', '.join(GEOMETRY_KEYS)} or a designation")
        given = [k for k in GEOMETRY_KEYS[:3] if bearing.get(k) is not None]
        designation = str(bearing.get("designation") or "")
        if not given and designation:
            return cls.from_designation(designation)
        missing = [k for k in GEOMETRY_KEYS[:3] if bearing.get(k) is None]
        if missing:
            raise BearingError(
                f"{source}: bearing.{missing[0]} missing; give {', '.join(GEOMETRY_KEYS[:3])} (and contact_angle_deg) "
                "or a designation from the table (--bearing 'SKF 6205')"
            )
        unknown = sorted(set(bearing) - set(GEOMETRY_KEYS) - {"designation"})
        if unknown:
            raise BearingError(f"{source}: bearing.{unknown[0]} is not a bearing key; use {', '.join(GEOMETRY_KEYS)}, "
                               "designation")
        try:
            return cls(int(bearing["n_rolling_elements"]), float(bearing["rolling_element_diameter_m"]),
                       float(bearing["pitch_diameter_m"]), float(bearing.get("contact_angle_deg") or 0.0), designation)
        except (TypeError, ValueError) as e:
            if isinstance(e, BearingError):
                raise BearingError(f"{source}: {e}") from None
            raise BearingError(f"{source}: bearing geometry must be numbers ({e})") from None


def _key(name: str) -> str:
    return re.sub(r"[\s\-_]", "", str(name)).upper()


def designations() -> tuple[RollingBearing, ...]:
    """Every bearing of the designation table (package data ``bearing/designations.csv``)."""
    return _designations()


def designation_sources() -> dict[str, str]:
    """The source of each designation's geometry."""
    text = resources.files(__package__).joinpath(DESIGNATIONS_CSV).read_text(encoding="utf-8")
    return {row["designation"]: row["source"] for row in csv.DictReader(text.splitlines())}


def _designations() -> tuple[RollingBearing, ...]:
    text = resources.files(__package__).joinpath(DESIGNATIONS_CSV).read_text(encoding="utf-8")
    return tuple(
        RollingBearing(int(r["n_rolling_elements"]), float(r["rolling_element_diameter_m"]), float(r["pitch_diameter_m"]),
                       float(r["contact_angle_deg"]), r["designation"])
        for r in csv.DictReader(text.splitlines())
    )


@dataclass(frozen=True)
class Kinematics:
    """Kinematic frequencies of a bearing with a stationary outer ring [Hz].

    Attributes
    ----------
    shaft_Hz : float
        Shaft (inner ring) rotation frequency f_r.
    ftf_Hz : float
        Fundamental train (cage) frequency, (1 - s) f_r / 2 (1 - g).
    bpfo_Hz : float
        Ball (roller) pass frequency on the outer race, Z FTF.
    bpfi_Hz : float
        Ball (roller) pass frequency on the inner race, Z (f_r - FTF).
    bsf_Hz : float
        Ball (roller) spin frequency relative to the cage, (1 - s) D / (2 d) f_r (1 - g^2); a defect on a
        rolling element strikes the races at 2 BSF.
    """

    shaft_Hz: float
    ftf_Hz: float
    bpfo_Hz: float
    bpfi_Hz: float
    bsf_Hz: float

    @classmethod
    def from_geometry(cls, bearing: RollingBearing, shaft_Hz: float, cage_slip: float = 0.0) -> "Kinematics":
        """Kinematics of ``bearing`` at shaft rate ``shaft_Hz`` [Hz] with the cage slipping by ``cage_slip`` [-].

        Slip: the cage and the rolling elements' spin lag the rolling kinematics by the fraction s (they
        skid on the raceways), so FTF, BPFO and BSF scale by (1 - s) and BPFI = Z (f_r - FTF) grows; the
        shaft rate does not slip. Real cages slip 1-2 % (s = 0.01-0.02).
        """
        if not 0.0 <= cage_slip < 1.0:
            raise BearingError(f"cage_slip = {cage_slip}; give a fraction in [0, 1)")
        g, z = bearing.diameter_ratio, bearing.n_rolling_elements
        fr, lag = float(shaft_Hz), 1.0 - float(cage_slip)
        ftf = lag * 0.5 * fr * (1 - g)
        bsf = lag * 0.5 * bearing.pitch_diameter_m / bearing.rolling_element_diameter_m * fr * (1 - g**2)
        return cls(shaft_Hz=fr, ftf_Hz=ftf, bpfo_Hz=z * ftf, bpfi_Hz=z * (fr - ftf), bsf_Hz=bsf)

    @classmethod
    def from_dict(cls, d: Mapping, source: str = "kinematics") -> "Kinematics":
        """From the dict the workflow writes to ``kinematics.json`` (:data:`KINEMATIC_KEYS`; others ignored)."""
        missing = [k for k in KINEMATIC_KEYS if k not in d]
        if missing:
            raise BearingError(f"{source}: key '{missing[0]}' missing; kinematics need {', '.join(KINEMATIC_KEYS)} [Hz]")
        return cls(**{k: float(d[k]) for k in KINEMATIC_KEYS})

    def to_dict(self) -> dict[str, float]:
        """The ``kinematics.json`` dict [Hz]."""
        return {k: float(getattr(self, k)) for k in KINEMATIC_KEYS}

    @property
    def n_rolling_elements(self) -> float:
        """Z = BPFO / FTF [-]."""
        return self.bpfo_Hz / self.ftf_Hz

    def at_shaft_rate(self, shaft_Hz: float) -> "Kinematics":
        """The same bearing at another shaft rate (every frequency scales with it) [Hz]."""
        scale = float(shaft_Hz) / self.shaft_Hz
        return Kinematics(*(scale * getattr(self, k) for k in KINEMATIC_KEYS))
