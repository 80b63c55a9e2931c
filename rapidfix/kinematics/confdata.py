"""ABB confdata [cf1, cf4, cf6, cfx] and choosing a solution: by confdata or nearest.

cf1, cf4, cf6 are the quadrants floor(θ / 90°) of axes 1, 4 and 6 (−1 for
[−90°, 0°), 1 for [90°, 180°), …). cfx (0–7) = 4·(wrist centre behind axis 1)
+ 2·(wrist centre behind the lower arm, i.e. on the far side of the line through
axes 2 and 3 from where it is at θ = 0) + (θ5 < 0).
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from rapidfix.compiled import load_kernel, numpy_only
from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics import conf_columns
from rapidfix.kinematics.batches import as_joint_batch
from rapidfix.kinematics.ik_analytic import wrist_centre
from rapidfix.kinematics.ik_result import IKSolutions, IKStatus
from rapidfix.kinematics.screws import (
    forward_is_compiled,
    forward_switched_on,
    product_of_exponentials,
)

if TYPE_CHECKING:
    from rapidfix.kinematics.robot_model import RobotModel

QUADRANT = np.pi / 2
CONF_TOL = np.radians(0.01)
"""Angles (rad) this close to a quadrant boundary (or θ5 this close to 0) match both sides.

0.01°: programs store positions to 0.001 mm and quaternions to ~9 decimals, so a target
written with j4 = j6 = 0 comes back from IK off by up to ~1e-5° (more near the wrist
singularity) and may land on either side of the boundary. 0.01° is far above that
rounding and far below any pose a controller would tell apart by its confdata.
"""
CONF_TOL_MM = 0.01
"""Wrist-centre distances (mm) this close to the axis-1 or lower-arm side boundary match
both sides (the cfx bits 4 and 2), for the same reason as CONF_TOL."""


def conf_quantities(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Signed quantities (..., 6) behind confdata: θ1, θ4, θ6 (rad), wrist centre ahead of
    axis 1 (mm), wrist centre ahead of the lower arm line (mm), θ5 (rad). Inside
    `screws.compiled_forward` the wrist centre's distances come from the compiled kernel
    (`conf_compiled.wrist_sides_rows`), which `select_by_conf` uses too, or from its
    arithmetic in numpy columns (`conf_columns`) where numba is not installed."""
    q = np.asarray(q, dtype=float)
    flat = q.reshape(-1, 6)
    finite = np.all(np.isfinite(flat), axis=1)
    safe = np.where(finite[:, None], flat, 0.0)
    w, r, c0, fwd0, side_sign = _arm_frame(model)
    switched = flat.shape[0] >= _COMPILED_FROM and forward_switched_on()
    kernel = load_kernel("rapidfix.kinematics.conf_compiled") \
        if switched and forward_is_compiled() else None
    if switched:  # the same quantities to rounding (~1e-13 mm), in one pass
        if kernel is None:
            sides = conf_columns.wrist_sides(safe, w, r, c0, fwd0, side_sign)
        else:
            sides = np.empty((flat.shape[0], 2))
            kernel.wrist_sides_rows(safe, w, r, c0, fwd0, side_sign, sides)
        out = np.stack([safe[:, 0], safe[:, 3], safe[:, 5], sides[:, 0], sides[:, 1],
                        safe[:, 4]], axis=1)
        out[~finite] = np.nan
        return out.reshape((*q.shape[:-1], 6))
    # only the arm's three axes place the wrist centre
    arm3, prefix = product_of_exponentials(w[:3], r[:3], np.eye(4), safe[:, :3])
    R, t = arm3[:, :3, :3], arm3[:, :3, 3]  # e^{S1θ1} e^{S2θ2} e^{S3θ3}
    c = np.einsum("nij,j->ni", R, c0) + t
    # Ahead of axis 1: along the arm plane's forward direction, turned by θ1.
    R1 = prefix[:, 1, :3, :3]
    ahead1 = np.einsum("ni,ni->n", c - r[0], np.einsum("nij,j->ni", R1, fwd0))
    # Ahead of the lower arm: side of the line axis 2 → axis 3 (in the arm plane).
    a2 = np.einsum("nij,j->ni", prefix[:, 1, :3, :3], r[1]) + prefix[:, 1, :3, 3]
    a3 = np.einsum("nij,j->ni", prefix[:, 2, :3, :3], r[2]) + prefix[:, 2, :3, 3]
    w2 = np.einsum("nij,j->ni", prefix[:, 1, :3, :3], w[1])
    arm = a3 - a2
    arm_len = np.linalg.norm(arm, axis=1)
    side = np.einsum("ni,ni->n", np.cross(arm, c - a2), w2) / arm_len
    side *= side_sign
    out = np.stack([safe[:, 0], safe[:, 3], safe[:, 5], ahead1, side, safe[:, 4]], axis=1)
    out[~finite] = np.nan
    return out.reshape((*q.shape[:-1], 6))


