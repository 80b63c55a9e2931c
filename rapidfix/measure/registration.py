"""Registration of the laser-tracker frame to the robot base frame (paper eq. 6).

Convention: p_tracker = R @ p_robot + t, so p_robot = R.T @ (p_tracker − t) — the
paper's p = Q⁻¹(p' − T) with Q = R and T = t.

`register` is the initial, model-free step: a rigid (Kabsch) fit of positions the
nominal model predicts to the measured ones, made robust by trimming — points far
outside the bulk of the residuals are dropped and reported, and the fit repeated
until the set of kept points no longer changes. `rapidfix.measure.sweeps` then
refines the pose jointly with the joint errors.

Gauge: a constant joint-1 error cannot be told from a tracker turned about axis 1.
The chosen gauge is "the joint-1 error is zero at θ1 = 0"; `move_joint1_offset`
moves such a constant between the joint errors and the tracker pose.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.exceptions import MeasurementError

#: A residual beyond max(TRIM_FACTOR × median, median + TRIM_SIGMAS × robust spread) is an outlier.
TRIM_FACTOR = 4.0
TRIM_SIGMAS = 6.0


@dataclass(frozen=True)
class Registration:
    """Tracker pose in the robot base frame: p_tracker = R @ p_robot + t (mm).

    `residuals_mm (N,)` are the distances left per input point, `outlier_rows` the
    file rows (or indices) of the points the fit left out, `rms_mm` the RMS of the
    kept residuals.
    """

    R: np.ndarray
    t: np.ndarray
    rms_mm: float
    outlier_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    residuals_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    inliers: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    def to_robot(self, p_tracker: np.ndarray) -> np.ndarray:
        """Tracker-frame points (N, 3) in the robot base frame."""
        return (np.asarray(p_tracker, dtype=float) - self.t) @ self.R

    def to_tracker(self, p_robot: np.ndarray) -> np.ndarray:
        """Robot-frame points (N, 3) in the tracker frame."""
        return np.asarray(p_robot, dtype=float) @ self.R.T + self.t

    def report(self) -> dict[str, Any]:
        """JSON data: R, t, quaternion [w, x, y, z], tracker origin, residuals, outliers."""
        x, y, z, w = Rotation.from_matrix(self.R).as_quat()
        return {"convention": "p_tracker = R @ p_robot + t",
                "R": self.R.tolist(), "t_mm": self.t.tolist(),
                "quaternion_wxyz": [float(w), float(x), float(y), float(z)],
                "tracker_origin_in_robot_mm": (-self.R.T @ self.t).tolist(),
                "rms_mm": self.rms_mm,
                "outlier_rows": [int(r) for r in self.outlier_rows]}


def rigid_fit(p_robot: np.ndarray, p_tracker: np.ndarray,
              weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares rotation and translation with p_tracker ≈ R p_robot + t (Kabsch)."""
    p_robot = np.asarray(p_robot, dtype=float)
    p_tracker = np.asarray(p_tracker, dtype=float)
    w = np.ones(len(p_robot)) if weights is None else np.asarray(weights, dtype=float)
    c_r = np.average(p_robot, axis=0, weights=w)
    c_t = np.average(p_tracker, axis=0, weights=w)
    rot, _ = Rotation.align_vectors(p_tracker - c_t, p_robot - c_r, weights=w)
    R = rot.as_matrix()
    return R, c_t - R @ c_r


def outlier_mask(residuals_mm: np.ndarray, floor_mm: float = 0.0) -> np.ndarray:
    """True where a residual distance lies far outside the bulk (median/MAD rule).

    Residuals below `floor_mm` (what the instrument's noise alone can explain) never count.
    """
    r = np.asarray(residuals_mm, dtype=float)
    med = np.median(r)
    spread = 1.4826 * np.median(np.abs(r - med))
    return r > max(TRIM_FACTOR * med, med + TRIM_SIGMAS * spread, floor_mm)


def register(p_robot: np.ndarray, p_tracker: np.ndarray, *, rows: np.ndarray | None = None,
             max_rounds: int = 10) -> Registration:
    """Robust rigid registration of predicted robot-frame points to tracker points.

    Needs at least 3 points that are not on one line. `rows` (N,) names the points
    in `outlier_rows` (default: their indices).
    """
    p_robot = np.asarray(p_robot, dtype=float)
    p_tracker = np.asarray(p_tracker, dtype=float)
    n = len(p_robot)
    rows = np.arange(n) if rows is None else np.asarray(rows)
    centred = p_robot - p_robot.mean(axis=0)
    if n < 3 or np.linalg.svd(centred, compute_uv=False)[1] < 1e-6 * max(1.0, n):
        raise MeasurementError("registration needs at least 3 points that are not on a line")
    keep = np.ones(n, dtype=bool)
    for _ in range(max_rounds):
        R, t = rigid_fit(p_robot[keep], p_tracker[keep])
        resid = np.linalg.norm(p_robot @ R.T + t - p_tracker, axis=1)
        new_keep = ~outlier_mask(resid)
        if new_keep.sum() < max(3, n // 2):
            break
        if np.array_equal(new_keep, keep):
            break
        keep = new_keep
    rms = float(np.sqrt(np.mean(resid[keep] ** 2)))
    return Registration(R=R, t=t, rms_mm=rms, outlier_rows=rows[~keep], residuals_mm=resid,
                        inliers=keep)


def move_joint1_offset(R: np.ndarray, t: np.ndarray, offset_rad: float, axis_dir: np.ndarray,
                       axis_point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tracker pose that shows the same data after a joint-1 error c moves into it.

    R f(θ + c·e1) + t = R' f(θ) + t' for every pose, with a rotation by c about
    joint 1's axis (direction w through point a): R' = R·Rot(w, c),
    t' = t + R (a − Rot(w, c) a).
    """
    rot = Rotation.from_rotvec(np.asarray(axis_dir) * offset_rad).as_matrix()
    a = np.asarray(axis_point, dtype=float)
    return R @ rot, t + R @ (a - rot @ a)
