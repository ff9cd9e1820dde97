"""Sparse direct factorisations of symmetric matrices: MKL PARDISO where installed, SuperLU otherwise.

The FEM solves of the sensor and of the housing factorise symmetric matrices
once and back-substitute many times (influence lines, shift-invert Lanczos,
time steps). PARDISO (Intel MKL's ``mkl_rt``, called here through ctypes)
factorises the housing's stiffness several times faster than SciPy's SuperLU
in the model's nested-dissection order, with 2.6x fewer factor entries
(benchmarks/bench_solvers.py; docs/performance.md). SciPy's SuperLU stays
the fallback and the reference: ``solver="superlu"`` is the method the tests
and the benchmark compare with.

The binding is ours, not ``pypardiso``'s: pypardiso searches the whole
environment (a recursive glob) for ``libmkl_rt`` at import and at every
solver it creates, 1-9 s each on a busy machine.

PARDISO runs in MKL's conditional-numerical-reproducibility mode (iparm 34)
so that two runs give the same bits whatever the threads do.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import glob
import os
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

SOLVERS = ("pardiso", "superlu")


@functools.cache
def _mkl_pardiso():
    """MKL's ``pardiso`` entry point, or None where MKL's runtime library is not installed."""
    names = [os.environ.get("PIEZOBEARING_MKL_RT"), ctypes.util.find_library("mkl_rt")]
    for d in (os.path.join(sys.prefix, "lib"), os.path.join(sys.base_prefix, "lib")):
        names += sorted(glob.glob(os.path.join(d, "libmkl_rt.so*")) + glob.glob(os.path.join(d, "libmkl_rt*.dylib")))
    for name in names:
        if not name:
            continue
        try:
            lib = ctypes.CDLL(name)
        except OSError:
            continue
        fn = lib.pardiso
        i32 = ctypes.POINTER(ctypes.c_int32)
        fn.argtypes = [ctypes.POINTER(ctypes.c_int64)] + [i32] * 5 + [ctypes.c_void_p, i32, i32, i32, i32, i32, i32]
        fn.argtypes += [ctypes.c_void_p, ctypes.c_void_p, i32]
        fn.restype = None
        return fn
    return None


def pardiso_available() -> bool:
    """True if MKL's runtime library (the ``mkl`` package) loads."""
    return _mkl_pardiso() is not None


def default_solver() -> str:
    """``pardiso`` if it loads, else ``superlu``; the environment variable ``PIEZOBEARING_SOLVER=superlu``
    forces the previous method (benchmarks/bench_workflow.py compares whole runs with each)."""
    if os.environ.get("PIEZOBEARING_SOLVER") == "superlu":
        return "superlu"
    return "pardiso" if pardiso_available() else "superlu"


def resolve(solver: str | None) -> str:
    """The solver name for ``None``/``"auto"`` (the default) or a name from :data:`SOLVERS`."""
    if solver in (None, "auto"):
        return default_solver()
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS} or 'auto', got {solver!r}")
    if solver == "pardiso" and not pardiso_available():
        raise ValueError("solver 'pardiso' needs Intel MKL's runtime (pip install mkl)")
    return solver


