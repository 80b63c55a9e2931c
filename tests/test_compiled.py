"""numba's first use without scipy's BLAS check (`rapidfix.compiled._numba_ready`): the
wrappers are held back only while numba loads its implementations, never left behind,
and not at all once scipy.linalg is imported."""

from __future__ import annotations

import subprocess
import sys
import types

import pytest

from rapidfix import compiled

BLAS = "scipy.linalg.cython_blas"


def _fake_numba(monkeypatch, refresh) -> None:
    """numba's registry as `_numba_ready` reaches it, with `refresh` as its target
    context's refresh (works whether numba is installed or not)."""
    registry = types.ModuleType("numba.core.registry")
    registry.cpu_target = types.SimpleNamespace(
        target_context=types.SimpleNamespace(refresh=refresh))
    for name, module in (("numba", types.ModuleType("numba")),
                         ("numba.core", types.ModuleType("numba.core")),
                         ("numba.core.registry", registry)):
        monkeypatch.setitem(sys.modules, name, module)
    sys.modules["numba"].core = sys.modules["numba.core"]
    sys.modules["numba.core"].registry = registry
    monkeypatch.delitem(sys.modules, "numba.np.arraymath", raising=False)
    monkeypatch.delitem(sys.modules, BLAS, raising=False)


@pytest.mark.parametrize("fails", [False, True])
def test_the_blas_wrappers_are_held_back_only_while_numba_loads(monkeypatch, fails):
    seen = []

    def refresh() -> None:
        seen.append(sys.modules.get(BLAS, "absent"))
        with pytest.raises(ImportError):  # what numba's check meets: no BLAS from scipy
            __import__(BLAS)
        if fails:
            raise RuntimeError("numba changed")

    _fake_numba(monkeypatch, refresh)
    compiled._numba_ready.__wrapped__()  # an error in numba's loading is not raised
    assert seen == [None]
    assert BLAS not in sys.modules  # nothing left behind: a later import is a real one


def test_nothing_is_held_back_once_scipy_linalg_is_imported(monkeypatch):
    seen = []
    _fake_numba(monkeypatch, lambda: seen.append("refreshed"))
    monkeypatch.setitem(sys.modules, BLAS, types.ModuleType(BLAS))
    compiled._numba_ready.__wrapped__()
    assert seen == [] and sys.modules[BLAS] is not None


def test_a_kernel_loads_without_scipy_linalg_and_scipy_linalg_still_imports():
    """In a fresh process: with numba installed, loading a kernel and running it leaves
    scipy.linalg unimported and importable; without numba there is no kernel."""
    code = (
        "import sys, numpy as np\n"
        "from rapidfix.compiled import load_kernel\n"
        "kernel = load_kernel('rapidfix.error_model.rbf_compiled')\n"
        "if kernel is None:\n"
        "    print('no numba', 'scipy.linalg' in sys.modules)\n"
        "else:\n"
        "    out = np.empty(3)\n"
        "    c = np.linspace(-1.0, 1.0, 9)\n"
        "    kernel.gaussian_sums(np.zeros(3), c, 4.0, np.ones(9), 0.25 * 4.0, True, False,\n"
        "                         out)\n"
        "    first = 'scipy.linalg' in sys.modules, sys.modules.get("
        "'scipy.linalg.cython_blas', 'absent')\n"
        "    import scipy.linalg.cython_blas\n"
        "    print('numba', *first, round(float(out[0]), 12))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    words = done.stdout.split()
    try:
        import numba  # noqa: F401
    except ImportError:
        assert words == ["no", "numba", "False"]
        return
    # the sum of the Gaussians at 0 over centres -1..1 (step 0.25, width 0.25)
    expected = sum(__import__("math").exp(-0.5 * (k / 1.0) ** 2) for k in range(-4, 5))
    assert words[:3] == ["numba", "False", "absent"]
    assert float(words[3]) == pytest.approx(expected, rel=1e-12)
