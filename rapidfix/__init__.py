"""rapidfix: accurate ABB robots without touching the controller.

Reads RAPID programs, solves every target in joint space with screw-theory
inverse kinematics, corrects the joints with a fitted joint motion error model
and writes the program back with compensated targets.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rapidfix")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+source"

__all__ = ["__version__"]
