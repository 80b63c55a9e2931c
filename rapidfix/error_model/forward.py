"""Forward kinematics on an effect-changed geometry: flange poses and their Jacobian.

When no effect changes the geometry the robot's own `fk`/`jacobian` are used.
Otherwise the product of exponentials is evaluated with the changed axes, which
may differ per pose (leading N axis), using the kinematics layer's screw
exponential, and the space Jacobian is assembled from the same prefix products.
"""

from __future__ import annotations

import numpy as np

from rapidfix.error_model.effect import Geometry
from rapidfix.kinematics import RobotModel, revolute_exp


def _per_pose(a: np.ndarray, n: int, tail: tuple[int, ...]) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return a if a.ndim == len(tail) + 1 else np.broadcast_to(a, (n, *tail))


def flange_poses(
    robot: RobotModel, geometry: Geometry, q: np.ndarray, *, with_jacobian: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """tool0 poses (N, 4, 4) at actual joints q (N, 6) rad, and the space Jacobian if asked."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if geometry.same_kinematics(robot):
        T = robot.fk(q)
        return T, (robot.jacobian(q) if with_jacobian else None)
    n = q.shape[0]
    dirs = _per_pose(geometry.axis_dirs, n, (6, 3))
    points = _per_pose(geometry.axis_points, n, (6, 3))
    home = _per_pose(geometry.home, n, (4, 4))
    current = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    jac = np.empty((n, 6, 6)) if with_jacobian else None
    exps = revolute_exp(dirs, points, q[:, :6])  # (N, 6, 4, 4), all joints in one batch
    for i in range(6):  # the six joints; every step is vectorised over poses
        if jac is not None:
            w = np.einsum("nij,nj->ni", current[:, :3, :3], dirs[:, i])
            p = np.einsum("nij,nj->ni", current[:, :3, :3], points[:, i]) + current[:, :3, 3]
            jac[:, :3, i] = w
            jac[:, 3:, i] = -np.cross(w, p)
        current = current @ exps[:, i]
    return current @ home, jac
