"""Test-wide settings.

Single-threaded BLAS: the suite runs in parallel workers (pytest-xdist) on
small matrices, where BLAS threads only oversubscribe the cores.
"""

import os

import pytest

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(autouse=True)
def _fast_route_from_the_first_character(monkeypatch):
    """Every test reads RAPID text by the route a large program takes (the fast parser),
    whatever ran before it in the process; the plain warm-up of a fresh process
    (rapidfix.rapid.parse.WARM_UP_CHARS) has its own tests."""
    from rapidfix.rapid import parse

    monkeypatch.setattr(parse, "WARM_UP_CHARS", 0)
