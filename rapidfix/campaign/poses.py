"""Which poses a measurement campaign measures: joint sweeps, calibration and
validation points, the ISO 9283 cube. Angles rad, lengths mm; every block is in
execution order and every random choice takes a seed.

- Sweeps follow the source paper: each joint over its range in 5° steps, three
  repeats, the others held at a pose chosen so that the ball stays far from the
  swept axis, above the floor, out of keep-out boxes and in the tracker's view
  (the longest such stretch of the range is kept); the virtual cell's hold
  (0, 0, 0, 0, 45, 0)° is kept unless another gives >10 % more range × radius.
- Calibration and validation points fill the work envelope: many random joint
  poses (Latin hypercube) are screened — joint limits, wrist singularity, floor,
  keep-outs, box, line of sight — and a farthest-point subset of the ball
  positions (and joint angles) is kept, so points spread through the box.
- The ISO 9283 cube: see `iso_cube`.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np
from scipy.stats import qmc

from rapidfix.campaign.envelope import Envelope
from rapidfix.campaign.sight import TrackerView
from rapidfix.campaign.timing import rated_joint_speed
from rapidfix.exceptions import RapidfixError
from rapidfix.kinematics import RobotModel
from rapidfix.sim import longest_run, plausible_poses

#: The held pose tried first for every sweep (the virtual cell's), deg.
DEFAULT_HOLD_DEG = (0.0, 0.0, 0.0, 0.0, 45.0, 0.0)
#: A ball this far (mm) from the swept axis or more draws a circle big enough.
GOOD_RADIUS_MM = 50.0
#: The default hold is kept while it scores at least this share of the best one.
HOLD_PREFERENCE = 0.9
WRIST_MIN_DEG = 15.0


@dataclass
class Block:
    """Measured poses of one kind, in execution order (see `rapidfix.campaign.pose_table`)."""

    set_name: str
    point_id: list[str]
    q: np.ndarray
    payload_kg: np.ndarray
    sweep_joint: np.ndarray  # 1..6, 0 outside sweeps
    repeat: np.ndarray  # 1.., 0 outside sweeps
    iso_pose: np.ndarray  # 1..5, 0 outside the ISO cube
    cycle: np.ndarray  # 1.., 0 outside the ISO cube

    def __len__(self) -> int:
        return len(self.point_id)


def ball_positions(robot: RobotModel, q: np.ndarray, smr_mm: np.ndarray) -> np.ndarray:
    """Nominal ball centres (N, 3) mm, base frame."""
    T = robot.fk(np.atleast_2d(q))
    return T[:, :3, :3] @ smr_mm + T[:, :3, 3]


def _allowed(robot: RobotModel, q: np.ndarray, smr: np.ndarray, envelope: Envelope,
             view: TrackerView | None, *, inside_box: bool) -> np.ndarray:
    ball = ball_positions(robot, q, smr)
    ok = plausible_poses(robot, q, smr) & robot.within_limits(q)
    ok &= envelope.contains(ball) if inside_box else envelope.safe(ball)
    if view is not None:
        ok &= view.visible(robot, q, smr)
    return ok


def _hold_candidates() -> np.ndarray:
    """Held poses (C, 6) deg, the default first."""
    grid = [list(DEFAULT_HOLD_DEG)]
    for j1, j2, j3, j5 in product((0.0, 90.0, -90.0, 180.0), (0.0, 30.0), (0.0, -30.0),
                                  (45.0, -45.0, 90.0)):
        grid.append([j1, j2, j3, 0.0, j5, 0.0])
    return np.array(grid)


def sweep_block(robot: RobotModel, smr_mm: np.ndarray, *, step_deg: float = 5.0,
                repeats: int = 3, joints: tuple[int, ...] = (1, 2, 3, 4, 5, 6),
                ranges_deg: dict[int, tuple[float, float]] | None = None,
                envelope: Envelope | None = None, view: TrackerView | None = None,
                payload_kg: float = 0.0, alternate: bool = False) -> Block:
    """Joint sweeps (joints 1-based). `alternate`: even repeats run downwards (backlash)."""
    smr = np.asarray(smr_mm, dtype=float)
    envelope = envelope or Envelope()
    limits = np.degrees(robot.limits)
    holds = _hold_candidates()
    ids: list[str] = []
    q_rows, joint_rows, rep_rows = [], [], []
    for j1 in joints:
        j = j1 - 1
        lo, hi = max(limits[j, 0], -180.0), min(limits[j, 1], 180.0)
        if ranges_deg and j1 in ranges_deg:
            lo, hi = max(lo, ranges_deg[j1][0]), min(hi, ranges_deg[j1][1])
        grid = np.arange(np.ceil(lo / step_deg - 1e-9), np.floor(hi / step_deg + 1e-9) + 1)
        grid = grid * step_deg
        if len(grid) < 3:
            raise RapidfixError(f"joint {j1}: its sweep range {lo:g}..{hi:g}° holds fewer "
                                f"than 3 steps of {step_deg:g}°")
        C, G = len(holds), len(grid)
        q = np.repeat(np.radians(holds), G, axis=0)
        q[:, j] = np.tile(np.radians(grid), C)
        ok = _allowed(robot, q, smr, envelope, view, inside_box=False).reshape(C, G)
        dirs, points = robot.joint_frames(q)
        ball = ball_positions(robot, q, smr)
        radius = np.linalg.norm(np.cross(ball - points[:, j], dirs[:, j]), axis=1).reshape(C, G)
        runs = np.array([longest_run(m) for m in ok])
        count = runs.sum(axis=1)
        r_min = np.where(runs, radius, np.inf).min(axis=1)
        score = count * np.minimum(1.0, np.where(count > 0, r_min, 0.0) / GOOD_RADIUS_MM)
        # the default hold (the virtual cell's) unless another is clearly better
        best = 0 if score[0] >= HOLD_PREFERENCE * score.max() else int(np.argmax(score))
        if count[best] < 3:
            raise RapidfixError(f"joint {j1}: no held pose gives 3 sweep steps with the ball "
                                "above the floor, out of the keep-out boxes and in view")
        sweep = q.reshape(C, G, 6)[best][runs[best]]
        for r in range(1, repeats + 1):
            order = sweep[::-1] if alternate and r % 2 == 0 else sweep
            q_rows.append(order)
            joint_rows.append(np.full(len(order), j1))
            rep_rows.append(np.full(len(order), r))
            ids += [f"S{j1}-{r}-{k + 1:03d}" for k in range(len(order))]
    n = len(ids)
    return Block("sweep", ids, np.vstack(q_rows), np.full(n, float(payload_kg)),
                 np.concatenate(joint_rows), np.concatenate(rep_rows), np.zeros(n, int),
                 np.zeros(n, int))


def _farthest_points(features: np.ndarray, n: int, start: int) -> np.ndarray:
    """Indices of `n` rows picked greedily, each farthest from those already picked."""
    chosen = [start]
    dist = np.linalg.norm(features - features[start], axis=1)
    for _ in range(n - 1):
        k = int(np.argmax(dist))
        chosen.append(k)
        dist = np.minimum(dist, np.linalg.norm(features - features[k], axis=1))
    return np.array(chosen)


def quick_tour(robot: RobotModel, q: np.ndarray, start: np.ndarray) -> np.ndarray:
    """An order of poses (N, 6) that keeps moves short: nearest next pose by joint time."""
    speed = rated_joint_speed(robot)
    left = np.ones(len(q), dtype=bool)
    order = []
    here = np.asarray(start, dtype=float)
    for _ in range(len(q)):
        cost = np.max(np.abs(q - here) / speed, axis=1)
        k = int(np.argmin(np.where(left, cost, np.inf)))
        order.append(k)
        left[k] = False
        here = q[k]
    return np.array(order, dtype=int)


def point_blocks(robot: RobotModel, smr_mm: np.ndarray, n_calibration: int,
                 n_validation: int, *, seed: int, envelope: Envelope | None = None,
                 view: TrackerView | None = None, payloads: tuple[float, ...] = (0.0,),
                 wrist_min_deg: float = WRIST_MIN_DEG,
                 start_q: np.ndarray | None = None) -> tuple[Block, Block]:
    """Calibration and validation points spread through the envelope (see module doc).

    Payloads are dealt out in turn (each payload gets points all over the envelope);
    points run grouped by payload, in the order given, each group in a short tour.
    """
    smr = np.asarray(smr_mm, dtype=float)
    envelope = envelope or Envelope()
    n = n_calibration + n_validation
    box = robot.limits.copy()
    box[[3, 5]] = np.clip(box[[3, 5]], -np.pi, np.pi)
    sampler = qmc.LatinHypercube(d=6, seed=seed)
    pool, total = [], 0
    for _ in range(40):
        q = qmc.scale(sampler.random(4000), box[:, 0], box[:, 1])
        ok = _allowed(robot, q, smr, envelope, view, inside_box=True)
        ok &= np.abs(q[:, 4]) >= np.radians(wrist_min_deg)
        pool.append(q[ok])
        total += int(ok.sum())
        if total >= 20 * n:
            break
    q_pool = np.vstack(pool)
    if len(q_pool) < n:
        raise RapidfixError(f"only {len(q_pool)} poses found for {n} calibration and "
                            "validation points: widen the box, or move the keep-out boxes, "
                            "floor or tracker")
    ball = ball_positions(robot, q_pool, smr)
    features = np.hstack([ball, 300.0 * q_pool])  # 300 mm per radian: spread the joints too
    rng = np.random.default_rng(seed)
    picked = _farthest_points(features, n, int(rng.integers(len(q_pool))))
    cal, val = picked[0::2][:n_calibration], picked[1::2][:n_validation]
    if len(cal) < n_calibration:  # more calibration than validation points
        rest = np.setdiff1d(picked, np.concatenate([cal, val]))
        cal = np.concatenate([cal, rest[:n_calibration - len(cal)]])
    elif len(val) < n_validation:
        rest = np.setdiff1d(picked, np.concatenate([cal, val]))
        val = np.concatenate([val, rest[:n_validation - len(val)]])
    start = np.radians(DEFAULT_HOLD_DEG) if start_q is None else start_q
    blocks = []
    for name, prefix, rows in (("calibration", "C", cal), ("validation", "V", val)):
        q = q_pool[rows]
        pay = np.asarray(payloads, dtype=float)[np.arange(len(rows)) % len(payloads)]
        order = []
        here = start
        for p in payloads:
            members = np.flatnonzero(pay == p)
            if len(members):
                tour = members[quick_tour(robot, q[members], here)]
                order.append(tour)
                here = q[tour[-1]]
        order_a = np.concatenate(order)
        start = q[order_a[-1]]
        m = len(rows)
        blocks.append(Block(name, [f"{prefix}{i + 1:03d}" for i in range(m)], q[order_a],
                            pay[order_a], np.zeros(m, int), np.zeros(m, int), np.zeros(m, int),
                            np.zeros(m, int)))
    return blocks[0], blocks[1]


# ----------------------------------------------------------------------------- ISO 9283

#: ISO 9283:1998, 6.2.3 / 7.2.1: P2–P5 lie on the diagonals of the test plane at
#: 10 % of the diagonal's length from its ends; the cycle visits P1, P5, P4, P3, P2.
ISO_CORNER_FRACTION = 0.10
ISO_CYCLE_ORDER = (1, 5, 4, 3, 2)
ISO_DEFAULT_CYCLES = 30


@dataclass(frozen=True)
class IsoCube:
    """The cube (centre, side, mm, edges along `axes` (3, 3) columns, base frame), the
    five poses' ball positions (5, 3) (P1..P5), the flange orientation `R` (3, 3) and the
    joints (5, 6) rad and confdata (5, 4) the nominal robot reaches them with."""

    centre_mm: np.ndarray
    side_mm: float
    axes: np.ndarray
    points_mm: np.ndarray
    R: np.ndarray
    q: np.ndarray
    conf: np.ndarray


def iso_points(centre: np.ndarray, side: float, axes: np.ndarray) -> np.ndarray:
    """P1..P5 (5, 3) on the diagonal plane C1-C2-C7-C8 of a cube (ISO 9283 fig. 4-5).

    The plane holds the cube's edge at (+x, −z) and the opposite edge at (−x, +z),
    both along y; P1 is the centre, P2 and P4 (P3 and P5) the ends of one diagonal
    pulled in by 10 % of its length.
    """
    a = side / 2.0
    corners_local = np.array([[a, -a, -a], [a, a, -a], [-a, a, a], [-a, -a, a]])
    corners = centre + corners_local @ axes.T  # C1, C2, C7, C8
    p1 = centre
    pull = ISO_CORNER_FRACTION
    p2 = corners[0] + pull * (corners[2] - corners[0])
    p4 = corners[2] + pull * (corners[0] - corners[2])
    p3 = corners[1] + pull * (corners[3] - corners[1])
    p5 = corners[3] + pull * (corners[1] - corners[3])
    return np.array([p1, p2, p3, p4, p5])


def iso_cube(robot: RobotModel, smr_mm: np.ndarray, *, envelope: Envelope | None = None,
             centre_mm: np.ndarray | None = None, side_mm: float | None = None,
             q_ref_deg: tuple[float, ...] = (0.0, 20.0, 10.0, 0.0, 45.0, 0.0),
             view: TrackerView | None = None) -> IsoCube:
    """The ISO 9283 cube: the largest cube in the envelope's box (edges along the box) the
    robot reaches with one flange orientation (that of `q_ref_deg`), shrunk in 5 % steps
    until every pose is reachable, within the limits and clear of the wrist singularity.

    Without a box the cube sits in front of the arm (0.75 × tool0's home reach and height)
    with a side of 0.4 × the reach. `centre_mm` / `side_mm` fix either.
    """
    smr = np.asarray(smr_mm, dtype=float)
    envelope = envelope or Envelope()
    axes = envelope.frame[:3, :3]
    reach = abs(robot.home[0, 3])
    if envelope.box is not None:
        box_centre = (envelope.box.lo + envelope.box.hi) / 2.0
        default_centre = envelope.frame[:3, :3] @ box_centre + envelope.frame[:3, 3]
        default_side = float(np.min(envelope.box.size))
    else:
        default_centre = np.array([0.75 * reach, 0.0, 0.75 * robot.home[2, 3]])
        default_side = 0.4 * reach
    centre = default_centre if centre_mm is None else np.asarray(centre_mm, dtype=float)
    side = default_side if side_mm is None else float(side_mm)
    q_ref = np.radians(q_ref_deg)
    R = robot.fk(q_ref)[:3, :3]
    for _ in range(40):
        pts = iso_points(centre, side, axes)
        T = np.tile(np.eye(4), (5, 1, 1))
        T[:, :3, :3] = R
        T[:, :3, 3] = pts - R @ smr
        q, status = robot.ik_nearest(T, q_ref)
        ok = (np.asarray(status) == 0) & envelope.safe(pts)
        ok &= np.abs(np.nan_to_num(q[:, 4])) >= np.radians(WRIST_MIN_DEG)
        if view is not None:
            ok &= view.visible(robot, np.nan_to_num(q), smr)
        if np.all(ok):
            return IsoCube(centre, float(side), axes, pts, R, q, robot.confdata(q))
        if side_mm is not None:
            bad = [f"P{k + 1}" for k in np.flatnonzero(~ok)]
            raise RapidfixError(f"ISO cube of side {side:g} mm: {', '.join(bad)} cannot be "
                                "reached, seen or kept out of the keep-out boxes; choose "
                                "a smaller --iso-side or another --iso-centre")
        side *= 0.95
    raise RapidfixError("no reachable ISO 9283 cube in the envelope: give --iso-centre "
                        "and --iso-side")


def iso_block(cube: IsoCube, cycles: int = ISO_DEFAULT_CYCLES, payload_kg: float = 0.0
              ) -> Block:
    """`cycles` cycles of P1, P5, P4, P3, P2 (ids I01P1 …)."""
    order = np.tile(np.array(ISO_CYCLE_ORDER), cycles)
    cycle = np.repeat(np.arange(1, cycles + 1), len(ISO_CYCLE_ORDER))
    ids = [f"I{c:02d}P{p}" for c, p in zip(cycle, order)]
    n = len(ids)
    return Block("iso9283", ids, cube.q[order - 1], np.full(n, float(payload_kg)),
                 np.zeros(n, int), np.zeros(n, int), order, cycle)
