"""The sensor stack in finite elements as result tables (Sec. III-C; Fig. 7, 8b): the parameters the sensor FEM
takes from the config, the mesh convergence table, the modal survey and the harmonic response with the band edges.

Pure functions of meshes and parameters; the stages in :mod:`piezobearing.stages.sensor_fem` read and write the
files (mesh VTK: :mod:`piezobearing.io`).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from ..config import paper
from . import fem
from .calibration import SensorCircuit, frequency_response
from .errors import SensorFemError
from .materials import (
    adhesive_from_config,
    alumina_from_config,
    paper_pzt,
    pzt_from_config,
    stress_charge_form,
    transverse_isotropy_report,
)
from .mesh import MeshDensity, StackGeometry, StackMesh, stack_mesh

log = logging.getLogger(__name__)

#: The paper's numbers the sensor FEM is held against (Sec. III-C), from the paper table.
PAPER_FIRST_RESONANCE_HZ = paper.value("first_resonance_Hz")
PAPER_BAND_LOW_HZ = paper.value("linear_from_Hz")
PAPER_BAND_HIGH_HZ = paper.value("band_high_Hz")
PAPER_REFERENCE_SENSITIVITY_V_PER_N = paper.value("reference_sensitivity_V_per_N")


# --------------------------------------------------------------------------- parameters


def mesh_inputs(config: dict) -> tuple[StackGeometry, MeshDensity, tuple]:
    """The stack's geometry, the mesh density and the refinement multipliers from the config (the sensor mesh
    reads these only: the PZT's material constants and the cable do not change the mesh)."""
    s, f = config["sensor"], config["sensor_fem"]
    mult = tuple(float(m) for m in f["refinement_multipliers"])
    if list(mult) != sorted(set(mult)):
        raise SensorFemError("config key sensor_fem.refinement_multipliers: must increase strictly")
    if not 1 <= f["mesh_level"] <= len(mult):
        raise SensorFemError(
            f"config key sensor_fem.mesh_level = {f['mesh_level']}: must be 1..{len(mult)} "
            "(an index into sensor_fem.refinement_multipliers)"
        )
    geo = StackGeometry(
        bottom_disk_diameter_m=f["bottom_disk_diameter_m"],
        bottom_disk_height_m=f["bottom_disk_height_m"],
        pzt_diameter_m=s["pzt_diameter_m"],
        pzt_height_m=s["pzt_height_m"],
        top_disk_diameter_m=f["top_disk_diameter_m"],
        top_disk_height_m=f["top_disk_height_m"],
        adhesive_height_m=f["adhesive_height_m"],
    )
    dens = MeshDensity(
        n_core=f["mesh_n_core"],
        n_rings=tuple(f["mesh_n_rings"]),
        n_layers=tuple(f["mesh_n_layers"]),
        grading=f["mesh_grading_ratio"],
    )
    return geo, dens, mult


def quality_factor(sensor_fem: dict, pzt) -> float:
    """The stack's mechanical Q [-]: ``sensor_fem.mechanical_quality_factor``, or where it is null the ceramic's
    own Qm (:attr:`piezobearing.sensor.materials.PiezoMaterial.mechanical_quality_factor`)."""
    q = sensor_fem["mechanical_quality_factor"]
    return float(pzt.mechanical_quality_factor if q is None else q)


@dataclass(frozen=True)
class SensorFemParams:
    """Everything the sensor FEM stages take from the validated config."""

    geometry: StackGeometry
    density: MeshDensity
    multipliers: tuple
    mesh_level: int
    order: int
    materials: fem.StackMaterials
    c66_rule: str
    modal_max_frequency_Hz: float
    damping_ratio: float
    n_ritz_modes: int
    sweep_min_Hz: float
    sweep_max_Hz: float
    sweep_points: int
    reference_frequency_Hz: float
    band_ratio_dB: float
    band_ratio_percent: float
    cable_capacitance_F: float

    @property
    def multiplier(self) -> float:
        return self.multipliers[self.mesh_level - 1]

    @classmethod
    def from_config(cls, config: dict) -> "SensorFemParams":
        s, f = config["sensor"], config["sensor_fem"]
        geo, dens, mult = mesh_inputs(config)
        if f["sweep_min_frequency_Hz"] >= f["reference_frequency_Hz"] or (
            f["reference_frequency_Hz"] >= f["sweep_max_frequency_Hz"]
        ):
            raise SensorFemError(
                "config keys sensor_fem.sweep_min_frequency_Hz < reference_frequency_Hz < sweep_max_frequency_Hz "
                "must hold"
            )
        pzt = pzt_from_config(s)
        alu = alumina_from_config(f)
        mats = fem.StackMaterials(stress_charge_form(pzt), pzt.density_kg_per_m3, alu, adhesive_from_config(f))
        q = quality_factor(f, pzt)
        return cls(
            geometry=geo,
            density=dens,
            multipliers=mult,
            mesh_level=int(f["mesh_level"]),
            order=int(f["element_order"]),
            materials=mats,
            c66_rule=s["c66_rule"],
            modal_max_frequency_Hz=f["modal_max_frequency_Hz"],
            damping_ratio=1.0 / (2.0 * q),
            n_ritz_modes=int(f["n_ritz_modes"]),
            sweep_min_Hz=f["sweep_min_frequency_Hz"],
            sweep_max_Hz=f["sweep_max_frequency_Hz"],
            sweep_points=int(f["sweep_points"]),
            reference_frequency_Hz=f["reference_frequency_Hz"],
            band_ratio_dB=f["band_ratio_dB"],
            band_ratio_percent=f["band_ratio_percent"],
            cable_capacitance_F=s["cable_length_m"] * s["cable_capacitance_F_per_m"] + s["daq_capacitance_F"],
        )


def _assemble(mesh: StackMesh, p: SensorFemParams) -> fem.Assembled:
    return fem.assemble(mesh, p.materials, order=p.order, load_face="bottom")


def convergence_row(rs: fem.ReducedSystem, level: int, mesh: StackMesh) -> dict:
    """The convergence table's row of one mesh: the SS family's first axial frequency, short and open."""
    short = fem.modes(rs, 3, "short")
    labels = [fem.label_mode(rs, short.shapes[:, i])[0] for i in range(3)]
    i_ax = labels.index("axial")
    f_open = fem.modes(rs, 3, "open").frequency_Hz[i_ax]
    return {
        "level": level,
        "multiplier": mesh.level,
        "n_cells": mesh.n_cells,
        "n_dof": int(rs.asm.n_u + rs.asm.p_coors.shape[0]),
        "first_axial_short_Hz": float(short.frequency_Hz[i_ax]),
        "first_axial_open_Hz": float(f_open),
    }


def convergence_table(meshes: list, p: SensorFemParams, known: dict | None = None) -> pd.DataFrame:
    """First axial frequency (short and open circuit) on every mesh, with the change from the previous one.

    ``known``: rows already computed, by level (1-based), as :func:`convergence_row` returns them (the rule
    sensor_modal computes the row of its own mesh on the system it factorised anyway).
    """
    rows = []
    for k, mesh in enumerate(meshes, start=1):  # a level in ``known`` may have None for its mesh
        if known and k in known:
            rows.append(dict(known[k]))
            continue
        t0 = time.perf_counter()
        rs = fem.reduce(_assemble(mesh, p), fem.stack_conditions(p.geometry.z_interfaces_m, "SS"))
        rows.append(convergence_row(rs, k, mesh))
        # Wall-clock time goes to the log only: result files must be identical from run to run.
        log.info("convergence level %d (%.2f s): %s", k, time.perf_counter() - t0, rows[-1])
    df = pd.DataFrame(rows)
    df["change_short_percent"] = 100 * df["first_axial_short_Hz"].pct_change()
    df["change_open_percent"] = 100 * df["first_axial_open_Hz"].pct_change()
    return df


def first_axial_mode_fields(survey: fem.ModalSurvey, mesh: StackMesh) -> dict:
    """Vertices, cells, groups and the first axial mode's displacement and potential at the vertices (arrays)."""
    rs = survey.ss_system
    u = fem.first_axial_shape(survey)
    nv = len(mesh.coors)
    disp = rs.full_u(u)[:nv]
    pot_free = rs.potential_of(u)
    # Potential on every potential node (interior from the solve, electrodes zero: short circuit).
    asm = rs.asm
    interior = np.setdiff1d(
        np.arange(asm.p_coors.shape[0]),
        np.flatnonzero(
            (np.abs(asm.p_coors[:, 2] - rs.bc.hot_z_m) < 1e-12)
            | (np.abs(asm.p_coors[:, 2] - rs.bc.ground_z_m) < 1e-12)
        ),
    )
    phi = np.zeros(asm.p_coors.shape[0])
    if len(interior) == len(pot_free):
        phi[interior] = pot_free
    key = {tuple(np.round(c, 12)): i for i, c in enumerate(asm.p_coors)}
    phi_v = np.array(
        [phi[key[tuple(np.round(c, 12))]] if tuple(np.round(c, 12)) in key else np.nan for c in mesh.coors]
    )
    return {
        "coors_m": mesh.coors,
        "cells": mesh.cells,
        "groups": mesh.groups,
        "displacement": disp,
        "potential": phi_v,
        "frequency_Hz": survey.first_axial.frequency_short_Hz,
    }


def placement_check(p: SensorFemParams) -> dict:
    """First axial frequency with the two alumina disks swapped, on the coarsest mesh."""
    g = p.geometry
    swapped = replace(
        g, bottom_disk_diameter_m=g.top_disk_diameter_m, top_disk_diameter_m=g.bottom_disk_diameter_m
    )
    mesh = stack_mesh(swapped, p.density, p.multipliers[0])
    asm = _assemble(mesh, p)
    rs = fem.reduce(asm, fem.stack_conditions(swapped.z_interfaces_m, "SS"))
    short = fem.modes(rs, 3, "short")
    i_ax = [fem.label_mode(rs, short.shapes[:, i])[0] for i in range(3)].index("axial")
    return {
        "bottom_disk_diameter_m": swapped.bottom_disk_diameter_m,
        "top_disk_diameter_m": swapped.top_disk_diameter_m,
        "mesh_multiplier": p.multipliers[0],
        "first_axial_short_Hz": float(short.frequency_Hz[i_ax]),
        "first_axial_open_Hz": float(fem.modes(rs, 3, "open").frequency_Hz[i_ax]),
    }


def modal_results(mesh: StackMesh, p: SensorFemParams) -> tuple[dict, fem.ModalSurvey]:
    """The modal analysis as a JSON-ready dict, and the survey (for the mode shape)."""
    t0 = time.perf_counter()
    asm = _assemble(mesh, p)
    survey = fem.modal_survey(asm, p.geometry.z_interfaces_m, p.modal_max_frequency_Hz)
    ax = survey.first_axial
    rs = survey.ss_system
    modes = [
        {
            "index": k,
            "label": r.label,
            "family": r.family,
            "multiplicity": r.multiplicity,
            "frequency_short_Hz": r.frequency_short_Hz,
            "frequency_open_Hz": r.frequency_open_Hz,
            "coupling_factor": r.coupling_factor,
            "kinetic_energy_fraction": r.kinetic,
        }
        for k, r in enumerate(survey.records, start=1)
    ]
    log.info("modal analysis: %.2f s", time.perf_counter() - t0)
    out = {
        "first_resonance_short_Hz": ax.frequency_short_Hz,
        "first_resonance_open_Hz": ax.frequency_open_Hz,
        "first_resonance_label": "axial",
        "first_resonance_coupling_factor": ax.coupling_factor,
        "paper_first_resonance_Hz": PAPER_FIRST_RESONANCE_HZ,
        "lowest_mode_Hz": survey.records[0].frequency_short_Hz,
        "lowest_mode_label": survey.records[0].label,
        "modal_max_frequency_Hz": p.modal_max_frequency_Hz,
        "modes": modes,
        "blocked_capacitance_F": rs.c0 / fem.SECTOR_FRACTION,
        "static_capacitance_F": rs.static_capacitance_F / fem.SECTOR_FRACTION,
        "effective_d33_C_per_N": float(rs.b @ rs.ks_inv_f) / fem.SECTOR_FRACTION,
        "static_open_circuit_V_per_N": rs.static_open_voltage_V(),
        "mesh": {
            "level": p.mesh_level,
            "multiplier": p.multiplier,
            "n_cells": mesh.n_cells,
            "n_dof_displacement": int(asm.n_u),
            "n_dof_potential": int(asm.p_coors.shape[0]),
            "element_order": p.order,
            "sector": "quarter; families SS, SA (= AS mirrored, multiplicity 2), AA",
        },
        "boundary_conditions": {
            "mechanical": "top face of the top disk clamped (u = 0); everything else free",
            "electrical_short": "both PZT faces at 0 V",
            "electrical_open": "PZT top face 0 V, bottom face one floating potential with zero net charge",
        },
        "material_symmetry": transverse_isotropy_report(paper_pzt(c66_rule="paper").c_E_Pa),
        "pzt_density_kg_per_m3": p.materials.pzt_density_kg_per_m3,
    }
    return out, survey


def sweep_frequencies(p: SensorFemParams, f_res_Hz: float) -> np.ndarray:
    """Log-spaced sweep plus a dense linear run around the first resonance (if inside the sweep)."""
    f = np.geomspace(p.sweep_min_Hz, p.sweep_max_Hz, p.sweep_points)
    lo, hi = 0.9 * f_res_Hz, min(1.1 * f_res_Hz, p.sweep_max_Hz)
    if lo < p.sweep_max_Hz:
        f = np.concatenate([f, np.linspace(lo, hi, p.sweep_points // 2)])
    return np.unique(f)


def ritz_arrays(rs: fem.ReducedSystem, p: SensorFemParams) -> dict:
    """The harmonic analysis's Ritz model of the SS family, as arrays (what :func:`harmonic_from_ritz` needs).

    ``p.n_ritz_modes`` short-circuit modes plus the static shapes (:func:`fem.reduced_model`, undamped: the
    damping ratio is applied where the model is used), the first axial frequency short and open, and the
    size of the displacement field. Computed by the rule sensor_modal on its SS system, whose saddle
    factorisation it already holds, so sensor_harmonic assembles and factorises nothing.
    """
    short = fem.modes(rs, p.n_ritz_modes, "short")
    model = fem.reduced_model(rs, short)
    labels = [fem.label_mode(rs, short.shapes[:, i])[0] for i in range(len(short.frequency_Hz))]
    i_ax = labels.index("axial")
    f_open = fem.modes(rs, i_ax + 2, "open").frequency_Hz[i_ax]
    return {
        "omega2": model.omega2,
        "b_k": model.b_k,
        "f_k": model.f_k,
        "c0_F": np.float64(model.c0_F),
        "first_axial_short_Hz": np.float64(short.frequency_Hz[i_ax]),
        "first_axial_open_Hz": np.float64(f_open),
        "n_dof_displacement": np.int64(rs.asm.n_u),
    }


def harmonic_results(mesh: StackMesh, p: SensorFemParams, rc_paper: SensorCircuit, band_low_Hz: float):
    """Harmonic response with the circuit, the band edges, the RC comparison (assembling the mesh's system).

    ``rc_paper`` is the calibration stage's RC model (fitted R, cable, the
    paper's d33 and Cp); its R and cable capacitance are the FEM's circuit.
    Returns (the sweep DataFrame, the band dict).
    """
    t0 = time.perf_counter()
    rs = fem.reduce(_assemble(mesh, p), fem.stack_conditions(p.geometry.z_interfaces_m, "SS"))
    out = harmonic_from_ritz(ritz_arrays(rs, p), p, rc_paper, band_low_Hz)
    log.info("harmonic analysis: %.2f s", time.perf_counter() - t0)
    return out


def harmonic_from_ritz(ritz: dict, p: SensorFemParams, rc_paper: SensorCircuit, band_low_Hz: float):
    """:func:`harmonic_results` from the Ritz model of :func:`ritz_arrays` (no FEM solve)."""
    resistance_ohm = rc_paper.resistance_ohm
    model = fem.ReducedModel(
        omega2=ritz["omega2"], b_k=ritz["b_k"], f_k=ritz["f_k"], c0_F=float(ritz["c0_F"]),
        damping_ratio=p.damping_ratio,
    )
    circuit = fem.MeasuringCircuit(resistance_ohm, p.cable_capacitance_F)
    f_short, f_open = float(ritz["first_axial_short_Hz"]), float(ritz["first_axial_open_Hz"])
    f_peak = fem.loaded_resonance_Hz(model, circuit, 0.97 * f_short, 1.03 * f_open)
    ref = abs(model.voltage_per_force(p.reference_frequency_Hz, circuit)[0])
    r_db = 10 ** (p.band_ratio_dB / 20)
    r_pc = 1 + p.band_ratio_percent / 100
    edge_db = fem.band_edge_Hz(model, circuit, r_db, ref, p.reference_frequency_Hz, f_peak)
    edge_pc = fem.band_edge_Hz(model, circuit, r_pc, ref, p.reference_frequency_Hz, f_peak)
    s_low = abs(model.voltage_per_force(band_low_Hz, circuit)[0])
    edge_db_low = fem.band_edge_Hz(model, circuit, r_db, s_low, band_low_Hz, f_peak)
    edge_pc_low = fem.band_edge_Hz(model, circuit, r_pc, s_low, band_low_Hz, f_peak)

    freqs = sweep_frequencies(p, f_peak)
    h = model.voltage_per_force(freqs, circuit)
    d_eff, c_fe = model.charge_per_force_C_per_N, model.static_capacitance_F
    h_rc = frequency_response(freqs, rc_paper)
    df = pd.DataFrame(
        {
            "frequency_Hz": freqs,
            "voltage_per_force_V_per_N": np.abs(h),
            "phase_deg": np.degrees(np.angle(h)),
            "rc_model_V_per_N": np.abs(h_rc),
            "open_circuit_V_per_N": np.abs(model.voltage_per_force(freqs, None)),
        }
    )
    tau_fe = resistance_ohm * (c_fe + p.cable_capacitance_F)
    band = {
        "band_low_Hz": float(band_low_Hz),
        "band_high_Hz": edge_db,
        "band_high_27_percent_Hz": edge_pc,
        "band_ratio_dB": p.band_ratio_dB,
        "band_ratio_percent": p.band_ratio_percent,
        "reference": "mid-band: |V/F| at reference_frequency_Hz (the flat plateau between the RC corner and the "
        "resonance)",
        "reference_frequency_Hz": p.reference_frequency_Hz,
        "reference_sensitivity_V_per_N": ref,
        "mid_band_sensitivity_V_per_N": ref,
        "sensitivity_at_band_low_V_per_N": s_low,
        "band_high_rel_band_low_Hz": edge_db_low,
        "band_high_27_percent_rel_band_low_Hz": edge_pc_low,
        "loaded_resonance_Hz": f_peak,
        "first_axial_short_Hz": f_short,
        "first_axial_open_Hz": f_open,
        "effective_d33_C_per_N": d_eff,
        "fem_capacitance_F": c_fe,
        "cable_capacitance_F": p.cable_capacitance_F,
        "resistance_ohm": resistance_ohm,
        "fem_corner_Hz": 1.0 / (2 * np.pi * tau_fe),
        "rc_model_corner_Hz": 1.0 / (2 * np.pi * rc_paper.tau_s),
        "rc_model_mid_band_V_per_N": rc_paper.open_circuit_gain_V_per_N,
        "damping_ratio": p.damping_ratio,
        "n_ritz_modes": p.n_ritz_modes,
        "paper": {
            "band_low_Hz": PAPER_BAND_LOW_HZ,
            "band_high_Hz": PAPER_BAND_HIGH_HZ,
            "reference_sensitivity_V_per_N": PAPER_REFERENCE_SENSITIVITY_V_PER_N,
        },
        "mesh": {"level": p.mesh_level, "multiplier": p.multiplier,
                 "n_dof_displacement": int(ritz["n_dof_displacement"])},
    }
    return df, band
