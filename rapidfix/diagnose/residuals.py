"""Residuals of a model on a measured point set, in the robot base frame.

The model predicts where the tracker sees the ball; the residual measured −
predicted is mapped back into the robot base frame through the model's own
registration (so per-axis numbers are robot x, y, z). Its length is what the
robot would still miss by after compensation with this model.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from rapidfix.error_model import ErrorModel, MeasuredPoints, OutsideRangeWarning, world_to_base
from rapidfix.kinematics import RobotModel
from rapidfix.report import position_error_stats


@dataclass(frozen=True)
class Residuals:
    """Residual vectors (N, 3) mm in the base frame (measured − predicted)."""

    vectors: np.ndarray

    @property
    def norms(self) -> np.ndarray:
        """|residual| per point (N,) mm."""
        return np.linalg.norm(self.vectors, axis=1)

    @property
    def mean_mm(self) -> float:
        """Mean distance."""
        return float(self.norms.mean())

    @property
    def rms_mm(self) -> float:
        """RMS distance."""
        return float(np.sqrt(np.mean(self.norms**2)))

    def stats(self) -> dict[str, Any]:
        """Mean, RMS, max and per-axis statistics (mm)."""
        return position_error_stats(np.zeros_like(self.vectors), self.vectors)


def residuals(model: ErrorModel, robot: RobotModel, data: MeasuredPoints) -> Residuals:
    """Measured − predicted ball positions (N, 3) mm in the model's base frame."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideRangeWarning)
        world = model.geometry(robot, data.q, data.ctx).world
        measured = world_to_base(world, data.xyz)
        predicted = model.predict_ball(robot, data.q, data.row_balls_mm, data.ctx)
    return Residuals(measured - predicted)
