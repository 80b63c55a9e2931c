"""Gravity torques about any joint, from the nominal kinematics of the commanded pose.

A mass m at p loads joint j with τ_j = ((p − a_j) × m g) · w_j, a_j a point on
joint j's current axis and w_j its direction. Two kinds of load are computed:

- the payload: m (kg) at its centre of gravity, a point fixed in the flange frame;
- a body of unknown mass fixed to some link: its torque is linear in its mass
  moment C = m (c − a_j) written in that link's home frame, τ = ((R C) × g) · w_j,
  R the link's rotation at the pose. The unit moments along three axes give three
  regressors; a moment along w_j itself never loads the joint.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from rapidfix.kinematics import RobotModel, load_robot

GRAVITY_MS2 = 9.81
DOWN = np.array([0.0, 0.0, -1.0])


@lru_cache(maxsize=8)
def nominal_robot(name: str) -> RobotModel:
    """The nominal robot model (cached)."""
    return load_robot(name)


def link_transforms(robot: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (N, 6, 3, 3) and translation (N, 6, 3) mm of each link at the poses q:
    link j moves with joints 1..j by e^[S1]θ1 … e^[Sj]θj (its home pose to its pose)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    dirs = np.asarray(robot.axis_dirs, dtype=float)
    points = np.asarray(robot.axis_points, dtype=float)
    n = q.shape[0]
    rot = np.empty((n, 6, 3, 3))
    shift = np.empty((n, 6, 3))
    R = np.broadcast_to(np.eye(3), (n, 3, 3))
    t = np.zeros((n, 3))
    for j in range(6):  # six joints, each vectorised over the poses
        from scipy.spatial.transform import Rotation  # when used: start-up time

        Rj = Rotation.from_rotvec(q[:, [j]] * dirs[j]).as_matrix()
        tj = points[j] - Rj @ points[j]  # a turn about the axis through points[j]
        t = np.einsum("nij,nj->ni", R, tj) + t
        R = R @ Rj
        rot[:, j], shift[:, j] = R, t
    return rot, shift


def payload_torques(robot: RobotModel, q: np.ndarray, cog_mm: np.ndarray,
                    payload_kg: np.ndarray, gravity_dir: np.ndarray = DOWN) -> np.ndarray:
    """Gravity torque (N, 6) N·m of the payload about every joint.

    `cog_mm` is the centre of gravity in the flange frame, (3,) or (N, 3).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    T = robot.fk(q)
    cog = np.broadcast_to(np.asarray(cog_mm, dtype=float), (q.shape[0], 3))
    p = np.einsum("nij,nj->ni", T[:, :3, :3], cog) + T[:, :3, 3]
    dirs, points = robot.joint_frames(q)
    lever = (p[:, None, :] - points) * 1e-3  # (N, 6, 3) m
    force = GRAVITY_MS2 * np.asarray(gravity_dir, dtype=float)
    per_kg = np.einsum("nki,nki->nk", np.cross(lever, force), dirs)
    return per_kg * np.asarray(payload_kg, dtype=float).reshape(-1, 1)


def body_torque_regressors(robot: RobotModel, q: np.ndarray, joint: int, link: int,
                           gravity_dir: np.ndarray = DOWN) -> np.ndarray:
    """Torque (N, 4) N·m about `joint` of a body fixed to `link` (both 0-based, link ≥
    joint): per unit of its mass moment m·c (kg·m, c its centre of mass in the home
    pose, from the base origin) along x, y and z, and per kg of its mass m.

    m (x − a_j) = R_L (m c) + m (t_L − a_j) for the link's motion x = R_L c + t_L.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    rot, shift = link_transforms(robot, q)
    dirs, points = robot.joint_frames(q)
    force = GRAVITY_MS2 * np.asarray(gravity_dir, dtype=float)
    R = rot[:, link]
    moments = np.cross(np.transpose(R, (0, 2, 1)), force)  # rows R e_k × g, (N, 3, 3)
    lever = (shift[:, link] - points[:, joint]) * 1e-3  # m
    columns = np.concatenate([moments, np.cross(lever, force)[:, None, :]], axis=1)
    return np.einsum("nki,ni->nk", columns, dirs[:, joint])
