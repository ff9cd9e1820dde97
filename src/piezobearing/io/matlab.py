"""What a MATLAB file holds, as published: variables, structs and nested structs, struct arrays, cell arrays,
numbers of any class and text, each by its MATLAB path.

:func:`mat_contents` reads a ``.mat`` file of either kind MATLAB writes (v5 through ``scipy.io.loadmat``; v7.3,
HDF5, through ``h5py``, where a struct is a group with the attribute ``MATLAB_class = 'struct'``, a cell array
a dataset of object references into ``#refs#``, text a ``char`` dataset of UTF-16 codes) and flattens it into
paths as MATLAB writes them: ``bearing.gs`` (a field of a struct), ``ch(2).data`` (a field of the second
element of a struct array), ``signals{1}`` (the first cell), ``run.ch{2}.data``. Numbers keep MATLAB's
orientation (an n x k matrix as (n, k), a scalar 1 x 1) and their class (an ``int32`` rate stays an integer
until it is used).

A struct that holds a text field ``name`` (or ``label``, ``channel``, ``title``, ``id``; any case) and one
numeric array with more than one element is a channel with that name: its array is reachable by the name as
well as by its path (:attr:`MatContents.names`).

The file's MATLAB header tells the two kinds apart (``scipy.io.matlab.matfile_version``); h5py (0.03-0.04 s
of CPU to import) loads for a v7.3 file only, or to ask of a file without a MATLAB header whether it is HDF5.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.io import loadmat
from scipy.io.matlab import MatlabFunction, MatlabOpaque, matfile_version

if TYPE_CHECKING:
    import h5py

#: Text fields that name the channel of the struct that holds them (compared in lower case).
NAME_FIELDS = ("name", "label", "channel", "title", "id")
#: The HDF5 groups MATLAB keeps for itself in a v7.3 file.
_V73_INTERNAL = ("#refs#", "#subsystem#")
#: MATLAB's numeric and logical classes in a v7.3 file.
_V73_NUMERIC = {"double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                "logical"}


@dataclass
class MatContents:
    """A MATLAB file flattened to paths.

    Attributes
    ----------
    version : str
        ``"v5"`` or ``"v7.3"``.
    arrays : dict
        Path -> numeric array, at least 2-D in MATLAB's orientation (scalars are 1 x 1).
    texts : dict
        Path -> the text a ``char`` variable or field holds.
    names : dict
        A channel's name (the text of its struct's name field) -> the path of its array.
    """

    version: str
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)
    names: dict[str, str] = field(default_factory=dict)

    def scalars(self) -> dict[str, float]:
        """Path -> value of every real numeric scalar (any integer or float class) [the file's unit]."""
        return {p: float(a.ravel()[0]) for p, a in self.arrays.items()
                if a.size == 1 and not np.iscomplexobj(a)}


def mat_contents(path: str | Path) -> MatContents:
    """Every numeric array and text a MATLAB file holds, by its MATLAB path (module docstring)."""
    path = Path(path)
    if is_v73(path):
        import h5py  # the v7.3 reader (module docstring)

        out = MatContents("v7.3")
        with h5py.File(path, "r") as f:
            for name, item in f.items():
                if name not in _V73_INTERNAL:
                    _walk_v73(f, name, item, out)
        return out
    out = MatContents("v5")
    for name, value in loadmat(path, squeeze_me=False, chars_as_strings=True).items():
        if not name.startswith("__"):
            _walk_v5(name, value, out)
    return out


def is_v73(path: Path) -> bool:
    """A MATLAB v7.3 (HDF5) file: its header's version 2; a file without a MATLAB header, where h5py finds HDF5."""
    try:
        return matfile_version(str(path))[0] == 2
    except Exception:  # noqa: BLE001 - no MATLAB header (HDF5 written without one, or a damaged file): h5py decides
        import h5py  # the v7.3 reader (module docstring)

        return bool(h5py.is_hdf5(path))


# --------------------------------------------------------------------------- v5 (scipy.io)


def _walk_v5(path: str, value, out: MatContents) -> None:
    if not isinstance(value, np.ndarray) or isinstance(value, (MatlabOpaque, MatlabFunction)):
        return  # an opaque MATLAB object (a function handle, a string or datetime object): no numbers to read
    if value.dtype.names is not None:  # a struct, or a struct array
        elements = value.ravel(order="F")
        for i, element in enumerate(elements):
            at = path if elements.size == 1 else f"{path}({i + 1})"
            fields = {name: element[name] for name in value.dtype.names}
            for name, v in fields.items():
                _walk_v5(f"{at}.{name}", v, out)
            _name_channel(at, fields, out)
    elif value.dtype == object:  # a cell array
        for i, element in enumerate(value.ravel(order="F")):
            _walk_v5(f"{path}{{{i + 1}}}", element, out)
    elif value.dtype.kind in "US":
        rows = [str(r) for r in value.ravel()]
        out.texts[path] = "\n".join(rows)
    elif value.dtype.kind in "biufc" and value.size:
        out.arrays[path] = np.atleast_2d(value)


# --------------------------------------------------------------------------- v7.3 (HDF5)


def _matlab_class(item) -> str:
    c = item.attrs.get("MATLAB_class")
    return c.decode() if isinstance(c, bytes) else (str(c) if c is not None else "")


def _is_reference(item) -> bool:
    import h5py  # the v7.3 reader (module docstring)

    return isinstance(item, h5py.Dataset) and item.dtype == h5py.ref_dtype


def _walk_v73(f: h5py.File, path: str, item, out: MatContents) -> None:
    import h5py  # the v7.3 reader (module docstring)

    cls = _matlab_class(item)
    if isinstance(item, h5py.Group):
        members = _fields_in_order(item)
        if members and all(_is_reference(m) and not _matlab_class(m) for m in members.values()):
            # a struct array: each field a dataset of references, one per element (MATLAB's element order)
            n = next(iter(members.values())).size
            for i in range(n):
                at = path if n == 1 else f"{path}({i + 1})"
                for name, refs in members.items():
                    _walk_v73(f, f"{at}.{name}", f[refs[()].ravel()[i]], out)
                _name_channel_v73(f, at, {name: f[refs[()].ravel()[i]] for name, refs in members.items()}, out)
            return
        for name, member in members.items():
            _walk_v73(f, f"{path}.{name}", member, out)
        _name_channel_v73(f, path, members, out)
        return
    if item.attrs.get("MATLAB_empty", 0):
        return  # an empty array: the dataset holds its dimensions, not values
    if cls == "cell" or _is_reference(item):
        for i, ref in enumerate(np.asarray(item[()]).ravel()):  # the transposed array's C order: MATLAB's order
            _walk_v73(f, f"{path}{{{i + 1}}}", f[ref], out)
    elif cls == "char":
        codes = np.atleast_2d(np.asarray(item[()])).T  # MATLAB's rows
        out.texts[path] = "\n".join("".join(chr(int(c)) for c in row) for row in codes)
    elif (cls in _V73_NUMERIC or not cls) and np.issubdtype(item.dtype, np.number) and item.size:
        # MATLAB stores arrays column-major: an n x k matrix reads as (k, n)
        out.arrays[path] = np.atleast_2d(np.asarray(item[()]).T)
    elif item.dtype.names is not None and {"real", "imag"} <= set(item.dtype.names):
        z = np.asarray(item[()])
        out.arrays[path] = np.atleast_2d((z["real"] + 1j * z["imag"]).T)


def _fields_in_order(group: h5py.Group) -> dict:
    """A struct's fields in MATLAB's order (its ``MATLAB_fields`` attribute; HDF5 lists them by name)."""
    members = dict(group.items())
    order = group.attrs.get("MATLAB_fields")
    if order is None:
        return members
    names = ["".join(c.decode() for c in np.asarray(name).ravel()) for name in order]
    return {n: members[n] for n in names if n in members} | members


def _name_channel_v73(f: h5py.File, at: str, members: dict, out: MatContents) -> None:
    import h5py  # the v7.3 reader (module docstring)

    fields = {}
    for name, m in members.items():
        if isinstance(m, h5py.Dataset) and _matlab_class(m) == "char" and not m.attrs.get("MATLAB_empty", 0):
            fields[name] = "".join(chr(int(c)) for c in np.asarray(m[()]).ravel())
        elif isinstance(m, h5py.Dataset) and np.issubdtype(m.dtype, np.number):
            fields[name] = np.empty(m.size)
    _name_channel(at, fields, out)


# --------------------------------------------------------------------------- channel names


def _text_of(value) -> str | None:
    if isinstance(value, str):
        return value
    if isinstance(value, np.ndarray) and value.dtype.kind in "US" and value.size == 1:
        return str(value.ravel()[0])
    return None


def _name_channel(at: str, fields: dict, out: MatContents) -> None:
    """Where the struct at ``at`` holds a name field and one numeric array of more than one element, record
    that array's path under the name (a name two structs share names neither)."""
    name = next((t for k, v in fields.items() if k.lower() in NAME_FIELDS and (t := _text_of(v))), None)
    data = [k for k, v in fields.items() if isinstance(v, np.ndarray) and v.dtype.kind in "biufc" and v.size > 1]
    if not name or len(data) != 1:
        return
    target = f"{at}.{data[0]}"
    if name in out.names and out.names[name] != target:
        out.names[name] = ""  # ambiguous: only the paths name these channels
    else:
        out.names[name] = target