def _arm_frame(model: RobotModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                            float]:
    """What the wrist centre's distances are measured with: the axis directions and
    points (n, 3), the wrist centre at home, the arm plane's forward direction at home
    and the sign that makes the lower-arm side positive at home."""
    w = np.ascontiguousarray(model.axis_dirs, dtype=float)
    r = np.ascontiguousarray(model.axis_points, dtype=float)
    c0 = np.asarray(wrist_centre(model.nominal), dtype=float)
    fwd0 = (c0 - r[0]) - ((c0 - r[0]) @ w[0]) * w[0]
    fwd0 /= np.linalg.norm(fwd0)
    side0 = np.cross(r[2] - r[1], c0 - r[1]) @ w[1]
    return w, r, c0, fwd0, float(np.sign(side0)) if side0 != 0 else 1.0

def confdata(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """ABB confdata (N, 4) int [cf1, cf4, cf6, cfx] of joints q (N, 6) rad ((6,) gives (4,))."""
    qb, single = as_joint_batch(q)
    if not np.all(np.isfinite(qb)):
        raise KinematicsError("joint values contain NaN or infinite values")
    k = conf_quantities(model, qb)
    quads = np.floor(k[:, :3] / QUADRANT).astype(int)
    cfx = 4 * (k[:, 3] < 0) + 2 * (k[:, 4] < 0) + (k[:, 5] < 0)
    out = np.concatenate([quads, cfx[:, None].astype(int)], axis=1)
    return out[0] if single else out


def slot_confdata(model: RobotModel, sols: IKSolutions) -> np.ndarray:
    """confdata (N, S, 4) int of every valid slot of `sols` (0 in the others).

    The geometry behind cfx is worked out once per branch, not per slot: a slot differs
    from its branch by whole turns, which move no part of the arm; cf1, cf4, cf6 and the
    θ5 bit are read from the slot's own angles."""
    valid = sols.valid
    n, slots = valid.shape
    found = np.zeros((n, slots, 4), dtype=int)
    if not valid.any():
        return found
    k = conf_quantities(model, sols.base_q)  # (N, 8, 6)
    per_branch = slots // 8
    q = sols.q[valid]
    ahead = np.repeat(k[..., 3], per_branch, axis=1)[valid]
    side = np.repeat(k[..., 4], per_branch, axis=1)[valid]
    found[valid, :3] = np.floor(q[:, [0, 3, 5]] / QUADRANT).astype(int)
    found[valid, 3] = 4 * (ahead < 0) + 2 * (side < 0) + (q[:, 4] < 0)
    return found


def conf_matches(
    model: RobotModel, q: np.ndarray, conf: np.ndarray, tol: float = CONF_TOL,
    tol_mm: float = CONF_TOL_MM,
) -> np.ndarray:
    """(...,) mask: joints q (..., 6) have confdata `conf` (..., 4); values within `tol`
    (rad) or `tol_mm` of a boundary match both sides."""
    return _quantities_match(conf_quantities(model, q), conf, tol, tol_mm)


def _quantities_match(k: np.ndarray, conf: np.ndarray, tol: float, tol_mm: float) -> np.ndarray:
    """`conf_matches` on the quantities `conf_quantities` gave (so that one evaluation of
    the geometry serves several tolerances)."""
    conf = np.asarray(conf)
    with np.errstate(invalid="ignore"):
        ok = np.ones(k.shape[:-1], dtype=bool)
        for j in range(3):
            lo = np.floor((k[..., j] - tol) / QUADRANT)
            hi = np.floor((k[..., j] + tol) / QUADRANT)
            ok &= (lo <= conf[..., j]) & (conf[..., j] <= hi)
        cfx = conf[..., 3]
        for bit, j, t in ((4, 3, tol_mm), (2, 4, tol_mm), (1, 5, tol)):
            wants_neg = (cfx & bit) != 0
            value = k[..., j]
            ok &= np.where(wants_neg, value < t, value > -t)
    return ok & np.all(np.isfinite(k), axis=-1)


def _pick(
    sols: IKSolutions, chosen: np.ndarray, found: np.ndarray, miss: int
) -> tuple[np.ndarray, np.ndarray]:
    n = len(sols)
    rows = np.arange(n)
    q = np.where(found[:, None], sols.q[rows, chosen], np.nan)
    status = np.where(found, IKStatus.OK, miss).astype(np.int8)
    status[found & sols.singular[rows, chosen]] = IKStatus.WRIST_SINGULAR
    failed = ~sols.valid.any(axis=1)
    status[failed] = sols.status[failed]
    return q, status


def select_by_conf(
    model: RobotModel, sols: IKSolutions, conf: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The valid solution whose confdata is `conf` (N, 4) or (4,): (q (N, 6), status (N,)).

    Poses with no such solution get NaN joints and status NO_MATCHING_CONF (or the
    pose's own status when it has no valid solution at all). Of several matching
    slots the first in slot order is taken.

    Works on the compact form: the whole-turn variant of each axis is chosen per
    branch by the quadrant (axes 1, 4, 6) and sign (axis 5) tests alone, and the
    wrist-centre geometry is evaluated on that one joint vector per branch, never
    on every ±360° combination.
    """
    n = len(sols)
    conf = np.asarray(conf, dtype=int)
    if conf.shape not in ((4,), (n, 4)):
        raise KinematicsError(f"confdata must have shape (4,) or ({n}, 4), got {conf.shape}")
    conf = np.broadcast_to(conf, (n, 4))
    kernel = load_kernel("rapidfix.kinematics.conf_compiled") if sols.backend == "numba" \
        and n >= _COMPILED_FROM and not numpy_only() else None
    if kernel is not None:
        return _select_compiled(kernel, model, sols, conf)
    first, ambiguous = _turns_on_conf(sols, conf)
    candidate = np.all(first >= 0, axis=2)
    rows, branches = np.nonzero(candidate)
    q_cand = sols.base_q[rows, branches] + 2.0 * np.pi * first[rows, branches]
    k = conf_quantities(model, q_cand)  # once, for the rounded and the exact test
    match = np.zeros((n, 8), dtype=bool)
    match[rows, branches] = _quantities_match(k, conf[rows], CONF_TOL, CONF_TOL_MM)
    found = match.any(axis=1)
    chosen = _prefer_exact(match, rows, branches, k, conf[rows])
    q = np.full((n, 6), np.nan)
    q[found] = sols.base_q[found, chosen[found]] + 2.0 * np.pi * first[found, chosen[found]]
    status = np.where(found, IKStatus.OK, IKStatus.NO_MATCHING_CONF).astype(np.int8)
    status[found & sols.base_singular[np.arange(n), chosen]] = IKStatus.WRIST_SINGULAR
    any_valid = np.any(sols.reachable & np.all(sols.turn_ok != 0, axis=2), axis=1)
    status[~any_valid] = sols.status[~any_valid]
    # A branch whose first candidate fails the geometry test but has further
    # candidates (an axis 2, 3 or 5 with more than one turn in range) is settled
    # slot by slot; with the usual ranges this never happens.
    before = np.where(found, chosen, 8)[:, None] > np.arange(8)
    redo = np.flatnonzero(np.any(ambiguous & candidate & ~match & before, axis=1))
    if redo.size:
        q[redo], status[redo] = _select_expanded(model, _take(sols, redo), conf[redo])
    return q, status


#: the boundary tolerance of an exact match (rad or mm), preferred over a rounded one
EXACT_TOL = 1e-9
#: batches smaller than this stay in numpy (a kernel call has a fixed cost)
_COMPILED_FROM = 64


def _select_compiled(kernel: ModuleType, model: RobotModel, sols: IKSolutions,
                     conf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`select_by_conf` by the compiled kernel (`conf_compiled`), where the IK's closed
    form was compiled too: the same choice, one pass over the poses."""
    n = len(sols)
    w, r, c0, fwd0, side_sign = _arm_frame(model)
    q = np.empty((n, 6))
    found = np.empty(n, dtype=bool)
    chosen = np.empty(n, dtype=np.int64)
    any_valid = np.empty(n, dtype=bool)
    redo = np.empty(n, dtype=bool)
    kernel.select_on_conf(
        np.ascontiguousarray(sols.base_q, dtype=float), np.ascontiguousarray(sols.reachable),
        np.ascontiguousarray(sols.turn_ok), np.asarray(sols.counts, dtype=np.int64),
        np.ascontiguousarray(conf, dtype=np.int64), w, r, c0, fwd0, side_sign, CONF_TOL,
        CONF_TOL_MM, EXACT_TOL,
        q, found, chosen, any_valid, redo)
    status = np.where(found, IKStatus.OK, IKStatus.NO_MATCHING_CONF).astype(np.int8)
    status[found & sols.base_singular[np.arange(n), chosen]] = IKStatus.WRIST_SINGULAR
    status[~any_valid] = sols.status[~any_valid]
    again = np.flatnonzero(redo)
    if again.size:
        q[again], status[again] = _select_expanded(model, _take(sols, again), conf[again])
    return q, status


def _prefer_exact(match: np.ndarray, rows: np.ndarray, branches: np.ndarray,
                  quantities: np.ndarray, conf: np.ndarray) -> np.ndarray:
    """Per pose the first matching slot, one that matches exactly (not only within the
    rounding tolerance of a boundary) if there is one; `quantities` are the candidates'
    `conf_quantities`."""
    exact = np.zeros_like(match)
    exact[rows, branches] = _quantities_match(quantities, conf, EXACT_TOL, EXACT_TOL)
    exact &= match
    return np.where(exact.any(axis=1), np.argmax(exact, axis=1), np.argmax(match, axis=1))


def _turns_on_conf(sols: IKSolutions, conf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per branch and axis, the first whole turn (N, 8, 6) whose angle is within the limits
    and passes the confdata's quadrant / θ5-sign test (-1: none), and (N, 8) whether
    an axis of the branch has more than one such turn."""
    n = len(sols)
    base, allowed = _by_axis(sols)
    first = np.full((6, n, 8), -1, dtype=np.int64)
    several = np.zeros((n, 8), dtype=bool)
    quadrant_of = {0: 0, 3: 1, 5: 2}  # axis -> confdata entry
    wants_neg = ((conf[:, 3] & 1) != 0)[:, None]
    with np.errstate(invalid="ignore"):
        for j, count in enumerate(sols.counts):
            seen = np.zeros((n, 8), dtype=bool)
            for k in range(count):
                angle = base[j] + 2.0 * np.pi * k
                ok = ((allowed[j] >> k) & 1).astype(bool) & sols.reachable
                if j in quadrant_of:
                    want = conf[:, quadrant_of[j], None]
                    lo = np.floor((angle - CONF_TOL) / QUADRANT)
                    hi = np.floor((angle + CONF_TOL) / QUADRANT)
                    ok &= (lo <= want) & (want <= hi)
                elif j == 4:
                    ok &= np.where(wants_neg, angle < CONF_TOL, angle > -CONF_TOL)
                first[j] = np.where(ok & ~seen, k, first[j])
                several |= ok & seen
                seen |= ok
    return np.moveaxis(first, 0, 2), several


def _take(sols: IKSolutions, rows: np.ndarray) -> IKSolutions:
    """The solutions of a subset of the poses."""
    return IKSolutions(
        base_q=sols.base_q[rows],
        reachable=sols.reachable[rows],
        turn_ok=sols.turn_ok[rows],
        base_singular=sols.base_singular[rows],
        status=sols.status[rows],
        counts=sols.counts,
        backend=sols.backend,
    )


def _select_expanded(
    model: RobotModel, sols: IKSolutions, conf: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """`select_by_conf` slot by slot over the expanded solutions (for the rare poses
    the compact choice cannot settle)."""
    match = sols.valid & conf_matches(model, sols.q, conf[:, None, :])
    found = match.any(axis=1)
    chosen = np.argmax(match, axis=1)
    return _pick(sols, chosen, found, IKStatus.NO_MATCHING_CONF)


def select_nearest(sols: IKSolutions, q_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The valid solution nearest q_prev (N, 6) or (6,) in joint space (Euclidean, rad).

    Of equally near slots the first in slot order is taken. Works on the compact
    form: the distance is a sum over the axes, so each branch's nearest slot takes
    each axis's nearest whole-turn variant, and only the eight branches are compared.
    """
    n = len(sols)
    qp, _ = as_joint_batch(q_prev)
    qp = np.broadcast_to(qp, (n, 6))
    turns, gap = _nearest_turns(sols, qp)
    usable = sols.reachable & np.all(turns >= 0, axis=2)
    q8 = sols.base_q + 2.0 * np.pi * np.maximum(turns, 0)
    with np.errstate(invalid="ignore"):
        dist = np.sum((q8 - qp[:, None, :]) ** 2, axis=2)
    dist = np.where(usable, dist, np.inf)
    chosen = np.argmin(dist, axis=1)
    found = usable.any(axis=1)
    rows = np.arange(n)
    q = np.where(found[:, None], q8[rows, chosen], np.nan)
    status = np.where(found, IKStatus.OK, IKStatus.UNREACHABLE).astype(np.int8)
    status[found & sols.base_singular[rows, chosen]] = IKStatus.WRIST_SINGULAR
    status[~found] = sols.status[~found]
    # Where another variant of an axis is as near to within rounding, or q_prev is not
    # finite, the sum's rounding decides: those poses are settled slot by slot.
    with np.errstate(invalid="ignore"):
        close = np.any(gap[rows, chosen] <= 1e-12 * (1.0 + dist[rows, chosen])[:, None], axis=1)
    redo = np.flatnonzero((found & close) | ~np.all(np.isfinite(qp), axis=1))
    if redo.size:
        q[redo], status[redo] = _nearest_expanded(_take(sols, redo), qp[redo])
    return q, status


def _nearest_turns(sols: IKSolutions, qp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per branch and axis, the whole turn (N, 8, 6) within the limits nearest qp (-1: none;
    the first of equals) and how much farther the runner-up is (squared, rad²; inf: none)."""
    n = len(sols)
    base, allowed = _by_axis(sols)
    best = np.full((6, n, 8), -1, dtype=np.int64)
    best_sq = np.full((6, n, 8), np.inf)
    second_sq = np.full((6, n, 8), np.inf)
    with np.errstate(invalid="ignore"):
        for j, count in enumerate(sols.counts):
            for k in range(count):
                d = base[j] + 2.0 * np.pi * k - qp[:, j, None]
                sq = d * d
                ok = ((allowed[j] >> k) & 1).astype(bool) & sols.reachable
                nearer = ok & (sq < best_sq[j])
                second_sq[j] = np.where(nearer, best_sq[j],
                                        np.where(ok, np.minimum(second_sq[j], sq), second_sq[j]))
                best[j] = np.where(nearer, k, best[j])
                best_sq[j] = np.where(nearer, sq, best_sq[j])
        gap = second_sq - best_sq
    return np.moveaxis(best, 0, 2), np.moveaxis(gap, 0, 2)


def _by_axis(sols: IKSolutions) -> tuple[np.ndarray, np.ndarray]:
    """Branch angles and turn masks axis-major, (6, N, 8): each axis's slice contiguous."""
    return (np.ascontiguousarray(np.moveaxis(sols.base_q, 2, 0)),
            np.ascontiguousarray(np.moveaxis(sols.turn_ok, 2, 0)))


def _nearest_expanded(sols: IKSolutions, qp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`select_nearest` slot by slot over the expanded solutions."""
    with np.errstate(invalid="ignore"):
        dist = np.sum((sols.q - qp[:, None, :]) ** 2, axis=2)
    dist = np.where(sols.valid, dist, np.inf)
    chosen = np.argmin(dist, axis=1)
    found = sols.valid.any(axis=1)
    return _pick(sols, chosen, found, IKStatus.UNREACHABLE)


def nearest_chain(sols: IKSolutions, q_start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The paper's rule for a sequence of targets: each solution nearest the one before.

    The solutions are already computed for the whole batch; only this choice walks
    the sequence, because each pick depends on the previous one. A target without
    a solution keeps the chain at the last solved joints.
    """
    n = len(sols)
    prev, _ = as_joint_batch(q_start)
    prev = prev[0]
    q = np.full((n, 6), np.nan)
    status = np.array(sols.status, dtype=np.int8, copy=True)
    for i in range(n):  # inherently sequential: one small vector operation per target
        valid = sols.valid[i]
        if not valid.any():
            continue
        dist = np.where(valid, np.sum((sols.q[i] - prev) ** 2, axis=1), np.inf)
        k = int(np.argmin(dist))
        q[i] = prev = sols.q[i, k]
        status[i] = IKStatus.WRIST_SINGULAR if sols.singular[i, k] else IKStatus.OK
    return q, status
