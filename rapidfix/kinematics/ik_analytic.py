"""Analytic inverse kinematics of a nominal ABB-type arm from Paden–Kahan subproblems.

The arm must have (checked by `check_structure` when a robot file is loaded):
axis 1 perpendicular to axis 2 and lying in the arm plane (the plane through the
wrist centre perpendicular to axis 2), axes 2 and 3 parallel, and a spherical
wrist (axes 4, 5 and 6 meet in one point, the wrist centre). All ABB six-axis
serial arms shipped here are of this kind. Then, with G = T·M⁻¹:

1. the wrist centre c goes to p = G·c; θ1 turns c's direction onto p's about
   axis 1 (subproblem 1), or that plus 180° (the wrist behind axis 1);
2. θ3 sets the distance from axis 2 to the wrist centre (subproblem 3, two
   elbow solutions), θ2 then swings the wrist centre onto p (subproblem 1);
3. the wrist rotation R_w = (R1 R2 R3)ᵀ R_G: axes 4 and 5 bring the direction of
   axis 6 into place (subproblem 2, two wrist solutions), θ6 turns a vector
   perpendicular to axis 6 into place (subproblem 1).

Eight branches per pose, all computed at once for the whole batch.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rapidfix.kinematics.screws import invert_transform, rotate_vectors
from rapidfix.kinematics.subproblems import subproblem1, subproblem2, subproblem3

if TYPE_CHECKING:
    from rapidfix.kinematics.robot_model import RobotModel

_PARALLEL_TOL = 1e-9
_DISTANCE_TOL = 1e-6  # mm


def _line_closest_points(r1: np.ndarray, w1: np.ndarray, r2: np.ndarray, w2: np.ndarray):
    """Closest points of two non-parallel lines and their distance."""
    d = r2 - r1
    k = w1 @ w2
    denom = 1.0 - k * k
    s = (d @ w1 - k * (d @ w2)) / denom
    t = (k * (d @ w1) - d @ w2) / denom
    a, b = r1 + s * w1, r2 + t * w2
    return a, b, float(np.linalg.norm(a - b))


def _distance_to_line(p: np.ndarray, r: np.ndarray, w: np.ndarray) -> float:
    d = p - r
    return float(np.linalg.norm(d - (d @ w) * w))


def wrist_centre(model: RobotModel) -> np.ndarray:
    """Where axes 4 and 5 meet at θ = 0 (mm)."""
    w, r = model.axis_dirs, model.axis_points
    a, b, _ = _line_closest_points(r[3], w[3], r[4], w[4])
    return 0.5 * (a + b)


def check_structure(model: RobotModel) -> tuple[str, str] | None:
    """None if the analytic IK applies to `model`, else (robot-file key, reason)."""
    w, r = model.axis_dirs, model.axis_points
    if np.linalg.norm(np.cross(w[3], w[4])) < _PARALLEL_TOL:
        return "joint[5].axis", "axis 5 must not be parallel to axis 4 (spherical wrist)"
    if np.linalg.norm(np.cross(w[5], w[4])) < _PARALLEL_TOL:
        return "joint[6].axis", "axis 6 must not be parallel to axis 5 (spherical wrist)"
    _, _, gap = _line_closest_points(r[3], w[3], r[4], w[4])
    if gap > _DISTANCE_TOL:
        return "joint[5].point", f"axis 5 misses axis 4 by {gap:.3g} mm (wrist not spherical)"
    c = wrist_centre(model)
    if _distance_to_line(c, r[5], w[5]) > _DISTANCE_TOL:
        return "joint[6].point", "axis 6 does not pass through the wrist centre"
    if np.linalg.norm(np.cross(w[1], w[2])) > _PARALLEL_TOL:
        return "joint[3].axis", "axis 3 must be parallel to axis 2"
    if abs(w[0] @ w[1]) > _PARALLEL_TOL:
        return "joint[2].axis", "axis 2 must be perpendicular to axis 1"
    if abs((r[0] - c) @ w[1]) > _DISTANCE_TOL:
        return "joint[1].point", "axis 1 must lie in the arm plane through the wrist centre"
    if _distance_to_line(c, r[0], w[0]) < _DISTANCE_TOL:
        return "joint[5].point", "the wrist centre must not lie on axis 1 at θ = 0"
    if _distance_to_line(c, r[2], w[2]) < _DISTANCE_TOL:
        return "joint[5].point", "the wrist centre must not lie on axis 3"
    return None


def _perpendicular_unit(w: np.ndarray) -> np.ndarray:
    helper = np.eye(3)[int(np.argmin(np.abs(w)))]
    v = np.cross(w, helper)
    return v / np.linalg.norm(v)


def _wrap(a: np.ndarray) -> np.ndarray:
    """Angles to (-π, π]."""
    return np.pi - np.mod(np.pi - a, 2.0 * np.pi)


class AnalyticIK:
    """The eight closed-form branches of a nominal model, for batches of tool0 poses."""

    def __init__(self, model: RobotModel) -> None:
        self.w = np.array(model.axis_dirs)
        self.r = np.array(model.axis_points)
        self.c = wrist_centre(model)
        self.home_inv = invert_transform(np.array(model.home))
        self.u_side = _perpendicular_unit(self.w[5])
        # ABB-type wrist (axis 6 along axis 4 at θ = 0, axis 5 across both): the flipped
        # wrist (θ4 + π, −θ5, θ6 + π) gives the same rotation, so θ6 is solved only once.
        w4, w5, w6 = self.w[3], self.w[4], self.w[5]
        self.flip_identity = bool(
            np.linalg.norm(np.cross(w4, w6)) < 1e-12 and abs(w4 @ w5) < 1e-12 and w4 @ w6 > 0
        )

    def base_branches(
        self, T: np.ndarray, q_prev: np.ndarray, wrist_tol: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q (N, 8, 6), reachable (N, 8), wrist_singular (N, 8)) for finite poses T (N, 4, 4).

        Branch index = 4·(θ1 turned by 180°) + 2·(second elbow root) + (flipped wrist).
        At a wrist singularity (|sin θ5| < wrist_tol) θ4 is q_prev[:, 3] and θ6
        carries the rest. Angles lie in (-π, π] except a held θ4.
        """
        w, r, c = self.w, self.r, self.c
        G = T @ self.home_inv
        RG, tG = G[:, :3, :3], G[:, :3, 3]
        p = RG @ c + tG  # wrist centre target (N, 3)

        # θ1: turn the home wrist centre's direction onto the target's (subproblem 1).
        t1, _ = subproblem1(w[0], r[0], c, p, tol=np.inf)
        d1 = p - r[0]
        d1 = d1 - (d1 @ w[0])[:, None] * w[0]
        shoulder_singular = np.einsum("ni,ni->n", d1, d1) < _DISTANCE_TOL**2
        t1 = np.where(shoulder_singular, q_prev[:, 0], t1)
        theta1 = np.stack([t1, _wrap(t1 + np.pi)], axis=1)  # (N, 2)

        # Turn back by θ1 at once (one sine per angle): the wrist centre target, where
        # axis 6 must point and a vector across it, p' = e^{-S1θ1} p etc.
        targets = np.stack([p - r[0], RG @ w[5], RG @ self.u_side], axis=1)  # (N, 3, 3)
        back1 = rotate_vectors(w[0], -theta1[:, :, None], targets[:, None])  # (N, 2, 3, 3)
        p_arm = back1[:, :, 0] + r[0]  # (N, 2, 3)

        # θ3 from the distance axis 2 → wrist centre (subproblem 3), then θ2 (subproblem 1).
        delta = np.sqrt(np.sum((p_arm - r[1]) ** 2, axis=-1))
        t3, reach = subproblem3(w[2], r[2], c, r[1], delta, tol=1e-9)  # (N, 2, 2)
        theta3 = _wrap(t3)
        c3 = rotate_vectors(w[2], theta3, c - r[2]) + r[2]  # (N, 2, 2, 3)
        theta2, _ = subproblem1(w[1], r[1], c3, p_arm[:, :, None, :], tol=np.inf)

        # Wrist: R_w = (R1 R2 R3)ᵀ R_G acting on the axis-6 direction and on a vector
        # across it; turned back joint by joint without building any matrix.
        pair = back1[:, :, None, 1:]  # (N, 2, 1, 2, 3)
        pair = rotate_vectors(w[1], -theta2[..., None], pair)
        pair = rotate_vectors(w[2], -theta3[..., None], pair)  # (N, 2, 2, 2, 3)
        v6, side = pair[..., 0, :], pair[..., 1, :]  # in the arm frame
        origin = np.zeros(3)
        t4, t5, _ = subproblem2(w[3], w[4], origin, w[5], v6, tol=np.inf)  # (N, 2, 2, 2)
        across = v6 - (v6 @ w[3])[..., None] * w[3]
        singular = np.sqrt(np.sum(across * across, axis=-1)) < wrist_tol  # (N, 2, 2)

        if singular.any():
            held = np.broadcast_to(q_prev[:, 3, None, None, None], t4.shape)
            t4 = np.where(singular[..., None], held, t4)
            v6_after4 = rotate_vectors(w[3], -t4, v6[..., None, :])
            t5_held, _ = subproblem1(w[4], origin, w[5], v6_after4, tol=np.inf)
            t5 = np.where(singular[..., None], t5_held, t5)
        if self.flip_identity:
            side = rotate_vectors(w[3], -t4[..., 0], side)
            side = rotate_vectors(w[4], -t5[..., 0], side)
            t6a, _ = subproblem1(w[5], origin, self.u_side, side, tol=np.inf)
            flipped = np.where(singular, t6a, _wrap(t6a + np.pi))  # held θ4: no flip
            t6 = np.stack([t6a, flipped], axis=-1)
        else:
            side = rotate_vectors(w[3], -t4, side[..., None, :])
            side = rotate_vectors(w[4], -t5, side)
            t6, _ = subproblem1(w[5], origin, self.u_side, side, tol=np.inf)

        n = T.shape[0]
        q = np.empty((n, 2, 2, 2, 6))
        q[..., 0] = theta1[:, :, None, None]
        q[..., 1] = theta2[..., None]
        q[..., 2] = theta3[..., None]
        q[..., 3] = t4
        q[..., 4] = t5
        q[..., 5] = t6
        ok = np.broadcast_to(reach[:, :, None, None], (n, 2, 2, 2))
        sing = np.broadcast_to(singular[..., None], (n, 2, 2, 2))
        return q.reshape(n, 8, 6), ok.reshape(n, 8).copy(), sing.reshape(n, 8).copy()


def analytic_solver(model: RobotModel) -> AnalyticIK:
    """The (cached) closed-form solver of a nominal model."""
    solver = getattr(model, "_analytic", None)
    if solver is None:
        solver = AnalyticIK(model)
        model._analytic = solver
    return solver
