"""One BLAS thread inside the per-point solvers.

A harmonic-balance point works on small matrices (tens to a few hundred unknowns, dense
LU of a few hundred DOFs): there OpenBLAS's threads only synchronise, and on a 2-core
machine a sweep with the default two threads ran 5 to 10 times slower than with one
(the link sweep of tests/test_gear_trains.py, 2026-12-02). Parallel work belongs to the
study level (several sweeps at once), so :func:`single_blas_thread` limits BLAS to one
thread for the duration of a sweep, a continuation or a time integration, and restores
the caller's setting afterwards (threadpoolctl).
"""

from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def single_blas_thread(func):
    """Run ``func`` with BLAS limited to one thread (the caller's limit restored after).

    Parameters
    ----------
    func : callable
        The function to wrap.

    Returns
    -------
    callable
    """

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper
