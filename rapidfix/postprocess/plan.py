"""The compensation plan: TCP targets -> flange poses -> ideal joints -> commanded joints.

One vectorised pass over every target of a program: the flange poses from the
targets' tool and work-object frames, the analytic IK on the branch each
confdata names (or, for intermediate path points, the branch nearest a seed),
then the error model's compensation solve. Every target that fails gets a
reason a programmer can act on; no NaN leaves this module.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rapidfix import chunks
from rapidfix.error_model import Context, ErrorModel, solve_compensation
from rapidfix.exceptions import ModelError
from rapidfix.kinematics import IKStatus, RobotModel
from rapidfix.postprocess.placement import Placement

REASONS = {
    IKStatus.WRIST_SINGULAR: "wrist singularity (axis 5 at 0 deg): axes 4 and 6 are not determined",
    IKStatus.BEYOND_LIMITS: "beyond the joint limits on every branch",
    IKStatus.UNREACHABLE: "out of reach",
    IKStatus.NO_MATCHING_CONF: "no solution on the branch its confdata names",
    IKStatus.INVALID_POSE: "not a valid pose (quaternion or numbers)",
}
LIMIT_REASON = "beyond the joint limits after compensation"
SOLVE_REASON = "compensation did not converge"


@dataclass(frozen=True)
class Plan:
    """Per target: `flange` (N,4,4) intended tool0 pose in the base frame, `q_ideal` and
    `q_cmd` (N,6) rad, `ok` (N,) and `reason` (N,) ('' where ok), and the `context`
    (payload, directions, temperature) every row was compensated in."""

    flange: np.ndarray
    q_ideal: np.ndarray
    q_cmd: np.ndarray
    ok: np.ndarray
    reason: np.ndarray
    context: Context


def ik_on_conf(robot: RobotModel, flange: np.ndarray, conf: np.ndarray) -> tuple[np.ndarray,
               np.ndarray]:
    """The IK solution each confdata names (q (N,6) rad, status (N,)): `robot.ik_conf`,
    which chooses on the compact IK result without expanding every ±360° variant."""
    return robot.ik_conf(flange, np.asarray(conf, dtype=int))


def compensate_joints(
    model: ErrorModel, robot: RobotModel, q_ideal: np.ndarray, ctx: Context
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Commanded joints (N,6) for ideal joints, with success mask and reasons."""
    n = q_ideal.shape[0]
    reason = np.full(n, "", dtype=object)
    if n == 0:
        return np.zeros((0, 6)), np.zeros(0, dtype=bool), reason
    try:
        result = solve_compensation(model, robot, q_ideal, ctx)
    except ModelError as err:
        reason[:] = f"the model cannot compensate it: {err.message}"
        return q_ideal.copy(), np.zeros(n, dtype=bool), reason
    q_cmd = np.asarray(result.q_cmd, dtype=float)
    finite = np.all(np.isfinite(q_cmd), axis=1)
    ok = np.asarray(result.converged, dtype=bool) & finite
    reason[~ok] = SOLVE_REASON
    inside = robot.within_limits(np.where(finite[:, None], q_cmd, 0.0))
    reason[ok & ~inside] = LIMIT_REASON
    ok &= inside
    return np.where(ok[:, None], q_cmd, q_ideal), ok, reason


def _explain_conf(robot: RobotModel, flange: np.ndarray, conf: np.ndarray, status: np.ndarray,
                  reason: np.ndarray, shown: int = 3) -> None:
    """Name the confdata that do reach a target whose own confdata names no solution:
    the `shown` nearest to its own (sum of absolute differences; ties in confdata order).

    Vectorised over the failing targets, a chunk at a time: a program written in the
    wrong work object can fail on every move, and each has up to 8 branches × turns."""
    failing = np.flatnonzero(status == IKStatus.NO_MATCHING_CONF)
    for start in range(0, failing.size, chunks.EXPLAIN_CONF):
        _explain_rows(robot, flange, conf, failing[start:start + chunks.EXPLAIN_CONF],
                      reason, shown)


def _explain_rows(robot: RobotModel, flange: np.ndarray, conf: np.ndarray, rows: np.ndarray,
                  reason: np.ndarray, shown: int) -> None:
    """`_explain_conf` of the failing targets `rows`."""
    sols = robot.ik(flange[rows])
    valid = sols.valid
    found = robot.slot_confdata(sols)
    dist = np.abs(found - conf[rows][:, None, :]).sum(axis=2)
    # sort each row's slots by (invalid last, distance, confdata): the same order as the
    # distinct confdata sorted, then stably by distance
    keys = (found[..., 3], found[..., 2], found[..., 1], found[..., 0], dist, ~valid)
    order = np.lexsort(keys, axis=-1)
    ranked = np.take_along_axis(found, order[..., None], axis=1)
    # the first `shown` usable slots of each row, each unlike the one before it
    fresh = np.take_along_axis(valid, order, axis=1)
    fresh[:, 1:] &= np.any(ranked[:, 1:] != ranked[:, :-1], axis=2)
    picked = fresh & (np.cumsum(fresh, axis=1) <= shown)
    options = ranked[picked].tolist()  # row by row, in rank order
    ends = np.cumsum(picked.sum(axis=1)).tolist()
    begin = 0
    for row, end, own in zip(rows.tolist(), ends, conf[rows].tolist()):
        if end > begin:
            reason[row] = (f"no solution on the branch its confdata {own} names "
                           f"(it is reachable with {', '.join(map(str, options[begin:end]))})")
        begin = end


@dataclass(frozen=True)
class FreeConfiguration:
    """Rows that run with configuration monitoring off (`ConfL`/`ConfJ \\Off`): the
    controller reaches them on the configuration nearest the one it is in, whatever their
    confdata names. `rows` (N,) bool; `prev` (N+M,) the point executed just before each
    row (-1 not known), where points N.. are `extra` (M,6) joints of MoveAbsJ moves."""

    rows: np.ndarray
    prev: np.ndarray
    extra: np.ndarray


#: passes of "nearest the move before" along a chain of moves whose configuration is
#: free; each pass carries a changed branch one move further
_FREE_PASSES = 64


def _follow_nearest(robot: RobotModel, flange: np.ndarray, q: np.ndarray, status: np.ndarray,
                    free: FreeConfiguration) -> tuple[np.ndarray, np.ndarray]:
    """Joints (N,6) and status (N,) with the free rows on the solution nearest the joints
    of the move before them. A free row whose move before is not known keeps its
    confdata's solution, or, without one, takes the one nearest the calibration
    position (all joints 0), where an arm is when a cell starts. The passes follow each
    chain a move at a time, `_FREE_PASSES` moves deep; a row past them is solved nearest
    the nearest move before it that has joints, and the turns are then unwound along the
    chains (`_unwound`)."""
    n = q.shape[0]
    rows = np.flatnonzero(free.rows)
    q = np.where((status == IKStatus.OK)[:, None], np.asarray(q, dtype=float), np.nan)
    status = np.asarray(status).copy()
    start = rows[(free.prev[rows] < 0) & (status[rows] != IKStatus.OK)]
    if start.size:
        qn, st = robot.ik_nearest(flange[start], np.zeros((start.size, 6)))
        q[start] = np.where((st == IKStatus.OK)[:, None], qn, np.nan)
        status[start] = st
    chained = rows[free.prev[rows] >= 0]
    before = free.prev[chained]
    seeds = np.full((chained.size, 6), np.nan)
    points = np.concatenate([q, free.extra])
    # the chained rows after each point, found by the point: those of a pass are the ones
    # whose move before changed in the pass before (all at first)
    order = np.argsort(before, kind="stable")
    after = before[order]
    ahead = np.arange(chained.size)
    for _ in range(_FREE_PASSES):
        now = points[before[ahead]]
        changed = np.isfinite(now).all(axis=1) & ~np.all(now == seeds[ahead], axis=1)
        if not changed.any():
            break
        at = ahead[changed]
        seeds[at] = now[changed]
        sel = chained[at]
        qn, st = robot.ik_nearest(flange[sel], now[changed])
        good = st == IKStatus.OK
        old = q[sel]
        q[sel] = points[sel] = np.where(good[:, None], qn, old)
        status[sel] = np.where(good, IKStatus.OK, status[sel])
        moved = sel[~np.all(q[sel] == old, axis=1)]
        ahead = np.sort(order[_spans(np.searchsorted(after, moved, "left"),
                                     np.searchsorted(after, moved, "right"))])
    # not reached: the move before failed too, or stands farther along the chain than the
    # passes reach: nearest the nearest move before it that has joints, else the
    # calibration position
    rest = rows[status[rows] == IKStatus.NO_MATCHING_CONF]
    if rest.size:
        points = np.concatenate([q, free.extra])
        above = _solved_ancestors(np.isfinite(points).all(axis=1), free.prev)[rest]
        seeds = np.where((above >= 0)[:, None], points[np.maximum(above, 0)], 0.0)
        qn, st = robot.ik_nearest(flange[rest], seeds)
        q[rest] = np.where((st == IKStatus.OK)[:, None], qn, np.nan)
        status[rest] = st
    return _unwound(robot, q[:n], free.extra, free.prev, chained), status


