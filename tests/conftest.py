"""Test-wide settings.

Single-threaded BLAS: the suite runs in parallel workers (pytest-xdist) on
small matrices, where BLAS threads only oversubscribe the cores.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

os.environ.setdefault("MPLBACKEND", "Agg")
