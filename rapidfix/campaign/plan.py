"""A measurement campaign's plan: the poses, their order and approach, the checks,
the schedule and the RAPID program (see `rapidfix plan`).

`make_plan` assembles the blocks of `rapidfix.campaign.poses` in the order the
robot runs them (sweeps, calibration, validation, ISO cube), adds the approach
moves, checks everything before anything is written and estimates the run time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.atomic import write_text_atomic
from rapidfix.campaign.envelope import Envelope
from rapidfix.campaign.pose_table import PoseTable, write_pose_table
from rapidfix.campaign.poses import (
    ISO_DEFAULT_CYCLES,
    WRIST_MIN_DEG,
    Block,
    IsoCube,
    ball_positions,
    iso_block,
    iso_cube,
    point_blocks,
    sweep_block,
)
from rapidfix.campaign.program import ProgramOptions, measurement_module
from rapidfix.campaign.sight import TrackerView
from rapidfix.campaign.timing import (
    mean_joint_speed,
    move_durations,
    rated_joint_speed,
    schedule,
)
from rapidfix.exceptions import RapidfixError
from rapidfix.kinematics import RobotModel
from rapidfix.measure import toml_value

APPROACH_MODES = ("same", "both", "none")


@dataclass(frozen=True)
class PlanSettings:
    """What to measure and how (see `rapidfix plan --help` for each)."""

    smr_offset_mm: tuple[float, float, float] = (60.0, 80.0, 90.0)
    sweep_joints: tuple[int, ...] = (1, 2, 3, 4, 5, 6)
    step_deg: float = 5.0
    repeats: int = 3
    sweep_ranges_deg: dict[int, tuple[float, float]] = field(default_factory=dict)
    sweep_payload_kg: float = 0.0
    n_calibration: int = 60
    n_validation: int = 40
    payloads_kg: tuple[float, ...] = (0.0,)
    envelope: Envelope = field(default_factory=Envelope)
    tracker: TrackerView | None = None
    iso: bool = False
    iso_cycles: int = ISO_DEFAULT_CYCLES
    iso_centre_mm: tuple[float, float, float] | None = None
    iso_side_mm: float | None = None
    approach: str = "same"
    approach_deg: float = 2.0
    pause_s: float = 60.0
    seed: int = 0
    program: ProgramOptions = field(default_factory=ProgramOptions)


@dataclass
class Plan:
    """The pose table, the program's text, the ISO cube (or None) and a summary."""

    table: PoseTable
    program: str
    cube: IsoCube | None
    summary: dict[str, Any]
    settings: PlanSettings
    robot: RobotModel


def _both_sides(block: Block) -> tuple[Block, np.ndarray]:
    """Each pose twice, first approached from below ('u'), then from above ('d')."""
    twice = np.repeat(np.arange(len(block)), 2)
    side = np.tile([1, -1], len(block))
    ids = [f"{block.point_id[i]}{'u' if s > 0 else 'd'}" for i, s in zip(twice, side)]
    return Block(block.set_name, ids, block.q[twice], block.payload_kg[twice],
                 block.sweep_joint[twice], block.repeat[twice], block.iso_pose[twice],
                 block.cycle[twice]), side


def _approach_poses(robot: RobotModel, q: np.ndarray, side: np.ndarray,
                    step_rad: float) -> np.ndarray:
    """Approach joints (N, 6), NaN rows where the move itself arrives from the right side.

    A joint's side is the direction of its last motion; an approach pose q − step·side
    (within the limits) is inserted before a pose whenever some joint would otherwise
    arrive from the other side or keep the other side from an earlier move. A joint
    at its limit cannot be approached from beyond it and keeps the side it came from.
    """
    out = np.full_like(q, np.nan)
    state = np.zeros(6)
    prev = None
    for i in range(len(q)):
        s = float(side[i])
        if s == 0:
            continue
        delta = np.zeros(6) if prev is None else q[i] - prev
        arrive = np.where(np.abs(delta) > 1e-12, np.sign(delta), state)
        if prev is None or np.any(arrive != s):
            out[i] = np.clip(q[i] - s * step_rad, robot.limits[:, 0], robot.limits[:, 1])
            moved = np.abs(q[i] - out[i]) > 1e-12
            state = np.where(moved, s, arrive)
        else:
            state = arrive
        prev = q[i]
    return out


