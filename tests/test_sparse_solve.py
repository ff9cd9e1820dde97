"""The sparse direct solvers (piezobearing.numerics.sparse_solve): PARDISO and SuperLU agree on FEM-like matrices."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from piezobearing.numerics import sparse_solve

SOLVERS = ["superlu"] + (["pardiso"] if sparse_solve.pardiso_available() else [])


def laplacian_3d(n: int) -> sp.csr_matrix:
    """The 7-point Laplacian on an n^3 grid with Dirichlet ends (symmetric positive definite)."""
    d = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    eye = sp.identity(n)
    return (sp.kron(sp.kron(d, eye), eye) + sp.kron(sp.kron(eye, d), eye) + sp.kron(sp.kron(eye, eye), d)).tocsr()


def saddle(n: int) -> sp.csr_matrix:
    """[[K, G], [G^T, -P]]: symmetric indefinite, as the piezoelectric FEM's short-circuit matrix."""
    k = laplacian_3d(n)
    rng = np.random.default_rng(3)
    m = n**3 // 4
    g = sp.random(k.shape[0], m, density=5.0 / k.shape[0], random_state=rng)
    p = sp.diags(np.full(m, 2.0)) + sp.diags([-0.5, -0.5], [-1, 1], shape=(m, m))
    return sp.bmat([[k, g], [g.T, -p]], format="csr")


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("definite", [True, False])
def test_factor_solves_one_and_many_right_hand_sides(solver, definite):
    a = laplacian_3d(12) if definite else saddle(12)
    rng = np.random.default_rng(0)
    x = rng.standard_normal((a.shape[0], 3))
    lu = sparse_solve.factorize(a, definite=definite, solver=solver)
    assert lu.factor_nnz > a.nnz // 2
    np.testing.assert_allclose(lu.solve(a @ x), x, rtol=0, atol=1e-10 * np.abs(x).max())
    y = lu.solve(a @ x[:, 0])
    assert y.shape == (a.shape[0],)
    np.testing.assert_allclose(y, x[:, 0], rtol=0, atol=1e-10 * np.abs(x).max())


def test_auto_prefers_pardiso_and_names_are_checked():
    assert sparse_solve.resolve(None) == ("pardiso" if sparse_solve.pardiso_available() else "superlu")
    assert sparse_solve.resolve("superlu") == "superlu"
    with pytest.raises(ValueError, match="solver must be one of"):
        sparse_solve.resolve("umfpack")


@pytest.mark.skipif(not sparse_solve.pardiso_available(), reason="pypardiso not installed")
def test_pardiso_is_reproducible_bit_for_bit():
    a = saddle(10)
    b = np.random.default_rng(1).standard_normal(a.shape[0])
    x1 = sparse_solve.factorize(a, definite=False, solver="pardiso").solve(b)
    x2 = sparse_solve.factorize(a, definite=False, solver="pardiso").solve(b)
    assert np.array_equal(x1, x2)
