"""Compensation: the joints to command so that the real robot reaches the ideal pose.

Per-joint models (every effect separable, no geometry change): each joint solves
θc + Δθ(θc) = θ_ideal on its own by Newton's method with the analytic derivative
(a fixed-point step where 1 + Δθ' is too small), vectorised over all poses.

Any other model: the general solve finds θc with actual_flange(θc) = T(θ_ideal),
the tool0 pose the nominal robot reaches at θ_ideal, by damped least squares
(Levenberg–Marquardt) on the full forward model, seeded by θ_ideal − Δθ(θ_ideal). Matching
tool0's whole pose matches every rigid tool's TCP too, so no tool enters the
solve. New effects are compensated by this solve without new code. Effects that
describe the measurement (tracker frame and scale, target-ball offset) never act
on tool0 and so are not compensated. Tolerance: 1e-9° on every joint step.

Poses that do not converge are reported per pose (`CompensationResult.converged`);
their last iterate is returned, never NaN. `compensate()` raises ModelError
listing them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix import chunks
from rapidfix.error_model.context import EMPTY, Context
from rapidfix.error_model.model import ErrorModel
from rapidfix.exceptions import ModelError
from rapidfix.kinematics import RobotModel

TOL_DEG = 1e-9
_MAX_ITER = 60
#: rows of the pose error in mm are divided by this to balance them against radians
_LENGTH_SCALE_MM = 1000.0
_DAMPING = 1e-14
#: squared scaled pose error of a pose that matches to round-off (1e-9 rad, 1e-6 mm)
_MATCHED_COST = 1e-18


@dataclass(frozen=True)
class CompensationResult:
    """The solve's answer and how well each pose was solved.

    q_cmd (N, 6) rad; converged (N,) bool; last_step_deg (N,): per pose the largest
    joint residual of θc + Δθ(θc) − θ_ideal (per-joint solve) or the largest joint
    step of the last Newton iteration (general solve), degrees; method
    ("per-joint" or "general"); iterations used.
    """

    q_cmd: np.ndarray
    converged: np.ndarray
    last_step_deg: np.ndarray
    method: str
    iterations: int

    @property
    def failed_rows(self) -> np.ndarray:
        """Indices of poses that did not converge."""
        return np.flatnonzero(~self.converged)


def _ideal(q_ideal: np.ndarray) -> np.ndarray:
    q = np.atleast_2d(np.asarray(q_ideal, dtype=float))
    if q.ndim != 2 or q.shape[1] != 6:
        raise ModelError(f"ideal joints must have shape (N, 6), got {q.shape}")
    bad = np.flatnonzero(~np.isfinite(q).all(axis=1))
    if bad.size:
        raise ModelError(f"ideal joints are not finite in rows {bad[:10].tolist()}")
    return q



def _rows_context(ctx: Context | None, q: np.ndarray) -> Context:
    """The context of every row of q (N,6), checked for N rows, with the motion
    directions fixed over all rows before any row is solved on its own."""
    ctx = EMPTY if ctx is None else ctx
    ctx.check_rows(q.shape[0])
    return ctx.with_directions(q)


def solve_per_joint(
    model: ErrorModel,
    q_ideal: np.ndarray,
    ctx: Context | None = None,
    *,
    tol_deg: float = TOL_DEG,
    max_iter: int = _MAX_ITER,
    chunk: int = chunks.COMPENSATE,
) -> CompensationResult:
    """Solve θc + Δθ(θc) = θ_ideal joint by joint (Newton, fixed-point fallback).

    Every pose is solved on its own, so the poses go through in chunks of `chunk`:
    the model's (poses × basis functions) temporaries then stay in the cache, about
    three times faster than one pass over a whole program, with the same answers.
    """
    target = _ideal(q_ideal)
    n = target.shape[0]
    ctx = _rows_context(ctx, target)
    q_cmd = np.empty_like(target)
    step = np.empty_like(target)
    iterations = 0
    for start in range(0, n, max(1, chunk)):
        rows = slice(start, start + chunk)
        sub_ctx = ctx if start == 0 and n <= chunk else ctx.take(rows)
        q_cmd[rows], step[rows], used = _per_joint_newton(
            model, target[rows], sub_ctx, np.radians(tol_deg), max_iter
        )
        iterations = max(iterations, used)
    converged = np.all(step <= np.radians(tol_deg), axis=1)
    return CompensationResult(q_cmd, converged, np.degrees(step.max(axis=1, initial=0.0)),
                              "per-joint", iterations)


def _per_joint_newton(
    model: ErrorModel, target: np.ndarray, ctx: Context, tol: float, max_iter: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """(θc, |residual| per joint, iterations) for one chunk of poses."""
    x = target - model.delta(target, ctx)
    # the first Newton step needs the derivative where the residual is taken: both at once
    delta, first_slope = model.delta_and_derivative(x, ctx)
    derivative: np.ndarray | None = first_slope
    residual = x + delta - target
    step = np.abs(residual)
    iterations = 0
    while iterations < max_iter and np.any(step > tol):
        iterations += 1
        if derivative is None:
            derivative = model.delta_derivative(x, ctx)
        slope = 1.0 + derivative
        derivative = None
        slope = np.where(np.abs(slope) > 0.1, slope, 1.0)  # fixed-point step if flat
        active = np.abs(residual) > tol
        x = np.where(active, x - residual / slope, x)
        residual = x + model.delta(x, ctx) - target
        step = np.abs(residual)
    return x, step, iterations


def _pose_error(target: np.ndarray, current: np.ndarray) -> np.ndarray:
    """Space-frame twist (N, 6) (ω rad, v mm) taking current to target, first order in v."""
    delta = target @ np.linalg.inv(current)
    from scipy.spatial.transform import Rotation  # when used: start-up time

    omega = Rotation.from_matrix(delta[:, :3, :3]).as_rotvec()
    p = delta[:, :3, 3]
    v = p - 0.5 * np.cross(omega, p)
    return np.concatenate([omega, v], axis=1)


def solve_general(
    model: ErrorModel,
    robot: RobotModel,
    q_ideal: np.ndarray,
    ctx: Context | None = None,
    *,
    tol_deg: float = TOL_DEG,
    max_iter: int = _MAX_ITER,
) -> CompensationResult:
    """Damped Newton on the full forward model: actual tool0 at θc = nominal tool0 at θ_ideal.

    Matching tool0's whole pose matches the pose of every rigid tool on it, so one
    solve serves any mix of tools and work objects. Each row is solved on its own
    (rows that have converged are left alone); the context is taken row by row
    with them, after the motion directions have been fixed over all rows. Rows the
    plain Newton step does not settle (near a stretched or folded arm, where it runs
    away) are solved again by Levenberg–Marquardt, which takes back any step that
    raises the pose error.
    """
    q_ideal = _ideal(q_ideal)
    n = q_ideal.shape[0]
    ctx = _rows_context(ctx, q_ideal)
    tol = np.radians(tol_deg)
    target = robot.fk(q_ideal)
    seed = q_ideal - model.delta(q_ideal, ctx)  # the per-joint answer: a close seed
    q, step, iterations = _newton(model, robot, target, seed.copy(), ctx, tol, max_iter,
                                  guarded=False)
    again = np.flatnonzero(~(step <= tol))
    if again.size:
        sub = ctx if again.size == n else ctx.take(again)
        q2, step2, more = _newton(model, robot, target[again], seed[again], sub, tol,
                                  max_iter, guarded=True)
        q[again], step[again] = q2, step2
        iterations += more
    converged = step <= tol
    return CompensationResult(q, converged, np.degrees(step), "general", iterations)


def _newton(model: ErrorModel, robot: RobotModel, target: np.ndarray, q: np.ndarray, ctx: Context,
            tol: float, max_iter: int, *, guarded: bool) -> tuple[np.ndarray, np.ndarray, int]:
    """Newton iterations on every row until its joint step is within `tol`; with
    `guarded`, Levenberg–Marquardt: a step that raises the row's pose error is taken
    back and retried with more damping, and an unfinished row returns its best iterate."""
    n = q.shape[0]
    scale = np.array([1.0, 1.0, 1.0] + [1.0 / _LENGTH_SCALE_MM] * 3)
    step = np.full(n, np.inf)
    iterations = 0
    eye = np.eye(6)
    damping = np.full(n, _DAMPING)
    best_q, best_cost = q.copy(), np.full(n, np.inf)
    kept_err, kept_jac = np.zeros((n, 6)), np.zeros((n, 6, 6))
    while iterations < max_iter and np.any(step > tol):
        iterations += 1
        active = np.flatnonzero(step > tol)  # converged poses are left alone
        sub_ctx = ctx if active.size == n else ctx.take(active)
        current, jac = model.flange_and_jacobian(robot, q[active], sub_ctx)
        err = _pose_error(target[active], current) * scale
        a = jac * scale[None, :, None]
        back = active[:0]
        if guarded:
            cost = np.einsum("ij,ij->i", err, err)
            worse = ~(cost <= best_cost[active] * (1.0 + 1e-9) + 1e-30)
            back, ahead = active[worse], active[~worse]
            q[back] = best_q[back]
            damping[back] = np.maximum(damping[back] * 100.0, 1e-10)
            err[worse], a[worse] = kept_err[back], kept_jac[back]
            best_q[ahead], best_cost[ahead] = q[ahead], cost[~worse]
            kept_err[ahead], kept_jac[ahead] = err[~worse], a[~worse]
            damping[ahead] = np.maximum(damping[ahead] / 10.0, _DAMPING)
        at = np.swapaxes(a, 1, 2)
        lhs = at @ a + damping[active][:, None, None] * eye
        dq = np.linalg.solve(lhs, (at @ err[:, :, None]))[:, :, 0]
        finite = np.isfinite(dq).all(axis=1)
        dq[~finite] = 0.0
        q[active] += dq
        step[active] = np.where(finite, np.abs(dq).max(axis=1), np.nan)
        # a step taken back converges only where the pose already matches (round-off)
        unfinished = (step[back] <= tol) & (best_cost[back] > _MATCHED_COST)
        step[back] = np.where(unfinished, 2.0 * tol, step[back])
        if not finite.all():  # a singular Jacobian: report the row, never iterate on NaN
            step[active[~finite]] = np.inf
            break
    if guarded:
        q = np.where((step <= tol)[:, None], q, best_q)
    return q, step, iterations


def solve_compensation(
    model: ErrorModel,
    robot: RobotModel,
    q_ideal: np.ndarray,
    ctx: Context | None = None,
    *,
    tol_deg: float = TOL_DEG,
) -> CompensationResult:
    """Per-joint solve when the model allows it, else the general solve; status per pose."""
    model.check_robot(robot.name)
    if model.separable:
        return solve_per_joint(model, q_ideal, ctx, tol_deg=tol_deg)
    return solve_general(model, robot, q_ideal, ctx, tol_deg=tol_deg)


def compensate(
    model: ErrorModel,
    robot: RobotModel,
    q_ideal: np.ndarray,
    ctx: Context | None = None,
) -> np.ndarray:
    """Commanded joints (N, 6) rad; ModelError listing the rows that did not converge."""
    result = solve_compensation(model, robot, q_ideal, ctx)
    failed = result.failed_rows
    if failed.size:
        raise ModelError(
            f"compensation did not converge for {failed.size} pose(s), rows "
            f"{failed[:10].tolist()}{' …' if failed.size > 10 else ''}",
            hint="use solve_compensation() to handle them one by one",
        )
    return result.q_cmd
