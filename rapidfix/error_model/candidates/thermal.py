"""Thermal drift: the arm's links grow as it warms up.

Steel and aluminium grow by α ≈ 11–23 ppm/K; a uniformly warmed arm standing on
its base scales every length about the base origin: axis points and tool0's
home position by s = 1 + 1e-6 · (c0 + c1 · (x − x_ref)), where x is the
temperature (°C, column temp_c) or, without a temperature, the time (hours,
column time_s) as a first-order stand-in for the warm-up. c0 is the scale at the
reference x_ref (the calibration set's mean), c1 the growth per kelvin (or hour).
A pose without the variable in its context is taken at x_ref.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Geometry
from rapidfix.exceptions import ModelError

VARIABLES = {"temp_c": ("growth_ppm_per_k", 1.0), "time_s": ("growth_ppm_per_h", 1 / 3600.0)}


class ThermalDrift(VectorEffect):
    """Arm lengths scaled by 1 + 1e-6 (c0 + c1 (x − x_ref)), per pose."""

    type_name: ClassVar[str] = "thermal_drift"
    changes_geometry: ClassVar[bool] = True

    def __init__(self, variable: str = "temp_c", reference: float = 20.0,
                 name: str | None = None, *, free: bool = True) -> None:
        if variable not in VARIABLES:
            raise ModelError(f"thermal drift needs temp_c or time_s, not {variable!r}")
        super().__init__(("scale_ppm", VARIABLES[variable][0]), name, steps=[1.0, 1.0],
                         free=free)
        self.variable = variable
        self.reference = float(reference)

    def _x(self, ctx: Context, n: int) -> np.ndarray:
        value = getattr(ctx, self.variable)
        if value is None:
            return np.zeros(n)
        unit = VARIABLES[self.variable][1]
        return (np.broadcast_to(np.asarray(value, dtype=float), (n,)) - self.reference) * unit

    def scale(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Length factor (N,) of every pose."""
        n = np.atleast_2d(q_cmd).shape[0]
        return 1.0 + 1e-6 * (self._p[0] + self._p[1] * self._x(ctx, n))

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """Scale axis points and home position per pose."""
        s = self.scale(q_cmd, ctx)
        n = s.shape[0]
        points = np.broadcast_to(geometry.axis_points, (n, 6, 3)) * s[:, None, None]
        dirs = np.broadcast_to(geometry.axis_dirs, (n, 6, 3)).copy()
        home = np.broadcast_to(geometry.home, (n, 4, 4)).copy()
        home[:, :3, 3] *= s[:, None]
        return geometry.replaced(axis_dirs=dirs, axis_points=points, home=home)

    def context_fields(self) -> frozenset[str]:
        """What this effect reads from the context."""
        return frozenset({self.variable})

    def describe(self) -> str:
        """One line naming the driving variable."""
        return f"{self.name} (arm length against {self.variable}, reference {self.reference:g})"

    def _state(self) -> dict[str, Any]:
        return {"variable": self.variable, "reference": self.reference}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> ThermalDrift:
        return cls(str(state["variable"]), float(state["reference"]), name)
