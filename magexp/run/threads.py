"""One BLAS thread for the processes that run experiments: deterministic numbers.

The matrices here are small, so BLAS threads buy nothing, and a threaded reduction order can move
a flat direction of a fit in its last digits. OpenBLAS, OpenMP and MKL read their thread counts
when they are loaded, so :func:`one_blas_thread` must run before numpy is imported: it is called
by magexp's own entry points (:func:`magexp.__main__.main`, ``python -m magexp.artifacts.reproduce``,
the test suite's ``conftest.py``), whose worker processes inherit it. ``import magexp`` in a
user's own process sets nothing (their numpy keeps its threads).
"""

from __future__ import annotations

import os

#: the variables set (each only if not set already)
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> None:
    """Set each of :data:`BLAS_THREADS` to 1 unless it is set (call before numpy is imported)."""
    for var in BLAS_THREADS:
        os.environ.setdefault(var, "1")
