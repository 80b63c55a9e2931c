"""rapidfix: accurate ABB robots without touching the controller.

Reads RAPID programs, solves every target in joint space with screw-theory
inverse kinematics, corrects the joints with a fitted joint motion error model
and writes the program back with compensated targets.
"""

from __future__ import annotations

__all__ = ["__version__"]


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