def make_plan(robot: RobotModel, settings: PlanSettings) -> Plan:
    """Plan the campaign, check it (RapidfixError naming the points) and schedule it."""
    st = settings
    if st.approach not in APPROACH_MODES:
        raise RapidfixError(f"--approach must be one of {', '.join(APPROACH_MODES)}")
    smr = np.asarray(st.smr_offset_mm, dtype=float)
    both = st.approach == "both"
    blocks: list[tuple[Block, np.ndarray]] = []
    if st.sweep_joints:
        sw = sweep_block(robot, smr, step_deg=st.step_deg, repeats=st.repeats,
                         joints=st.sweep_joints, ranges_deg=st.sweep_ranges_deg,
                         envelope=st.envelope, view=st.tracker, payload_kg=st.sweep_payload_kg,
                         alternate=both)
        if both:
            down = (sw.repeat % 2 == 0) & (sw.repeat > 0)
            side = np.where(down, -1, 1)
        else:
            side = np.ones(len(sw), int)
        blocks.append((sw, side))
    if st.n_calibration or st.n_validation:
        start = blocks[-1][0].q[-1] if blocks else None
        cal, val = point_blocks(robot, smr, st.n_calibration, st.n_validation, seed=st.seed,
                                envelope=st.envelope, view=st.tracker, payloads=st.payloads_kg,
                                start_q=start)
        for b in (cal, val):
            if len(b):
                blocks.append(_both_sides(b) if both else (b, np.ones(len(b), int)))
    cube = None
    if st.iso:
        cube = iso_cube(robot, smr, envelope=st.envelope, centre_mm=st.iso_centre_mm,
                        side_mm=st.iso_side_mm, view=st.tracker)
        ib = iso_block(cube, st.iso_cycles, st.payloads_kg[0])
        blocks.append(_both_sides(ib) if both else (ib, np.ones(len(ib), int)))
    if not blocks:
        raise RapidfixError("nothing to measure: no sweeps, points or ISO cube asked for")

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(b, name) for b, _ in blocks])

    ids = [pid for b, _ in blocks for pid in b.point_id]
    sets = np.concatenate([[b.set_name] * len(b) for b, _ in blocks])
    q = np.vstack([b.q for b, _ in blocks])
    payload = cat("payload_kg")
    side = np.concatenate([s for _, s in blocks])
    if st.approach == "none":
        side = np.zeros_like(side)
    approach = _approach_poses(robot, q, side, np.radians(st.approach_deg))
    pause = np.r_[payload[0] != 0.0, payload[1:] != payload[:-1]]
    has_app = ~np.isnan(approach[:, 0])
    # which joints each approach move turns (bit j-1 for joint j): they arrive from its side
    moved = has_app[:, None] & (np.abs(np.nan_to_num(approach) - q) > 1e-12)
    approach_joints = moved.astype(int) @ (1 << np.arange(6))

    _check(robot, smr, st, ids, sets, q, approach, cube)

    m = st.program.motion
    home = np.zeros(6)
    prev = np.vstack([home, q[:-1]])
    via = np.where(has_app[:, None], approach, prev)
    move_s = (move_durations(robot, prev, via, m, tool_mm=smr)
              + move_durations(robot, via, q, m, tool_mm=smr) + pause * st.pause_s)
    sched = schedule(move_s, m)
    speed = np.vstack([mean_joint_speed(robot, prev, via, m, tool_mm=smr),
                       mean_joint_speed(robot, via, q, m, tool_mm=smr)])
    share = float(np.max(speed / rated_joint_speed(robot))) if len(speed) else 0.0

    table = PoseTable(
        point_id=np.array(ids), set_name=sets, q=q, payload_kg=payload,
        ints={"sweep_joint": cat("sweep_joint"), "repeat": cat("repeat"),
              "iso_pose": cat("iso_pose"), "cycle": cat("cycle"),
              "approach": np.where(has_app, side, 0).astype(int),
              "approach_joints": approach_joints, "pause_before": pause.astype(int)},
        times={"t_arrive_s": sched.arrive_s, "t_trigger_s": sched.trigger_s,
               "t_leave_s": sched.leave_s}, rows=np.arange(len(ids)) + 2)
    counts = {str(name): int(np.sum(sets == name)) for name in dict.fromkeys(sets)}
    summary = {"robot": robot.name, "points": len(ids), "per_set": counts,
               "approach_moves": int(has_app.sum()), "payload_changes": int(pause.sum()),
               "run_time_s": sched.total_s, "fastest_joint_share_of_rated": share}
    if cube is not None:
        summary["iso9283"] = {"centre_mm": cube.centre_mm.tolist(), "side_mm": float(cube.side_mm),
                              "cycles": st.iso_cycles,
                              "points_mm": cube.points_mm.tolist()}
    header = [f"Measurement program: {len(ids)} measured poses "
              + ", ".join(f"{v} {k}" for k, v in counts.items()) + ".",
              f"Estimated run time {_hms(sched.total_s)} (h:mm:ss), payload changes "
              f"{int(pause.sum())} (each a Stop for the operator).",
              "Every pose: fine point, WaitTime nRfSettle, trigger "
              f"({st.program.trigger}), WaitTime nRfMeasure. Point ids in execution order "
              "are in the pose table.",
              f"Ball (tBall) {', '.join(f'{v:g}' for v in smr)} mm in the flange frame. "
              "Run at 100 % speed override so the schedule holds."]
    iso_args: dict[str, Any] = {"iso_q": None, "iso_trans": None, "iso_rot": None,
                                "iso_conf": None}
    if cube is not None:
        iso_args = {"iso_q": cube.q, "iso_trans": cube.points_mm, "iso_rot": cube.R,
                    "iso_conf": cube.conf}
    text = measurement_module(point_id=ids, set_name=sets, q=q, approach_q=approach,
                              iso_pose=cat("iso_pose"), pause_before=pause,
                              payload_kg=payload, smr_mm=smr, header=header,
                              options=st.program, **iso_args)
    return Plan(table, text, cube, summary, st, robot)


