"""The optional compiled (numba) kernels: one loader and one kind of switch for them all.

numba is an optional extra (`pip install 'rapidfix[fast]'`). Each kernel module
(`kinematics.ik_compiled`, `kinematics.fk_compiled`, `error_model.rbf_compiled`)
imports numba, so it is imported only when numba is installed; the environment
variable RAPIDFIX_IK_BACKEND=numpy keeps every computation in numpy. Kernels whose
results agree with numpy's only to rounding run inside a `Switch` that the
post-processor turns on, so fits and diagnoses give the same bytes with or without
numba.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from functools import cache
from types import ModuleType

BACKEND_ENV = "RAPIDFIX_IK_BACKEND"
"""Environment variable choosing the closed-form code: auto (default), numpy or numba."""


def numpy_only() -> bool:
    """Whether RAPIDFIX_IK_BACKEND=numpy asks to keep everything in numpy."""
    return os.environ.get(BACKEND_ENV, "").strip().lower() == "numpy"


@cache
def load_kernel(module: str) -> ModuleType | None:
    """The kernel module `module` (dotted path), or None when numba is not installed or
    does not import (e.g. one built for another numpy)."""
    if importlib.util.find_spec("numba") is None:
        return None
    try:
        kernel = importlib.import_module(module)
    except ImportError:
        return None
    _numba_ready()
    return kernel


_SCIPY_BLAS = "scipy.linalg.cython_blas"


@cache
def _numba_ready() -> None:
    """Load numba's implementations (its target context's `refresh`, which its first
    compile or cache load does anyway) with scipy's BLAS wrappers held back.

    Among them numba.np.arraymath checks once that `scipy.linalg.cython_blas` imports,
    and importing scipy.linalg costs 0.25 s of CPU: half of numba's first use in a
    process, paid by every rewrite large enough for the kernels. None of rapidfix's
    kernels calls BLAS. All that check decides is whether numba's np.convolve and
    np.correlate take their inner products from BLAS or from a loop; every other BLAS
    function numba compiles imports the wrappers itself when it is compiled (normally:
    they are held back only here). When scipy.linalg is imported already, nothing is
    held back; when anything here fails, numba loads as it would have. (Another thread
    importing scipy.linalg during this one call, 0.1 s, would see it refused; rapidfix's
    own threads, a batch worker's watcher and progress bars, import nothing.)
    """
    if _SCIPY_BLAS in sys.modules or "numba.np.arraymath" in sys.modules:
        return
    sys.modules[_SCIPY_BLAS] = None  # type: ignore[assignment]  # import raises ImportError
    try:
        from numba.core.registry import cpu_target

        cpu_target.target_context.refresh()
    except Exception:  # numba's own first use loads it then
        pass
    finally:
        if _SCIPY_BLAS in sys.modules and sys.modules[_SCIPY_BLAS] is None:
            del sys.modules[_SCIPY_BLAS]


class Switch:
    """A kernel that is off unless a block turns it on (`with switch.on():`)."""

    def __init__(self, name: str) -> None:
        self._on: ContextVar[bool] = ContextVar(name, default=False)

    def get(self) -> bool:
        """Whether the current block turned it on."""
        return self._on.get()

    @contextmanager
    def on(self) -> Iterator[None]:
        token = self._on.set(True)
        try:
            yield
        finally:
            self._on.reset(token)


__all__ = ["BACKEND_ENV", "Switch", "load_kernel", "numpy_only"]
