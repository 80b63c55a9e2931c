"""A target-ball (or TCP) offset that differs from the declared one.

The setup declares where the ball sits in the flange frame; if it sits
elsewhere (a different nest, a bent adapter), every measured point is off by
that vector turned with the flange. Three parameters, mm, in the flange frame.
It belongs to the measurement set-up, not to the robot: a program's tools are
declared (and measured) on their own, so compensation never applies it.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Geometry


class ToolOffset(VectorEffect):
    """Geometry.tool = translation (dx, dy, dz) mm after the declared tool."""

    type_name: ClassVar[str] = "tool_offset"
    changes_geometry: ClassVar[bool] = True
    measurement_only: ClassVar[bool] = True

    def __init__(self, name: str | None = None, *, free: bool = True) -> None:
        super().__init__(("dx_mm", "dy_mm", "dz_mm"), name, steps=[1e-3] * 3, free=free)

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """Append the translation to the tool correction."""
        T = np.eye(4)
        T[:3, 3] = self._p
        return geometry.replaced(tool=geometry.tool @ T)
