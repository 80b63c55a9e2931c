"""Inverse kinematics of an actual (perturbed) model: Newton / damped least squares.

Seeded by the analytic solution of the nominal model, which is within a few
millimetres, the vectorised Gauss–Newton step with a small Levenberg–Marquardt
damping converges quadratically to the actual model's exact solution.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from rapidfix.kinematics.robot_model import RobotModel

POSITION_TOL_MM = 1e-10
ROTATION_TOL_RAD = 1e-12


def pose_error(T_goal: np.ndarray, T_now: np.ndarray) -> np.ndarray:
    """Spatial twist (N, 6) = (ω, v) that carries T_now to T_goal to first order.

    ω is the rotation vector of R_goal R_nowᵀ; v = Δp − ω × p_now, so that the
    space Jacobian maps joint steps onto it directly.
    """
    R_err = T_goal[:, :3, :3] @ np.swapaxes(T_now[:, :3, :3], 1, 2)
    from scipy.spatial.transform import Rotation  # when used: start-up time

    omega = Rotation.from_matrix(R_err).as_rotvec()
    dp = T_goal[:, :3, 3] - T_now[:, :3, 3]
    v = dp - np.cross(omega, T_now[:, :3, 3])
    return np.concatenate([omega, v], axis=1)


def refine(
    model: RobotModel,
    T_goal: np.ndarray,
    q_seed: np.ndarray,
    max_iter: int = 30,
    damping: float = 1e-9,
) -> tuple[np.ndarray, np.ndarray]:
    """Solve fk(q) = T_goal from q_seed (M, 6) → (q (M, 6), converged (M,)).

    Converged means the tool0 position is within 1e-10 mm and the orientation
    within 1e-12 rad. Only the unconverged rows are iterated.
    """
    q = np.array(q_seed, dtype=float, copy=True)
    converged = np.zeros(q.shape[0], dtype=bool)
    active = np.flatnonzero(np.all(np.isfinite(q), axis=1))
    for _ in range(max_iter):
        if active.size == 0:
            break
        T_now = model.fk(q[active])
        err = pose_error(T_goal[active], T_now)
        pos_err = np.linalg.norm(T_goal[active, :3, 3] - T_now[:, :3, 3], axis=1)
        rot_err = np.linalg.norm(err[:, :3], axis=1)
        done = (pos_err < POSITION_TOL_MM) & (rot_err < ROTATION_TOL_RAD)
        converged[active[done]] = True
        active = active[~done]
        if active.size == 0:
            break
        J = model.jacobian(q[active])
        e = err[~done]
        # Levenberg–Marquardt step: (JJᵀ + λ²I) y = e, Δq = Jᵀ y; λ shrinks with the error.
        lam2 = damping * (1.0 + np.sum(e * e, axis=1))
        JJt = J @ np.swapaxes(J, 1, 2) + lam2[:, None, None] * np.eye(6)
        y = np.linalg.solve(JJt, e[:, :, None])
        q[active] += (np.swapaxes(J, 1, 2) @ y)[:, :, 0]
    return q, converged