class _Pardiso:
    """One PARDISO factorisation of a real symmetric matrix (upper triangle, CSR, 1-based)."""

    def __init__(self, a: sp.spmatrix, definite: bool):
        self._fn = _mkl_pardiso()
        self._mtype = 2 if definite else -2
        self._pt = np.zeros(64, dtype=np.int64)  # PARDISO's internal handle
        up = sp.triu(sp.csr_matrix(a), format="csr")
        up.sum_duplicates()
        up.sort_indices()
        if np.any(up.diagonal() == 0):
            raise ValueError("PARDISO needs every diagonal entry of a symmetric matrix stored and non-zero")
        self._data = np.ascontiguousarray(up.data, dtype=np.float64)
        self.shape = up.shape
        self._ia = (up.indptr + 1).astype(np.int32)
        self._ja = (up.indices + 1).astype(np.int32)
        self._perm = np.zeros(0, dtype=np.int32)
        ip = self._iparm = np.zeros(64, dtype=np.int32)
        ip[0] = 1  # use the values below, not the defaults
        ip[1] = 2  # METIS nested-dissection ordering
        ip[7] = 0  # iterative refinement: two steps, only if pivots were perturbed
        ip[9] = 8  # pivot perturbation 1e-8 (indefinite)
        ip[10] = 0 if definite else 1  # symmetric scaling (indefinite)
        ip[12] = 0 if definite else 1  # symmetric weighted matching (indefinite)
        ip[17] = -1  # report the factor's non-zeros
        ip[20] = 1  # Bunch-Kaufman pivoting (indefinite)
        ip[33] = 1  # conditional numerical reproducibility: same bits every run
        ip[34] = 0  # one-based indices
        self._alive = False
        # analysis (METIS ordering, symbolic factorisation) and numerical factorisation
        self._call(12, np.zeros((self.shape[0], 1)))
        self._alive = True

    @property
    def factor_nnz(self) -> int:
        return int(self._iparm[17])

    @property
    def perturbed_pivots(self) -> int:
        return int(self._iparm[13])

    def _call(self, phase: int, b: np.ndarray) -> np.ndarray:
        b = np.asfortranarray(b, dtype=np.float64)
        x = np.zeros_like(b)
        err = ctypes.c_int32(0)
        i32 = ctypes.POINTER(ctypes.c_int32)

        def c(v):
            return ctypes.byref(ctypes.c_int32(v))

        self._fn(
            self._pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            c(1),  # maxfct
            c(1),  # mnum
            c(self._mtype),
            c(phase),
            c(self.shape[0]),
            self._data.ctypes.data,
            self._ia.ctypes.data_as(i32),
            self._ja.ctypes.data_as(i32),
            self._perm.ctypes.data_as(i32),
            c(b.shape[1]),  # right-hand sides
            self._iparm.ctypes.data_as(i32),
            c(0),  # no messages
            b.ctypes.data,
            x.ctypes.data,
            ctypes.byref(err),
        )
        if err.value != 0:
            raise RuntimeError(f"PARDISO failed with error {err.value} in phase {phase}")
        return x

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        one = b.ndim == 1
        x = self._call(33, b[:, None] if one else b)
        return np.ascontiguousarray(x[:, 0] if one else x)

    def __del__(self):
        if getattr(self, "_alive", False):
            self._alive = False
            try:
                self._call(-1, np.zeros((self.shape[0], 1)))  # release PARDISO's memory
            except Exception:  # noqa: BLE001 - the interpreter may be shutting down
                pass


class _SuperLU:
    def __init__(self, a: sp.spmatrix, definite: bool, ordering: str):
        self._lu = spla.splu(
            sp.csc_matrix(a), permc_spec=ordering, diag_pivot_thresh=0.0, options={"SymmetricMode": True}
        )
        self.shape = a.shape

    @property
    def factor_nnz(self) -> int:
        return int(self._lu.L.nnz + self._lu.U.nnz)

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._lu.solve(np.asarray(b, dtype=float))


def factorize(a: sp.spmatrix, definite: bool = True, solver: str | None = None, ordering: str = "MMD_AT_PLUS_A"):
    """Factorise a real symmetric sparse matrix for repeated solves.

    Parameters
    ----------
    a : sparse matrix (n, n)
        Symmetric; only its upper triangle is read by PARDISO.
    definite : bool
        Positive definite (Cholesky, PARDISO mtype 2) or indefinite
        (Bunch-Kaufman LDL^T with symmetric matching, mtype -2).
    solver : {"pardiso", "superlu", "auto", None}
        ``auto``/None: PARDISO where installed.
    ordering : str
        SuperLU's column ordering (``permc_spec``) when SuperLU is used,
        without pivoting in symmetric mode; PARDISO orders with METIS.

    Returns
    -------
    object with ``solve(b)`` for b (n,) or (n, k), ``shape`` and ``factor_nnz``.
    """
    name = resolve(solver)
    if name == "pardiso":
        return _Pardiso(a, definite)
    return _SuperLU(a, definite, ordering)