def _hms(seconds: float) -> str:
    s = round(seconds)
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def _check(robot: RobotModel, smr: np.ndarray, st: PlanSettings, ids: list[str],
           sets: np.ndarray, q: np.ndarray, approach: np.ndarray, cube: IsoCube | None) -> None:
    """Refuse a plan that breaks a limit, leaves the envelope or cannot be seen."""

    def refuse(mask: np.ndarray, what: str) -> None:
        bad = [ids[i] for i in np.flatnonzero(mask)]
        if bad:
            more = f" and {len(bad) - 5} more" if len(bad) > 5 else ""
            raise RapidfixError(f"{what}: {', '.join(bad[:5])}{more}")

    refuse(~robot.within_limits(q), "poses beyond the joint limits")
    has_app = ~np.isnan(approach[:, 0])
    app_ok = np.ones(len(q), dtype=bool)
    app_ok[has_app] = robot.within_limits(approach[has_app])
    refuse(~app_ok, "approach poses beyond the joint limits")
    ball = ball_positions(robot, q, smr)
    refuse(~st.envelope.safe(ball), "poses below the floor or in a keep-out box")
    app_ball_ok = np.ones(len(q), dtype=bool)
    app_ball_ok[has_app] = st.envelope.safe(ball_positions(robot, approach[has_app], smr))
    refuse(~app_ball_ok, "approach poses below the floor or in a keep-out box")
    points = np.isin(sets, ("calibration", "validation"))
    refuse(points & ~st.envelope.contains(ball), "calibration/validation poses outside the box")
    refuse(points & (np.abs(q[:, 4]) < np.radians(WRIST_MIN_DEG)),
           "poses too close to the wrist singularity")
    if st.tracker is not None:
        refuse(~st.tracker.visible(robot, q, smr),
               f"poses whose ball faces more than {st.tracker.acceptance_deg:g}° away from "
               "the tracker")
    if cube is not None:  # the robtargets must give back these joints on their confdata
        T = robot.fk(cube.q)
        q_conf, status = robot.ik_conf(T, cube.conf)
        bad = (np.asarray(status) != 0) | ~np.all(np.abs(q_conf - cube.q) < 1e-6, axis=1)
        if np.any(bad):
            raise RapidfixError("ISO 9283 poses not reached on their confdata: "
                                + ", ".join(f"P{k + 1}" for k in np.flatnonzero(bad)))


def write_plan(plan: Plan, out_dir: str | Path, *, program_name: str = "measure.mod",
               table_name: str = "poses.csv") -> dict[str, Path]:
    """Write the program, the pose table and `plan.toml` (robot, ball, timing) atomically."""
    out = Path(out_dir)
    st = plan.settings
    m = st.program.motion
    paths = {"program": out / program_name, "poses": out / table_name,
             "plan": out / "plan.toml"}
    write_text_atomic(paths["program"], plan.program)
    write_pose_table(paths["poses"], plan.table)
    meta: dict[str, Any] = {
        "robot": plan.robot.name, "smr_offset_mm": list(map(float, st.smr_offset_mm)),
        "program": program_name, "poses": table_name, "points": plan.summary["points"],
        "run_time_s": round(plan.summary["run_time_s"], 3), "trigger": st.program.trigger,
        "settle_s": m.settle_s, "measure_s": m.measure_s, "tcp_speed_mm_s": m.tcp_speed_mm_s,
        "orient_speed_deg_s": m.orient_speed_deg_s, "joint_speed_pct": m.joint_speed_pct,
        "accel_s": m.accel_s, "approach": st.approach, "seed": st.seed}
    lines = ["# rapidfix plan: what `rapidfix import` and `rapidfix simulate --program` read"]
    lines += [f"{k} = {toml_value(v)}" for k, v in meta.items()]
    if plan.cube is not None:
        lines += ["", "[iso9283]", f"centre_mm = {toml_value(plan.cube.centre_mm.tolist())}",
                  f"side_mm = {float(plan.cube.side_mm)!r}", f"cycles = {st.iso_cycles}"]
    write_text_atomic(paths["plan"], "\n".join(lines) + "\n")
    return paths