def _spans(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The indices lo[i] .. hi[i]-1 of every i, one after the other."""
    size = hi - lo
    return np.repeat(lo - (np.cumsum(size) - size), size) + np.arange(int(size.sum()))


def _solved_ancestors(solved: np.ndarray, prev: np.ndarray) -> np.ndarray:
    """Per point: the nearest point before it along its chain (`prev`, -1 none) that is
    `solved`, or -1; by pointer jumping, each pass doubling the links passed over."""
    above = np.asarray(prev, dtype=np.int64).copy()
    for _ in range(64):
        passing = np.flatnonzero((above >= 0) & ~solved[np.maximum(above, 0)])
        if passing.size == 0:
            break
        above[passing] = above[above[passing]]
    return above


def _unwound(robot: RobotModel, q: np.ndarray, extra: np.ndarray, prev: np.ndarray,
             rows: np.ndarray) -> np.ndarray:
    """`q` (N,6) with the joints that turn more than once (a range over 360°) of each of
    `rows` moved by whole turns to stand nearest the joints of the move before it (`prev`,
    into q then `extra`), as moved already, along the chain: the controller follows a
    joint turn by turn, where a solution taken nearest a move farther back (past the moves
    the passes reach) may stand a turn off. The turns add up along a chain
    by pointer jumping; a move whose moved joints would leave the limits keeps its own,
    and the moves after it follow those."""
    limits = np.asarray(robot.limits, dtype=float)
    turns = limits[:, 1] - limits[:, 0] > 2.0 * np.pi + 1e-9
    if rows.size == 0 or not turns.any():
        return q
    n = q.shape[0]
    points = np.concatenate([q, extra])
    finite = np.isfinite(points).all(axis=1)
    links = np.full(points.shape[0], -1, dtype=np.int64)
    links[rows] = prev[rows]
    links[~finite | ~finite[np.maximum(links, 0)]] = -1
    linked = np.flatnonzero(links >= 0)
    steps = np.zeros_like(points)  # the whole turns between a move and the one before
    steps[np.ix_(linked, np.flatnonzero(turns))] = 2.0 * np.pi * np.round(
        (points[links[linked]] - points[linked])[:, turns] / (2.0 * np.pi))
    kept = np.zeros(points.shape[0], dtype=bool)  # moves that keep their own joints
    while True:
        parent = np.where(kept, -1, links)
        offset = np.where(kept[:, None], 0.0, steps)
        for _ in range(64):  # each pass doubles the links summed: chains of up to 2**64
            linked = np.flatnonzero(parent >= 0)
            if linked.size == 0:
                break
            up = parent[linked]
            offset[linked] = offset[linked] + offset[up]
            parent[linked] = parent[up]
        moved = q + offset[:n]
        outside = np.zeros(points.shape[0], dtype=bool)
        outside[:n] = finite[:n] & ~np.all((moved >= limits[:, 0]) & (moved <= limits[:, 1]),
                                           axis=1)
        # the first of a chain outside: the moves after it follow it, so may come back in
        first = outside & ~kept & ~(outside[np.maximum(links, 0)] & (links >= 0))
        if not first.any():
            return moved
        kept |= first


Conditions = Callable[[np.ndarray, np.ndarray], Context]
"""The context of every row for its joints (N,6) and whether each is solved (N,)."""


def plan_targets(
    model: ErrorModel,
    robot: RobotModel,
    targets: np.ndarray,
    conf: np.ndarray,
    placement: Placement,
    conditions: Context | Conditions,
    free: FreeConfiguration | None = None,
) -> Plan:
    """Plan every target (N,4,4) TCP pose in its work object, on its confdata branch
    (the `free` rows: on the branch nearest the move before them).

    `conditions` is the rows' context, or a function giving it for the rows' joints
    (motion directions follow from the joints). The directions are taken from the
    ideal joints first; rows where the commanded joints move the other way are
    solved again with the directions the commanded joints give.
    """
    n = targets.shape[0]
    flange = placement.flange(targets) if n else np.zeros((0, 4, 4))
    reason = np.full(n, "", dtype=object)
    if n == 0:
        return Plan(flange, np.zeros((0, 6)), np.zeros((0, 6)), np.zeros(0, bool), reason,
                    Context())
    context = conditions if callable(conditions) else (lambda _q, _known: conditions)
    if free is not None and free.rows.any():
        # a move whose configuration is free and whose move before is known goes where
        # the chain takes it: its confdata's solution is not asked for (taken mid-chain,
        # it would lead the moves after it onto its branch)
        own = np.flatnonzero(~(free.rows & (free.prev[:n] >= 0)))
        q_own, status_own = ik_on_conf(robot, flange[own], conf[own])
        q_ideal = np.full((n, 6), np.nan)
        status = np.full(n, IKStatus.NO_MATCHING_CONF, dtype=np.asarray(status_own).dtype)
        q_ideal[own], status[own] = q_own, status_own
        q_ideal, status = _follow_nearest(robot, flange, q_ideal, status, free)
    else:
        q_ideal, status = ik_on_conf(robot, flange, conf)
        status = np.asarray(status)
    solved = status == IKStatus.OK
    for code, text in REASONS.items():
        reason[status == code] = text
    _explain_conf(robot, flange, conf, status, reason)
    q_ideal = np.where(solved[:, None], np.nan_to_num(np.asarray(q_ideal, float)), 0.0)
    idx = np.flatnonzero(solved)
    q_cmd = q_ideal.copy()
    ok = np.zeros(n, dtype=bool)
    ctx = context(q_ideal, solved)
    if idx.size:
        qc, good, why = compensate_joints(model, robot, q_ideal[idx], ctx.take(idx))
        q_cmd[idx], ok[idx], reason[idx] = qc, good, why
        if ctx.last_direction is not None:
            again = context(q_cmd, solved)
            turned = idx[(again.last_direction[idx] != ctx.last_direction[idx]).any(axis=1)]
            if turned.size:
                qc, good, why = compensate_joints(model, robot, q_ideal[turned],
                                                  again.take(turned))
                q_cmd[turned], ok[turned], reason[turned] = qc, good, why
            ctx = again
    return Plan(flange, q_ideal, q_cmd, ok, reason, ctx)


def plan_nearest(
    model: ErrorModel,
    robot: RobotModel,
    targets: np.ndarray,
    seed: np.ndarray,
    placement: Placement,
    ctx: Context,
) -> Plan:
    """Plan intermediate path points: the IK branch nearest the seed joints (N,6)."""
    n = targets.shape[0]
    flange = placement.flange(targets)
    reason = np.full(n, "", dtype=object)
    q_ideal, status = robot.ik_nearest(flange, seed)
    status = np.asarray(status)
    solved = status == IKStatus.OK
    for code, text in REASONS.items():
        reason[status == code] = text
    q_ideal = np.where(solved[:, None], np.nan_to_num(np.asarray(q_ideal, float)), seed)
    idx = np.flatnonzero(solved)
    q_cmd = q_ideal.copy()
    ok = np.zeros(n, dtype=bool)
    if idx.size:
        qc, good, why = compensate_joints(model, robot, q_ideal[idx], ctx.take(idx))
        q_cmd[idx], ok[idx], reason[idx] = qc, good, why
    return Plan(flange, q_ideal, q_cmd, ok, reason, ctx)
