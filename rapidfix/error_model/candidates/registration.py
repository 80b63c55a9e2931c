"""The laser tracker's registration: its pose (frame) and its length scale.

Measurements are taken in the tracker frame: p_tracker = s · R · p_robot + t
(`Geometry.world`, used only to predict measurements, never to compensate).
`TrackerFrame` is the rigid part (rotation vector and translation), always fitted
with any model that is compared with tracker data; `TrackerScale` is the
candidate effect "registration": a length scale error of the tracker (ppm), e.g.
a wrong air temperature or pressure in its refraction compensation.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Geometry

_FRAME_NAMES = ("rot_x_rad", "rot_y_rad", "rot_z_rad", "t_x_mm", "t_y_mm", "t_z_mm")


class TrackerFrame(VectorEffect):
    """Rigid tracker pose: world = [R(rotvec) t] · world."""

    type_name: ClassVar[str] = "tracker_frame"
    changes_geometry: ClassVar[bool] = True
    measurement_only: ClassVar[bool] = True

    def __init__(self, name: str | None = None, *, free: bool = True) -> None:
        super().__init__(_FRAME_NAMES, name, steps=[1e-6] * 3 + [1e-3] * 3, free=free)

    @classmethod
    def from_pose(cls, R: np.ndarray, t: np.ndarray, name: str | None = None) -> TrackerFrame:
        """A frame effect holding p_tracker = R p + t."""
        eff = cls(name)
        from scipy.spatial.transform import Rotation  # when used: start-up time

        rotvec = Rotation.from_matrix(np.asarray(R, dtype=float)).as_rotvec()
        eff.set_fitted(np.concatenate([rotvec, np.asarray(t, dtype=float)]))
        return eff

    def matrix(self) -> np.ndarray:
        """The (4, 4) rigid transform base → tracker."""
        T = np.eye(4)
        from scipy.spatial.transform import Rotation  # when used: start-up time

        T[:3, :3] = Rotation.from_rotvec(self._p[:3]).as_matrix()
        T[:3, 3] = self._p[3:]
        return T

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """Put the tracker pose in front of the measurement transform."""
        return geometry.replaced(world=self.matrix() @ geometry.world)


class TrackerScale(VectorEffect):
    """The tracker's length scale error: world = world · diag(s, s, s, 1), s = 1 + ppm·1e-6."""

    type_name: ClassVar[str] = "registration"
    changes_geometry: ClassVar[bool] = True
    measurement_only: ClassVar[bool] = True

    def __init__(self, name: str | None = None, *, free: bool = True) -> None:
        super().__init__(("scale_ppm",), name, steps=[1.0], free=free)

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """Scale robot-frame lengths before the tracker pose."""
        S = np.diag([1.0 + 1e-6 * self._p[0]] * 3 + [1.0])
        return geometry.replaced(world=geometry.world @ S)


def world_to_base(world: np.ndarray, p_world: np.ndarray) -> np.ndarray:
    """Measured points (N, 3) mapped back into the robot base frame through `world` (4, 4)."""
    world = np.asarray(world, dtype=float)
    A = world[..., :3, :3]
    rhs = np.asarray(p_world, dtype=float) - world[..., :3, 3]
    if A.ndim == 2:
        return np.linalg.solve(A, rhs.T).T
    return np.linalg.solve(A, rhs[..., None])[..., 0]
