"""Path refinement of a rewrite: linear and circular moves that become joint moves.

A MoveL or MoveC written as MoveAbsJ runs joint-interpolated, so its TCP leaves the
line or arc. `refine_paths` finds where each such move starts, adds intermediate
points until the predicted path stays within the tolerance (`path.refine`), follows
the direction each joint moves along the refined path (a joint with play) and solves
again the points and destinations whose direction changed. A move whose start is not
known before run time, or whose path cannot be kept in tolerance, goes back to a
filtered robtarget. It takes a `ProgramPlan` and returns a `PathRefinement`; nothing
here edits text.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from rapidfix import chunks
from rapidfix.error_model import Context, ErrorModel
from rapidfix.kinematics import RobotModel
from rapidfix.postprocess.conditions import arrival_directions
from rapidfix.postprocess.path import (
    Curves,
    Refinement,
    chain_span,
    line_deviation_bound,
    refine,
    wrist_levers,
)
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import Plan, compensate_joints, plan_nearest
from rapidfix.postprocess.planning import ProgramPlan
from rapidfix.rapid import STOPS_SHORT, MotionInstruction, Program

#: why a MoveL/MoveC kept its instruction when its start is not known
START_UNKNOWN = "start not known before run time"
#: why a MoveL/MoveC kept its instruction when it starts off its path (with the tolerance)
OFF_START = ("it starts where the MoveAbsJ before it leaves the robot, farther from its "
             "path than the path tolerance")


#: why a synchronized MoveL/MoveC kept its instruction where its path needs points
SYNCHRONIZED = ("a synchronized move (\\ID) whose path would need intermediate points, "
                "which the other tasks of its MultiMove program would have to take too")


@dataclass(frozen=True)
class PathRefinement:
    """The refined paths of the moves that become joint moves, and what they changed.

    `solved` is the targets' plan after the directions along the paths (destinations
    whose joints arrive the other way solved again); `mode` each compensated site's
    emission mode after refinement and `filtered_reason` why a site went back to a
    filtered robtarget. Per refined segment, in order: `sites` (site indices); `points`
    the intermediate points (`path.Refinement`, None when nothing was refined), their
    segment's `frames` and run conditions `context`, and `direction` the arrival
    direction of every point where directions are followed (None otherwise).
    """

    solved: Plan
    mode: dict[int, str]
    filtered_reason: dict[int, str]
    sites: list[int]
    points: Refinement | None = None
    frames: Placement | None = None
    context: Context | None = None
    direction: np.ndarray | None = None

    @cached_property
    def _kept(self) -> np.ndarray:
        """Per segment: whether its move is still emitted as a joint move (worked out
        once: `mode` is not changed after refinement)."""
        return np.array([self.mode.get(i) == "joint" for i in self.sites], dtype=bool)

    def points_added(self) -> int:
        """How many intermediate points the rewrite inserts."""
        if self.points is None:
            return 0
        return int(np.isin(self.points.seg, np.flatnonzero(self._kept)).sum())

    def worst_path_mm(self) -> float | None:
        """The largest predicted deviation (mm) from a line or arc of the moves kept as
        joint moves; None when there are none."""
        if self.points is None:
            return None
        keep = self._kept
        return float(self.points.deviation[keep].max()) if keep.any() else None

    def intermediates(self) -> dict[int, tuple[int, int]]:
        """Refined site -> (first, end) index of its intermediate points in `points`."""
        inter: dict[int, tuple[int, int]] = {}
        if self.points is not None and self.points.seg.size:
            bounds = np.searchsorted(self.points.seg, np.arange(len(self.sites) + 1))
            for k, site_index in enumerate(self.sites):
                lo, hi = int(bounds[k]), int(bounds[k + 1])
                if hi > lo and self.mode.get(site_index) == "joint":
                    inter[site_index] = (lo, hi)
        return inter


class _TakeUp:
    """The direction of each joint along a path whose joints reverse at its start.

    A reversing joint with play stands still until its motor has taken the play up;
    between the two directions its direction is the fraction taken up, so the path
    check sees the joint stand (not jump) at the start of the move.
    """

    def __init__(self, play: np.ndarray, context: Context, from_row: np.ndarray,
                 q_start: np.ndarray, absj_rows: np.ndarray) -> None:
        self.play = play
        self.active = context.last_direction is not None and bool(np.any(play > 0))
        self.start_dir = np.zeros((len(from_row), 6))
        if context.last_direction is not None:
            self.start_dir = np.asarray(context.last_direction, dtype=float)[from_row].copy()
            # a MoveAbsJ start: its direction is not followed here
            self.start_dir[absj_rows] = 0.0
        self.q_start = q_start

    def __call__(self, ctx: Context, seg: np.ndarray, q: np.ndarray) -> Context:
        if not self.active or ctx.last_direction is None:
            return ctx
        travel = np.abs(q - self.q_start[seg])
        frac = np.clip(travel / np.where(self.play > 0, self.play, 1.0), 0.0, 1.0)
        frac = np.where(self.play > 0, frac, 1.0)
        start = self.start_dir[seg]
        return replace(ctx, last_direction=start + (ctx.last_direction - start) * frac)


def _start_state(motion: MotionInstruction | None) -> tuple | None:
    """(q_ideal, q_cmd) where the robot is after `motion` (not a site), if known before
    run time."""
    if motion is None:
        return None
    if motion.target_kind == "jointtarget" and motion.name.lower() == "moveabsj":
        data = motion.target.data if motion.target is not None else None
        if data is not None and motion.target.static:
            q = np.radians(np.asarray(data.robax, dtype=float))
            return q, q
    return None


def refine_paths(program: Program, model: ErrorModel, robot: RobotModel,
                 planned: ProgramPlan, path_tolerance_mm: float, emit: str) -> PathRefinement:
    """Start of every linear/circular move made a joint move, and intermediate points
    within `path_tolerance_mm`; nothing to refine unless `emit` is 'jointtargets'."""
    mode, filtered_reason = dict(planned.mode), {}
    if emit != "jointtargets":
        return PathRefinement(planned.solved, mode, filtered_reason, [])
    sites, motions = planned.sites, program.motions
    filtered_reason.update((i, sites[i].kept) for i, m in mode.items()
                           if m == "filtered" and sites[i].kept is not None)
    n = len(sites)
    t, p = planned.targets, planned.solved
    site_motion = planned.conditions.site_motion
    site_of_motion = np.full(len(motions) + 1, -1, dtype=np.int64)  # [-1]: no motion
    site_of_motion[site_motion] = np.arange(n)
    compensated = np.zeros(n, dtype=bool)
    compensated[np.fromiter(mode, dtype=np.int64, count=len(mode))] = True
    # each site's first and last target row (-1: none); rows come in site order
    owner = np.asarray(t.site, dtype=np.int64)
    first_of = np.flatnonzero(np.diff(owner, prepend=-1))
    first_row = np.full(n, -1, dtype=np.int64)
    last_row = np.full(n, -1, dtype=np.int64)
    first_row[owner[first_of]] = first_of
    last_row[owner[first_of]] = np.append(first_of[1:], owner.size) - 1
    kind = planned.conditions.site_kind
    joint = np.zeros(n, dtype=bool)
    joint[[i for i, m in mode.items() if m == "joint"]] = True
    moves = np.flatnonzero(joint & ((kind == "L") | (kind == "C")))
    previous = planned.conditions.predecessors()[site_motion[moves]]
    after = site_of_motion[previous]  # the site of the motion before, or -1
    # a move after another compensated site starts where that one ends (unless it may
    # stop short, a search, or be displaced); one after an instruction that is not a site
    # (a MoveAbsJ) may start at its joints
    ends_there = compensated & ~planned.conditions.displaced  # (displaced: elsewhere)
    others = np.flatnonzero(kind == "X").tolist()  # few: a search is one of them
    ends_there[[i for i in others if sites[i].motion.name.lower() in STOPS_SHORT]] = False
    keep = (after >= 0) & ends_there[np.maximum(after, 0)]
    start_rows = np.where(keep, last_row[np.maximum(after, 0)], -1)
    starts: dict[int, np.ndarray] = {}  # site -> the joints of the MoveAbsJ it follows
    for k in np.flatnonzero(after < 0).tolist():
        start = _start_state(motions[previous[k]] if previous[k] >= 0 else None)
        if start is not None:
            keep[k] = True
            starts[int(moves[k])] = start[0]
    for i in moves[~keep].tolist():
        mode[i] = "filtered"
        filtered_reason[i] = START_UNKNOWN
    seg_sites = moves[keep]
    segs = seg_sites.tolist()
    from_row = start_rows[keep]
    # segment -> the joints of the MoveAbsJ it follows (segments are in site order)
    at = np.searchsorted(seg_sites, np.fromiter(starts, dtype=np.int64, count=len(starts)))
    absj = {int(k): starts[i] for k, i in sorted(zip(at.tolist(), starts))}
    absj_rows = np.fromiter(absj, dtype=np.int64, count=len(absj))  # their segments
    if not segs:
        return PathRefinement(planned.solved, mode, filtered_reason, segs)
    to_row, via_row = last_row[seg_sites], first_row[seg_sites]
    circular = kind[seg_sites] == "C"
    q0i, q0c = p.q_ideal[from_row], p.q_cmd[from_row]
    start_flange = p.flange[from_row]  # the previous target's intended tool0 pose
    if absj:
        at = absj_rows
        q0i[at] = q0c[at] = np.array(list(absj.values()))
        start_flange[at] = robot.fk(q0i[at])
    frames = t.placement.take(to_row)
    start_tcp = frames.tcp(start_flange)
    curves = Curves(start_tcp, t.pose[to_row], t.pose[via_row, :3, 3], circular)
    # points between two targets run in the destination's conditions: its payload,
    # and each joint moving the way it moves into the destination
    seg_ctx = p.context.take(to_row)
    take_up = _TakeUp(model.play(), p.context, from_row, q0c, absj_rows)

    def predict(seg: np.ndarray, q: np.ndarray) -> np.ndarray:
        flange = model.actual_flange(robot, q, take_up(seg_ctx.take(seg), seg, q))
        return frames.take(seg).tcp_positions(flange)

    def solve(seg: np.ndarray, poses: np.ndarray, seed: np.ndarray) -> tuple:
        sub: Plan = plan_nearest(model, robot, poses, seed, frames.take(seg),
                                 seg_ctx.take(seg))
        return sub.q_ideal, sub.q_cmd, sub.ok

    bound = _line_bounds(robot, p, start_flange, to_row, q0c, frames)
    bound[circular] = np.inf
    # a segment whose robot starts off its path farther than the tolerance (after a
    # MoveAbsJ, whose joints are written as they are: no other start is off) cannot be
    # closed by any number of points: given up before it is split
    off = np.zeros(len(segs), dtype=bool)
    if absj:
        rows = absj_rows
        off[rows] = curves.distance(rows, predict(rows, q0c[rows])) > path_tolerance_mm
    unsplit = planned.conditions.synchronized[seg_sites]
    points = refine(curves, (q0i, p.q_ideal[to_row]), (q0c, p.q_cmd[to_row]),
                    path_tolerance_mm, predict, solve, bound, given_up=off,
                    unsplit=unsplit if unsplit.any() else None)
    for k in np.flatnonzero(points.failed):
        mode[segs[k]] = "filtered"
        filtered_reason[segs[k]] = (
            "its arc is degenerate" if curves.degenerate[k] else
            f"{OFF_START} {path_tolerance_mm:g} mm" if off[k] else
            SYNCHRONIZED if unsplit[k] else
            "no intermediate points keep its path within the path tolerance "
            f"{path_tolerance_mm:g} mm")
    solved, direction = p, None
    if seg_ctx.last_direction is not None and points.seg.size:
        solved, direction = _redirect(model, robot, planned, points, seg_ctx, q0c, to_row,
                                      take_up.start_dir)
    return PathRefinement(solved, mode, filtered_reason, segs, points, frames, seg_ctx,
                          direction)


def _redirect(model: ErrorModel, robot: RobotModel, planned: ProgramPlan, r: Refinement,
              seg_context: Context, q0c: np.ndarray, to_row: np.ndarray,
              start_dir: np.ndarray) -> tuple[Plan, np.ndarray]:
    """Directions along refined paths, and the points whose direction changed solved again.

    A joint need not move monotonically along a line: between intermediate points
    it moves the way the points say, and it arrives at the destination from the
    last of them. The points were solved with the destination's direction; those
    (and destinations) whose joints arrive the other way are compensated again
    (`r.q_cmd` in place). Returns the targets' plan after that and the arrival
    direction of every intermediate point.
    """
    p = planned.solved
    order = np.lexsort((r.s, r.seg))
    seg, q_inter = r.seg[order], r.q_cmd[order]
    m = to_row.shape[0]
    # one chain per segment: start, intermediate points, destination
    first = np.searchsorted(seg, np.arange(m))
    count = np.bincount(seg, minlength=m)
    pts = np.concatenate([q0c, q_inter, p.q_cmd[to_row]])
    start_id, inter_id = np.arange(m), m + np.arange(seg.shape[0])
    dest_id = m + seg.shape[0] + np.arange(m)
    prev = np.full(pts.shape[0], -1, dtype=np.int64)
    prev[inter_id] = np.where(np.arange(seg.shape[0]) == first[seg], start_id[seg],
                              inter_id - 1)
    prev[dest_id] = np.where(count > 0, m + first + count - 1, start_id)
    initial = np.zeros((pts.shape[0], 6))
    initial[:m] = start_dir  # where each path starts, joints point as they arrived there
    direction = arrival_directions(pts, prev, initial)
    dest_dir = np.asarray(p.context.last_direction, dtype=float)
    inter_dir, new_dest = direction[inter_id], direction[dest_id]
    forced = planned.conditions.forced
    if forced is not None:  # destinations behind an approach point arrive as planned
        new_dest = np.where(forced[to_row] != 0.0, forced[to_row], new_dest)
    used = seg_context.last_direction[seg]
    redo = np.flatnonzero((inter_dir != used).any(axis=1))
    if redo.size:
        ctx = replace(seg_context.take(seg[redo]), last_direction=inter_dir[redo])
        qc, good, _ = compensate_joints(model, robot, r.q_ideal[order][redo], ctx)
        rows = order[redo]
        r.q_cmd[rows] = np.where(good[:, None], qc, r.q_cmd[rows])
    inter_direction = np.empty_like(inter_dir)
    inter_direction[order] = inter_dir
    changed = np.flatnonzero((new_dest != dest_dir[to_row]).any(axis=1)
                             & (count > 0) & p.ok[to_row])
    if changed.size:
        rows = to_row[changed]
        all_dir = dest_dir.copy()
        all_dir[rows] = new_dest[changed]
        context = replace(p.context, last_direction=all_dir)
        qc, good, _ = compensate_joints(model, robot, p.q_ideal[rows], context.take(rows))
        q_cmd = p.q_cmd.copy()  # the program plan keeps its own joints
        q_cmd[rows] = np.where(good[:, None], qc, q_cmd[rows])
        p = replace(p, q_cmd=q_cmd, context=context)
    return p, inter_direction


def _line_bounds(robot: RobotModel, p: Plan, start_flange: np.ndarray, to_row: np.ndarray,
                 q0c: np.ndarray, frames: Placement) -> np.ndarray:
    """An upper bound of each segment's bow as a line (`path.line_deviation_bound`),
    inf where the robot does not carry the tool: a CAM program's short moves are
    settled by it without sampling."""
    span = chain_span(robot.axis_points)
    levers = wrist_levers(robot.axis_dirs, robot.axis_points, robot.home)
    bound = np.empty(to_row.shape[0])
    for start in range(0, to_row.shape[0], chunks.LINE_BOUND):  # a segment's bound is its own
        part = slice(start, start + chunks.LINE_BOUND)
        rows = to_row[part]
        bound[part] = line_deviation_bound(span, levers, start_flange[part], p.flange[rows],
                                           frames.tool[part, :3, 3], p.q_cmd[rows] - q0c[part])
    bound[frames.stationary] = np.inf
    return bound


__all__ = ["START_UNKNOWN", "PathRefinement", "refine_paths"]
