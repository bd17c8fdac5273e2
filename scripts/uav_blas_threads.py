"""One BLAS thread count in every process of the project, set before anything loads numpy:
scripts/setup.sh installs this module into .venv with a .pth file that imports it, so every
interpreter of the venv runs it at start-up, whoever starts it (a ROS node, the demo, a
script, a pytest or Dask worker) and whatever the caller's environment says.

Why: numpy's and scipy's wheels each bundle OpenBLAS, which splits some products between
its threads and then sums in another order, and proxsuite's Eigen runs larger products on
OpenMP threads; so a result depends on the thread count of the process that computed it,
and Dask's nanny starts its workers with one thread while a process of its own would take
one per core. OpenBLAS and OpenMP read the count from the environment once, when they
load (OpenBLAS: OPENBLAS_NUM_THREADS, else OMP_NUM_THREADS; OpenMP: OMP_NUM_THREADS). One
thread is also the faster for the project's small matrices (docs/performance.md). No pinned
wheel bundles MKL.
"""

from __future__ import annotations

import os

BLAS_THREADS = 1  # OpenBLAS and OpenMP threads per process
THREAD_COUNT_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")


def set_thread_counts() -> None:
    """Set every variable of THREAD_COUNT_VARIABLES to BLAS_THREADS in this process's
    environment, which the processes it starts inherit."""
    for name in THREAD_COUNT_VARIABLES:
        os.environ[name] = str(BLAS_THREADS)


set_thread_counts()
