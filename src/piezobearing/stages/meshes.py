"""Mesh files: the housing mesh (NPZ with its geometry, VTK to view) and the sensor's quarter mesh (binary
legacy VTK with its cell groups)."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import meshio
import numpy as np

from ..housing.mesh import HousingGeometry, HousingMesh
from ..io.results import ResultFileError, write_npz
from ..sensor.mesh import StackMesh


def write_housing_mesh(m, path: str | Path) -> None:
    """A :class:`~piezobearing.housing.mesh.HousingMesh` and its node sets as NPZ (with its geometry)."""
    write_npz(
        path,
        coors=m.coors,
        conn=m.conn,
        group=m.group,
        raceway_psi=m.raceway_psi,
        raceway_x=m.raceway_x,
        raceway_nodes=m.raceway_nodes,
        ring_outer_psi=m.ring_outer_psi,
        ring_outer_nodes=m.ring_outer_nodes,
        base_nodes=m.base_nodes,
        faulty=m.faulty,
        level=m.level,
        geometry=json.dumps(asdict(m.geometry)),
    )


def read_housing_mesh(path: str | Path):
    """A housing mesh written by :func:`write_housing_mesh`."""
    d = np.load(path)
    geo = HousingGeometry(**json.loads(str(d["geometry"])))
    keys = (
        "coors conn group raceway_psi raceway_x raceway_nodes ring_outer_psi ring_outer_nodes base_nodes"
    ).split()
    return HousingMesh(
        **{k: d[k] for k in keys}, geometry=geo, faulty=bool(d["faulty"]), level=float(d["level"])
    )


def write_housing_vtk(m, path: str | Path) -> None:
    """A housing mesh as VTK (hexahedra with the cell array ``group``), to view."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, meshio.Mesh(m.coors, [("hexahedron", m.conn)], cell_data={"group": [m.group]}))


def write_stack_mesh(mesh, path: str | Path) -> None:
    """The sensor's quarter mesh as binary legacy VTK with the cell groups (1 bottom disk, 2 PZT, 3 top disk)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    m = meshio.Mesh(
        mesh.coors, [("hexahedron", mesh.cells)], cell_data={"group": [mesh.groups.astype(np.int32)]}
    )
    meshio.write(str(path), m, file_format="vtk", binary=True)


def read_stack_mesh(path: str | Path, geometry, level: float, error: type[Exception] = ResultFileError):
    """Read a mesh written by :func:`write_stack_mesh` and check it against ``geometry`` (a StackGeometry)."""
    p = Path(path)
    if not p.exists():
        raise error(f"{p}: mesh file not found; run rule sensor_mesh")
    m = meshio.read(str(p))
    cells = m.cells_dict.get("hexahedron")
    if cells is None or "group" not in m.cell_data_dict:
        raise error(f"{p}: no hexahedra with a 'group' cell array; rerun rule sensor_mesh")
    groups = np.asarray(m.cell_data_dict["group"]["hexahedron"], dtype=int)
    z = geometry.z_interfaces_m
    if not np.isclose(m.points[:, 2].max(), z[-1], rtol=1e-9) or not set(groups) <= {1, 2, 3, 4}:
        raise error(f"{p}: mesh does not match the configured stack geometry; rerun rule sensor_mesh")
    return StackMesh(np.asarray(m.points, float), np.asarray(cells, int), groups, geometry, level)
