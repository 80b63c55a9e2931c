"""Line of sight from a laser tracker to the target ball.

A spherically mounted retroreflector returns the beam only within its acceptance
angle (±30° for a common 1.5" SMR) about its opening direction, the `normal`
given in the flange frame. The arm itself hiding the ball is not modelled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.kinematics import RobotModel


@dataclass(frozen=True)
class TrackerView:
    """Tracker head position (3,) mm in the base frame; SMR opening `normal` (3,) in the
    flange frame; half acceptance angle in degrees."""

    position_mm: np.ndarray
    normal: np.ndarray
    acceptance_deg: float = 30.0

    def angles_deg(self, robot: RobotModel, q: np.ndarray, smr_mm: np.ndarray) -> np.ndarray:
        """Angle (N,) between the SMR's opening and the line to the tracker, degrees."""
        T = robot.fk(np.atleast_2d(q))
        ball = T[:, :3, :3] @ smr_mm + T[:, :3, 3]
        n = T[:, :3, :3] @ (self.normal / np.linalg.norm(self.normal))
        to_tracker = self.position_mm - ball
        to_tracker /= np.linalg.norm(to_tracker, axis=1, keepdims=True)
        return np.degrees(np.arccos(np.clip(np.einsum("ni,ni->n", n, to_tracker), -1, 1)))

    def visible(self, robot: RobotModel, q: np.ndarray, smr_mm: np.ndarray) -> np.ndarray:
        """Mask (N,) of poses whose ball the tracker can see."""
        return self.angles_deg(robot, q, smr_mm) <= self.acceptance_deg
