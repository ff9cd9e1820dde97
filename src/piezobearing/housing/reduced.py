"""The housing's reduced model as the sensor comparison's runs use it, computed once per mesh and stored.

The mesh, the model, its modes to the cutoff (``sensor_comparison.mode_cutoff_ratio`` times the
accelerometer DAQ's Nyquist frequency) and the modal operators of the roller loads, the base motion and the
accelerometer's mounting places depend on the housing's config values alone (its geometry and defect, the mesh
level, the sensor's spring, the damping, the cutoff: ``piezobearing.workflow.registry.READS["sensor_comparison_housing"]``),
not on the speed, the surroundings or the seeds. The workflow computes them once per healthy or faulty mesh
(rule ``sensor_comparison_housing``, :func:`piezobearing.stages.housing_model.write_housing`) and every
comparison on that mesh, the main rule's and the study's cases, reads them
(:func:`piezobearing.stages.housing_model.load_housing`): the same arrays, to the bit, as building them in the
case.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import fem as housing_fem
from . import transient
from .mesh import build_housing_mesh


@dataclass(frozen=True)
class Housing:
    """The housing's reduced model as the rig's runs use it: the raceway's columns, the modal operators of the
    roller loads, of the base motion and of the accelerometer's mounting places.

    It depends on the housing's mesh (geometry, defect, level), the sensor's spring, the damping and the
    modes' cutoff, not on the speed, the surroundings or the seeds: :func:`build_housing` computes it once per
    mesh (the workflow's rule ``sensor_comparison_housing``, :func:`piezobearing.stages.housing_model.save_housing`), every case on that mesh
    reads it (:func:`piezobearing.stages.housing_model.load_housing`).

    Attributes
    ----------
    columns : RacewayColumns
        Where the roller loads enter.
    ops : ReducedOperators
        Modes, damping, and the sensor's and roller loads' modal operators.
    base : BaseMotionOperators
        The base motion's operators and one probe per mounting place (:data:`housing_fem.MOUNTING_POSITIONS`) or, after
        :meth:`at`, the accelerometer's one.
    n_dofs : int
        Free DOFs of the half model [-].
    """

    columns: housing_fem.RacewayColumns
    ops: housing_fem.ReducedOperators
    base: housing_fem.BaseMotionOperators
    n_dofs: int

    def at(self, position: str) -> Housing:
        """The housing with the probe at ``position`` alone (``accelerometer.position``)."""
        names = [p.position for p in self.base.probes]
        if position not in names:
            raise ValueError(f"config accelerometer.position must be one of {', '.join(names)}, got {position!r}")
        i = names.index(position)
        b = self.base
        one = replace(b, probes=b.probes[i:i + 1], probe_rows=b.probe_rows[i:i + 1],
                      probe_modal=b.probe_modal[i:i + 1], probe_base=b.probe_base[i:i + 1])
        return replace(self, base=one)

    def record(self) -> dict:
        """What the results say about it: DOFs, modes kept, the effective mass they carry, the (first) probe."""
        frac = self.base.effective_mass_fraction()
        p = self.base.probes[0]
        f = self.ops.omega / (2 * np.pi)
        return {
            "n_dofs": self.n_dofs,
            "n_modes": int(f.size),
            "highest_mode_Hz": float(f[-1]),
            "first_mode_Hz": float(f[0]),
            "effective_mass_fraction_y": float(frac[0, -1]),
            "effective_mass_fraction_z": float(frac[1, -1]),
            "dragged_mass_kg": float(self.base.rigid_mass_kg[0]),
            "sensor_force_per_base_acceleration_z_N_per_m_per_s2": float(self.base.static_sensor[1]),
            "accelerometer_node_m": list(p.coordinates_m),
            "accelerometer_axis": list(p.normal),
        }


#: Modes asked for first: the housing of the paper's geometry has 15-20 below 32 kHz (2.5 x 12.8 kHz).
FIRST_MODE_COUNT = 20
def modes_to(model: housing_fem.HousingModel, top_Hz: float, start: int, seed: int) -> housing_fem.Modes:
    """The housing's modes up to past ``top_Hz``: max(``start``, 20) modes, 1.5 times as many until the highest
    passes it (each try one shift-invert Lanczos solve on the factors of K)."""
    n = max(int(start), FIRST_MODE_COUNT)
    while True:
        modes = housing_fem.compute_modes(model, min(n, model.n_dofs - 2), seed=seed)
        if modes.frequencies_Hz[-1] >= top_Hz or n >= model.n_dofs - 2:
            return modes
        n = int(1.5 * n) + 1


def mode_top_Hz(config: dict) -> float:
    """The modes' cutoff: ``sensor_comparison.mode_cutoff_ratio`` times the accelerometer DAQ's Nyquist frequency
    [Hz]."""
    return config["sensor_comparison"]["mode_cutoff_ratio"] * (0.5 * config["accelerometer"]["daq"]["sample_rate_Hz"])


def build_housing(config: dict, faulty: bool) -> Housing:
    """The housing mesh of the case (``housing.mesh_level``), its model, its modes to :func:`mode_top_Hz`, the
    Rayleigh damping, and a probe at every mounting place."""
    h = config["housing"]
    mesh = build_housing_mesh(transient.housing_geometry(config), faulty, h["mesh_level"])
    model = transient.make_model(mesh, config)
    modes = modes_to(model, mode_top_Hz(config), h["n_modes"], config["seed"])
    alpha, beta = housing_fem.rayleigh_coefficients(h["damping_ratio"], h["damping_band_Hz"])
    ops = housing_fem.reduced_operators(model, modes, alpha, beta)
    probes = tuple(housing_fem.mounting_probe(mesh, p) for p in housing_fem.MOUNTING_POSITIONS)
    base = housing_fem.base_motion_operators(model, modes, probes)
    return Housing(housing_fem.RacewayColumns.of(model), ops, base, model.n_dofs)
