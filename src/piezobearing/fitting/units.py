"""The one registry of unit suffixes a diagnosis parameter name may end with.

Every parameter of a forward model or an effect carries its SI unit in its
name (``resistance_ohm``, ``delay_s``, ``beta_per_N``). :data:`UNITS` lists
the allowed suffixes with the unit a report shows them in;
:class:`~piezobearing.fitting.params.Param` refuses a name without one, and
the report formats values from it. A subject that needs a new unit (say
``_rad`` for a phase) adds one line here.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Unit:
    """An allowed suffix, its SI unit and how a report shows it.

    Attributes
    ----------
    suffix : str
        End of a parameter name, with its underscore (``_s``).
    si : str
        The SI unit the value is in (``s``).
    display_scale : float
        Values are shown divided by this [SI unit per display unit].
    display : str
        The unit shown (``ms``).
    """

    suffix: str
    si: str
    display_scale: float
    display: str


#: Allowed suffixes, in the order they are matched (the longest ambiguous ones first:
#: ``_per_N`` before ``_N``, ``_per_s`` before ``_s``). The report shows values in ``display`` units.
UNITS: tuple[Unit, ...] = (
    Unit("_ohm", "ohm", 1e6, "MOhm"),
    Unit("_F", "F", 1e-12, "pF"),
    Unit("_per_s", "1/s", 1.0, "1/s"),
    Unit("_s", "s", 1e-3, "ms"),
    Unit("_V", "V", 1e-3, "mV"),
    Unit("_Hz", "Hz", 1.0, "Hz"),
    Unit("_per_N", "1/N", 1.0, "1/N"),
    Unit("_ratio", "1", 1.0, "x"),
    Unit("_ppm", "1e-6", 1.0, "ppm"),
    # the running bearing (diagnosis/bearing): damping, loads, masses, widths and clearances, angles, a roller's
    # index
    Unit("_N_s_per_m", "N s/m", 1.0, "N s/m"),
    Unit("_N", "N", 1.0, "N"),
    Unit("_kg", "kg", 1.0, "kg"),
    Unit("_m", "m", 1e-3, "mm"),
    Unit("_rad", "rad", 1.0, "rad"),
    Unit("_index", "1", 1.0, ""),
)

#: The suffixes alone (for ``str.endswith``).
SUFFIXES: tuple[str, ...] = tuple(u.suffix for u in UNITS)


def unit_of(name: str) -> Unit | None:
    """The registered unit a parameter name ends with, or None."""
    for u in UNITS:
        if name.endswith(u.suffix):
            return u
    return None


def format_value(name: str, value: float | None) -> str:
    """A parameter value in its readable unit, from its name's suffix (``-`` for None)."""
    if value is None:
        return "-"
    u = unit_of(name)
    if u is None:
        return f"{value:.4g}"
    return f"{value / u.display_scale:.4g} {u.display}"
