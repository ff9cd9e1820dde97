"""One BLAS thread for code made of many small dense solves.

The detectors' and the diagnoses' fits work on matrices of n x (a few) values: a second BLAS thread only
waits and spins (measured on the loaded 2-core machine: the baseline detector's least squares 50-200x slower,
the bearing diagnosis's SVDs 70x, the calibration diagnosis 2-3.3x the CPU with OpenBLAS's threads). The
thread pools are found once per process: finding them (threadpoolctl walks every loaded library) cost about
3 ms a call, a tenth of the classification rule's 800 detections.
"""

from __future__ import annotations

import functools

import scipy.linalg  # noqa: F401  (loads SciPy's BLAS, so that the controller lists its pools)
from threadpoolctl import ThreadpoolController


@functools.lru_cache(maxsize=1)
def _blas_pools() -> ThreadpoolController:
    """The BLAS thread pools of this process, found once."""
    return ThreadpoolController()


def single_blas_thread():
    """A context manager: the BLAS pools limited to one thread inside it, restored after."""
    return _blas_pools().limit(limits=1, user_api="blas")


def one_blas_thread(fn):
    """``fn`` run on one BLAS thread (:func:`single_blas_thread`)."""

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        with single_blas_thread():
            return fn(*args, **kwargs)

    return wrapped
