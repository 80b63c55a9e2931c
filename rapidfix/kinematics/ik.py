"""All-branch inverse kinematics: analytic branches, ±360° variants, limits, statuses.

`solve_all(model, T)` is what `RobotModel.ik` calls. For a nominal model the eight
branches come in closed form (ik_analytic); for an actual model they are the
nominal branches refined on the actual screws (ik_numeric). Every branch is then
repeated for each whole-turn shift that an axis's limits allow (axes 4 and 6 of
most ABB arms have more than one turn; axis 3's range may leave (-180°, 180°]),
and checked against the limits. Batches are processed in chunks to bound memory.
"""

from __future__ import annotations

import itertools
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics.ik_analytic import analytic_solver
from rapidfix.kinematics.ik_numeric import refine
from rapidfix.kinematics.ik_result import IKSolutions, IKStatus
from rapidfix.kinematics.model import as_joint_batch, as_pose_batch
from rapidfix.kinematics.screws import invert_transform

if TYPE_CHECKING:
    from rapidfix.kinematics.frames import Tool, WorkObject
    from rapidfix.kinematics.model import RobotModel

WRIST_TOL = 1e-7
"""|sin θ5| below which the wrist counts as singular (θ4 is then held)."""

CHUNK = 8192
_LIMIT_TOL = 1e-9
_RIGID_TOL = 1e-6
_FIXED_POINT_STEPS = 6


def turn_counts(limits: np.ndarray) -> tuple[int, ...]:
    """Number of whole-turn variants per axis: the turns its range spans, plus one.

    An angle is first wrapped into [lo, lo + 2π); variant k adds k turns. An axis
    with exactly ±180° gets two, so that both −180° and +180° are offered.
    """
    return tuple(
        int(np.floor((hi - lo + 2.0 * _LIMIT_TOL) / (2.0 * np.pi))) + 1 for lo, hi in limits
    )


def turn_offsets(limits: np.ndarray) -> np.ndarray:
    """All combinations (V, 6) of whole-turn shifts, axis 1 varying slowest."""
    counts = turn_counts(limits)
    return np.array(list(itertools.product(*(range(c) for c in counts))), dtype=float)


@lru_cache(maxsize=64)
def _turn_table(counts: tuple[int, ...]) -> np.ndarray:
    """The whole-turn shifts (V, 6) in radians for the given variant counts."""
    table = 2.0 * np.pi * np.array(list(itertools.product(*(range(c) for c in counts))))
    table.setflags(write=False)
    return table


