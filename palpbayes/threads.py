"""One BLAS thread per process for the command line, unless the user chose otherwise.

palpbayes' numerical work is many small dense solves and products (the exact engine's Gram
matrices per surface node, the twin's tables, the budget's refits) and, in a campaign or a
map, one worker process per core.  OpenBLAS's default of one thread per core then runs several
threads per core that spin waiting for each other: on a two-core machine a ``palpbayes fit``
took 11.7 s with the default threads against 3.7 s with one (measured on 2026-12-07 with the
machine's other core busy; ``benchmarks/bench_cli.py`` sets the two side by side).

:func:`one_blas_thread` limits this process (:mod:`threadpoolctl`, which works after numpy is
imported) and sets ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1
for the worker processes it starts, unless one of them is already set: a user who wants more
threads sets it (``OMP_NUM_THREADS=2 palpbayes fit ...``).  The library (``import palpbayes``)
changes nothing of the sort by itself.
"""

from __future__ import annotations

import os

__all__ = ["BLAS_VARIABLES", "one_blas_thread"]

#: The environment variables the BLAS libraries numpy and scipy use read their thread count
#: from.
BLAS_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> bool:
    """Run BLAS on one thread in this process and the processes it starts; False (nothing
    changed) when the user set one of :data:`BLAS_VARIABLES`."""
    if any(os.environ.get(v) for v in BLAS_VARIABLES):
        return False
    for v in BLAS_VARIABLES:
        os.environ[v] = "1"
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)  # BLAS and OpenMP alike
    return True
