"""Rule sensor_comparison_housing: the housing's reduced model (:mod:`piezobearing.housing.reduced`) built once per
mesh and stored with the config values it was built from, and read back by every comparison on that mesh."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..housing import fem as housing_fem
from ..housing.reduced import Housing, build_housing
from ..workflow.registry import declared

#: The rule that builds a housing model (its config keys: piezobearing.workflow.registry.READS).
HOUSING_RULE = "sensor_comparison_housing"



def housing_reads(config: dict) -> dict:
    """The config values a housing model depends on (the rule ``sensor_comparison_housing``'s), JSON-ready."""
    return declared(config, HOUSING_RULE)


def save_housing(housing: Housing, faulty: bool, reads: dict, path: str | Path) -> None:
    """Write a housing model to ``path`` (.npz), with the config values it was built from."""
    o, b, c = housing.ops, housing.base, housing.columns
    rows = b.probe_rows.tocsr()
    np.savez(
        path,
        reads_json=np.array(json.dumps(reads, sort_keys=True)),
        faulty=np.array(bool(faulty)),
        n_dofs=np.array(housing.n_dofs),
        columns_psi_rad=c.psi_rad, columns_radius_m=np.array(c.radius_m),
        columns_patch_width_m=np.array(c.patch_width_m),
        **{f"ops_{k}": getattr(o, k) for k in housing_fem.ReducedOperators.__dataclass_fields__},
        base_rigid=b.rigid, base_participation=b.participation, base_rigid_mass_kg=b.rigid_mass_kg,
        base_static_sensor=b.static_sensor, base_probe_modal=b.probe_modal, base_probe_base=b.probe_base,
        probe_rows_data=rows.data, probe_rows_indices=rows.indices, probe_rows_indptr=rows.indptr,
        probe_rows_shape=np.array(rows.shape),
        probe_position=np.array([p.position for p in b.probes]),
        probe_node=np.array([p.node for p in b.probes]),
        probe_coordinates_m=np.array([p.coordinates_m for p in b.probes]),
        probe_normal=np.array([p.normal for p in b.probes]),
    )


def load_housing(path: str | Path, faulty: bool, reads: dict) -> Housing:
    """The housing model in ``path`` (:func:`save_housing`); stops if it was built for another case or config."""
    with np.load(path, allow_pickle=False) as d:
        if bool(d["faulty"]) != bool(faulty) or json.loads(str(d["reads_json"])) != json.loads(json.dumps(reads)):
            raise ValueError(
                f"{path}: this housing model was built for another {'faulty' if faulty else 'healthy'} mesh or "
                f"config; rebuild it (snakemake rule {HOUSING_RULE})"
            )
        ops = housing_fem.ReducedOperators(**{k: d[f"ops_{k}"] for k in housing_fem.ReducedOperators.__dataclass_fields__})
        probes = tuple(
            housing_fem.Probe(str(pos), int(node), tuple(float(v) for v in xyz), tuple(float(v) for v in n))
            for pos, node, xyz, n in zip(d["probe_position"], d["probe_node"], d["probe_coordinates_m"],
                                         d["probe_normal"], strict=True)
        )
        rows = sp.csr_matrix((d["probe_rows_data"], d["probe_rows_indices"], d["probe_rows_indptr"]),
                             shape=tuple(d["probe_rows_shape"]))
        base = housing_fem.BaseMotionOperators(
            rigid=d["base_rigid"], participation=d["base_participation"], rigid_mass_kg=d["base_rigid_mass_kg"],
            static_sensor=d["base_static_sensor"], probes=probes, probe_rows=rows, probe_modal=d["base_probe_modal"],
            probe_base=d["base_probe_base"],
        )
        columns = housing_fem.RacewayColumns(d["columns_psi_rad"], float(d["columns_radius_m"]),
                                     float(d["columns_patch_width_m"]))
        return Housing(columns, ops, base, int(d["n_dofs"]))


def write_housing(config: dict, faulty: bool, out_npz: str | Path) -> None:
    """Rule sensor_comparison_housing: the housing model of one mesh (healthy or faulty), built and written."""
    save_housing(build_housing(config, faulty), faulty, housing_reads(config), out_npz)