def _rigid(T: np.ndarray) -> np.ndarray:
    """(N,) mask: finite, orthonormal rotation with det +1 and last row [0, 0, 0, 1]."""
    finite = np.all(np.isfinite(T), axis=(1, 2))
    Ts = np.where(finite[:, None, None], T, np.eye(4))
    R = Ts[:, :3, :3]
    ortho = np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max(axis=(1, 2)) < _RIGID_TOL
    det = np.linalg.det(R) > 0
    row = np.abs(Ts[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1) < _RIGID_TOL
    return finite & ortho & det & row


def _prev_batch(q_prev: np.ndarray | None, n: int) -> np.ndarray:
    if q_prev is None:
        return np.zeros((n, 6))
    qp, _ = as_joint_batch(q_prev)
    if qp.shape[0] == 1:
        return np.broadcast_to(qp, (n, 6))
    if qp.shape[0] != n:
        raise KinematicsError(f"q_prev has {qp.shape[0]} rows for {n} poses")
    if not np.all(np.isfinite(qp)):
        raise KinematicsError("q_prev contains NaN or infinite values")
    return qp


def _base_branches(
    model: RobotModel, T: np.ndarray, q_prev: np.ndarray, wrist_tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    solver = analytic_solver(model.nominal)
    q8, ok8, sing8 = solver.base_branches(T, q_prev, wrist_tol)
    if model.is_nominal:
        return q8, ok8, sing8
    # Actual model. Branch-preserving fixed point first: solve the nominal model for
    # the target corrected by the current model difference, T' = F_n(q) F_a(q)⁻¹ T,
    # keeping each branch's own closed-form solution (the perturbation is small, so
    # this contracts fast and never hops between elbow or wrist branches). Newton on
    # the actual model then finishes to 1e-10 mm.
    n = T.shape[0]
    goals = np.repeat(T, 8, axis=0)
    prev = np.repeat(q_prev, 8, axis=0)
    pick = np.tile(np.arange(8), n)
    q = q8.reshape(-1, 6)
    for _ in range(_FIXED_POINT_STEPS):
        corrected = model.nominal.fk(q) @ invert_transform(model.fk(q)) @ goals
        q_all, _, _ = solver.base_branches(corrected, prev, wrist_tol)
        q = q_all[np.arange(q.shape[0]), pick]
    q_ref, conv = refine(model, goals, q)
    return q_ref.reshape(q8.shape), conv.reshape(ok8.shape), sing8


def _solve_chunk(
    model: RobotModel,
    T: np.ndarray,
    q_prev: np.ndarray,
    wrist_tol: float,
    out_q: np.ndarray,
    out_valid: np.ndarray,
    out_singular: np.ndarray,
) -> np.ndarray:
    """Solve one chunk into the given output views; returns the statuses."""
    n = T.shape[0]
    rigid = _rigid(T)
    Ts = np.where(rigid[:, None, None], T, np.eye(4))
    q8, ok8, sing8 = _base_branches(model, Ts, q_prev, wrist_tol)
    ok8 &= rigid[:, None]
    q8 = np.where(ok8[..., None], q8, np.nan)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    # Into [lo, lo + 2π) per axis (starting a hair below lo, so that an angle at a
    # limit is offered at both ends of a range of a whole number of turns).
    start = lo - _LIMIT_TOL
    q8 = start + np.mod(q8 - start, 2.0 * np.pi)
    # Slots (n, 8, K1, …, K6): each axis's variants broadcast along its own dimension,
    # and each axis's limits checked on its few variants before combining.
    counts = turn_counts(model.limits)
    v = int(np.prod(counts))
    np.add(q8[:, :, None, :], _turn_table(counts), out=out_q.reshape(n, 8, v, 6))
    inside = ok8.reshape(n, 8, *([1] * 6))
    for j, count in enumerate(counts):
        shape = [1] * 6
        shape[j] = count
        turns = (2.0 * np.pi * np.arange(count)).reshape(shape)
        angle = q8[:, :, j].reshape(n, 8, *([1] * 6)) + turns
        inside = inside & (angle >= lo[j] - _LIMIT_TOL) & (angle <= hi[j] + _LIMIT_TOL)
    out_valid[...] = np.broadcast_to(inside, (n, 8, *counts)).reshape(n, 8 * v)
    out_singular[...] = np.repeat(sing8 & ok8, v, axis=1)
    status = np.full(n, IKStatus.UNREACHABLE, dtype=np.int8)
    status[ok8.any(axis=1)] = IKStatus.BEYOND_LIMITS
    status[out_valid.any(axis=1)] = IKStatus.OK
    status[(out_valid & out_singular).any(axis=1)] = IKStatus.WRIST_SINGULAR
    status[~rigid] = IKStatus.INVALID_POSE
    return status


def solve_all(
    model: RobotModel,
    T: np.ndarray,
    *,
    tool: Tool | np.ndarray | None = None,
    wobj: WorkObject | np.ndarray | None = None,
    q_prev: np.ndarray | None = None,
    wrist_tol: float = WRIST_TOL,
    chunk: int = CHUNK,
) -> IKSolutions:
    """Every solution for poses T (N, 4, 4) (or (4, 4)), tool0 in the base frame.

    With `tool` and/or `wobj`, T is the TCP pose in the work-object frame (a
    robtarget) and is first turned into the flange pose. `q_prev` (N, 6) or (6,)
    supplies θ4 at wrist singularities (default 0). Never raises for a bad pose:
    it gets its status (INVALID_POSE, UNREACHABLE, BEYOND_LIMITS).
    """
    Tb, _ = as_pose_batch(T)
    if tool is not None or wobj is not None:
        from rapidfix.kinematics.frames import flange_target

        Tb = flange_target(Tb, tool, wobj)
    n = Tb.shape[0]
    prev = _prev_batch(q_prev, n)
    offsets = turn_offsets(np.asarray(model.limits))
    s = 8 * offsets.shape[0]
    q = np.empty((n, s, 6))
    valid = np.empty((n, s), dtype=bool)
    singular = np.empty((n, s), dtype=bool)
    status = np.empty(n, dtype=np.int8)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for start in range(0, n, max(1, chunk)):  # chunks bound memory; each is vectorised
            sl = slice(start, start + chunk)
            status[sl] = _solve_chunk(
                model, Tb[sl], prev[sl], wrist_tol, q[sl], valid[sl], singular[sl]
            )
    branch = np.repeat(np.arange(8), offsets.shape[0])
    turns = np.tile(offsets, (8, 1)).astype(int)
    return IKSolutions(
        q=q, valid=valid, status=status, branch=branch, turns=turns, singular=singular
    )
