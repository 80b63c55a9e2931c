"""rapidfix: accurate ABB robots without touching the controller.

Reads RAPID programs, solves every target in joint space with screw-theory
inverse kinematics, corrects the joints with a fitted joint motion error model
and writes the program back with compensated targets.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from importlib import import_module

__all__ = ["__version__", "lazy_exports"]


def lazy_exports(package: str, table: dict[str, str]
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """A package's module-level `__getattr__` and `__dir__` (PEP 562) for the names of its
    export table: `name -> module` (relative to the package). A name is imported from its
    module on first use and kept in the package's namespace, so exporting it costs nothing
    until someone uses it (the command line's start-up pays only for what it runs).

    Each package's `__init__` ends with `__getattr__, __dir__ = lazy_exports(__name__, TABLE)`.
    """
    namespace = sys.modules[package].__dict__

    def __getattr__(name: str) -> object:
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *table})

    return __getattr__, __dir__


def __getattr__(name: str) -> str:
    """`__version__`, read from the installed metadata when first asked for
    (importlib.metadata costs the command line's start-up tens of milliseconds)."""
    if name != "__version__":
        raise AttributeError(f"module 'rapidfix' has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        value = version("rapidfix")
    except PackageNotFoundError:  # running from a source tree that was never installed
        value = "0.0.0+source"
    globals()["__version__"] = value
    return value
