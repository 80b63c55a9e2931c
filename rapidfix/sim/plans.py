"""Measurement plans: which commanded joints a calibration session runs, in which order.

- sweeps as in the paper: each joint over its range in 5° steps, the others fixed,
  three repeats (joints with more than one turn are swept over one turn, ±180°);
  poses that put the ball under the floor or fold the arm onto itself are dropped;
- calibration / validation points: Latin-hypercube joints inside the swept ranges,
  away from the wrist singularity, the floor and the base — i.e. the nominal IK of
  well spread, reachable ball positions;
- a ballbar run: a semicircle of discrete points in a plane inclined 45°, the
  commanded joints being the nominal IK of the ideal positions.
All angles rad, lengths mm. Every plan takes a seed where it is random.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import RobotModel

FLOOR_MM = 100.0  # lowest allowed ball height above the base plane
FOLD_MM = 250.0  # closest allowed approach of the wrist centre to the lower arm (*)
BASE_MM = 300.0  # closest approach of the wrist centre to axis 1 below axis 2 + this (*)
# (*) for an arm of the IRB 1600-10/1.45's size, scaled by `arm_scale` for others.
WRIST_SINGULAR_DEG = 15.0  # |θ5| below this is too close to the wrist singularity
#: Preferred joint box for random points (deg), cut to the robot's swept ranges.
POINT_BOX_DEG = ((-150, 150), (-50, 80), (-120, 50), (-160, 160), (-110, 110), (-170, 170))


def _ball(robot: RobotModel, q: np.ndarray, smr: np.ndarray) -> np.ndarray:
    T = robot.fk(q)
    return T[:, :3, :3] @ smr + T[:, :3, 3]


def arm_scale(robot: RobotModel) -> float:
    """Size of the arm relative to an IRB 1600-10/1.45 (tool0 815 mm in front of axis 1)."""
    return float(np.clip(abs(robot.home[0, 3]) / 815.0, 0.3, 3.0))


def plausible_poses(robot: RobotModel, q: np.ndarray, smr: np.ndarray) -> np.ndarray:
    """Mask (N,) of poses a cell would run: ball above the floor, arm not folded onto
    itself, wrist not down beside the base."""
    _, points = robot.joint_frames(q)
    ball = _ball(robot, q, smr)
    wrist = points[:, 4]
    a, b = points[:, 1], points[:, 2]  # the lower arm, from axis 2 to axis 3
    s = np.clip(np.einsum("ni,ni->n", wrist - a, b - a) / np.einsum("ni,ni->n", b - a, b - a),
                0.0, 1.0)
    fold = np.linalg.norm(wrist - (a + s[:, None] * (b - a)), axis=1)
    size = arm_scale(robot)
    near_base = (np.linalg.norm(wrist[:, :2], axis=1) < BASE_MM * size) & (
        wrist[:, 2] < robot.axis_points[1, 2] + BASE_MM * size)
    return (ball[:, 2] >= FLOOR_MM) & (fold >= FOLD_MM * size) & ~near_base


def longest_run(mask: np.ndarray) -> np.ndarray:
    """The longest run of consecutive True values of `mask`, as a mask (a sweep has no gaps)."""
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    out = np.zeros_like(mask, dtype=bool)
    if len(starts):
        k = int(np.argmax(stops - starts))
        out[starts[k]:stops[k]] = True
    return out


@dataclass(frozen=True)
class SweepPlan:
    """Rows of a sweep session: moved joint (0-based), commanded pose (rad), repeat (1..)."""

    sweep_joint: np.ndarray
    q: np.ndarray
    repeat: np.ndarray


def sweep_plan(robot: RobotModel, smr_offset_mm: np.ndarray, *,
               fixed_deg: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 45.0, 0.0),
               step_deg: float = 5.0, repeats: int = 3,
               joints: tuple[int, ...] = (0, 1, 2, 3, 4, 5)) -> SweepPlan:
    """Each joint in `joints` over its range in `step_deg` steps, the others at `fixed_deg`.

    The range is the joint's limits cut to ±180°, then to the longest stretch of
    plausible poses (`plausible_poses`).

    Rows run joint by joint; within a joint, repeat by repeat, each in ascending angle.
    """
    smr = np.asarray(smr_offset_mm, dtype=float)
    limits = np.degrees(robot.limits)
    rows_joint, rows_q, rows_rep = [], [], []
    for j in joints:
        lo, hi = max(limits[j, 0], -180.0), min(limits[j, 1], 180.0)
        grid = np.arange(np.ceil(lo / step_deg), np.floor(hi / step_deg) + 1) * step_deg
        q = np.tile(np.radians(fixed_deg), (len(grid), 1))
        q[:, j] = np.radians(grid)
        q = q[longest_run(plausible_poses(robot, q, smr))]
        rows_joint.append(np.full(len(q) * repeats, j))
        rows_q.append(np.tile(q, (repeats, 1)))
        rows_rep.append(np.repeat(np.arange(1, repeats + 1), len(q)))
    return SweepPlan(np.concatenate(rows_joint), np.vstack(rows_q), np.concatenate(rows_rep))


def point_plan(robot: RobotModel, smr_offset_mm: np.ndarray, n: int, seed: int, *,
               ranges: np.ndarray | None = None) -> np.ndarray:
    """`n` well spread plausible poses (n, 6) rad in random (= execution) order.

    `ranges` (6, 2) rad bounds the joints (default: POINT_BOX_DEG cut to the limits);
    poses near the wrist singularity, under the floor or folded are rejected.
    """
    smr = np.asarray(smr_offset_mm, dtype=float)
    box = np.radians(np.asarray(POINT_BOX_DEG, dtype=float))
    if ranges is not None:
        box = np.column_stack([np.maximum(box[:, 0], ranges[:, 0]),
                               np.minimum(box[:, 1], ranges[:, 1])])
    box = np.column_stack([np.maximum(box[:, 0], robot.limits[:, 0]),
                           np.minimum(box[:, 1], robot.limits[:, 1])])
    sampler = qmc.LatinHypercube(d=6, seed=seed)
    chosen: list[np.ndarray] = []
    total = 0
    for _ in range(20):
        q = qmc.scale(sampler.random(4 * n), box[:, 0], box[:, 1])
        keep = plausible_poses(robot, q, smr) & (np.abs(q[:, 4]) >= np.radians(
            WRIST_SINGULAR_DEG))
        chosen.append(q[keep])
        total += int(keep.sum())
        if total >= n:
            break
    q = np.vstack(chosen)
    if len(q) < n:
        raise KinematicsError(f"found only {len(q)} plausible poses for {n} points")
    return q[:n]


@dataclass(frozen=True)
class BallbarPlan:
    """A ballbar run: centre (3,), radius, unit plane normal (3,), angles (M,) rad,
    ideal ball positions (M, 3) and the commanded joints (M, 6) rad."""

    centre_mm: np.ndarray
    radius_mm: float
    normal: np.ndarray
    angles: np.ndarray
    ideal_mm: np.ndarray
    q: np.ndarray


def ballbar_plan(robot: RobotModel, smr_offset_mm: np.ndarray, *,
                 centre_mm: tuple[float, float, float] | None = None,
                 radius_mm: float | None = None, inclination_deg: float = 45.0,
                 step_deg: float = 10.0,
                 q_ref_deg: tuple[float, ...] = (0.0, 20.0, 10.0, 0.0, 45.0, 0.0)) -> BallbarPlan:
    """A semicircle of points every `step_deg` in a plane inclined by `inclination_deg`.

    By default the centre lies in front of the arm and the radius is 150 mm (less
    for small arms). The plane contains the base y direction and is tilted about
    it; the flange keeps the orientation it has at `q_ref_deg` (a comfortable
    pose, wrist well away from its singularity); the commanded joints are the
    nominal IK solution nearest `q_ref_deg` of each ideal flange pose.
    """
    if centre_mm is None:  # in front of the arm, at half the height of tool0's home
        centre_mm = (0.98 * robot.home[0, 3], 0.0, 0.5 * robot.home[2, 3])
    if radius_mm is None:
        radius_mm = 150.0 * min(1.0, arm_scale(robot))
    c = np.asarray(centre_mm, dtype=float)
    incl = np.radians(inclination_deg)
    normal = np.array([-np.sin(incl), 0.0, np.cos(incl)])
    u = np.array([0.0, 1.0, 0.0])
    v = np.cross(normal, u)
    angles = np.radians(np.arange(0.0, 180.0 + 1e-9, step_deg))
    ideal = c + radius_mm * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    q_ref = np.radians(q_ref_deg)
    R_f = robot.fk(q_ref)[:3, :3]
    T = np.tile(np.eye(4), (len(angles), 1, 1))
    T[:, :3, :3] = R_f
    T[:, :3, 3] = ideal - R_f @ np.asarray(smr_offset_mm, dtype=float)
    q, status = robot.ik_nearest(T, q_ref)
    ok = np.asarray(status) == 0
    if not np.all(ok):
        raise KinematicsError(f"ballbar points {np.flatnonzero(~ok).tolist()} are not "
                              "reachable; move the centre or shrink the radius")
    return BallbarPlan(c, float(radius_mm), normal, angles, ideal, q)

