"""Numerical plumbing under the physics: sparse direct solves (MKL PARDISO with SciPy's SuperLU as the fallback),
sfepy's set-up, and the BLAS thread count of the fits."""
