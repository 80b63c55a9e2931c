"""How long the robot takes: a move's duration and the schedule of a measurement run.

The estimate is deliberately simple and conservative: a joint move (MoveAbsJ, or
MoveJ to a robtarget) lasts as long as its slowest limit allows — the TCP speed
and the reorientation speed of the speeddata, and each joint's rated speed — plus
a fixed time to accelerate and brake. The virtual robot uses the same model, so a
plan's schedule and a simulated run agree; on a real controller the estimate is
typically within 10–30 % (acceleration depends on load and pose).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.kinematics import RobotModel

#: Rated joint speeds, °/s, from ABB's product specifications ("Robot motion",
#: "axis max speed") of the shipped models. Other robots: `--joint-speed`.
RATED_JOINT_SPEED_DEG_S: dict[str, tuple[float, ...]] = {
    "IRB120-3/0.58": (250.0, 250.0, 250.0, 320.0, 320.0, 420.0),
    "IRB1600-10/1.45": (150.0, 160.0, 170.0, 320.0, 400.0, 460.0),
    "IRB2600-12/1.65": (175.0, 175.0, 175.0, 360.0, 360.0, 500.0),
    "IRB4600-60/2.05": (175.0, 175.0, 175.0, 250.0, 250.0, 360.0),
    "IRB6700-200/2.60": (110.0, 110.0, 110.0, 190.0, 150.0, 210.0),
}
#: Used for a robot without rated speeds: slow enough for any ABB six-axis arm.
FALLBACK_JOINT_SPEED_DEG_S = (100.0,) * 6


def rated_joint_speed(robot: RobotModel) -> np.ndarray:
    """Rated joint speeds (6,) rad/s of `robot` (a conservative fallback if unknown)."""
    return np.radians(RATED_JOINT_SPEED_DEG_S.get(robot.name, FALLBACK_JOINT_SPEED_DEG_S))


@dataclass(frozen=True)
class MotionSettings:
    """Speed of the measurement moves and the stop at each measured pose.

    `tcp_speed_mm_s`, `orient_speed_deg_s`: the speeddata; `joint_speed_pct` caps
    every joint at that share of its rated speed; `accel_s` the extra time of a
    start and a stop; `settle_s` the WaitTime before the trigger; `measure_s` how
    long the robot stays still after the trigger for the tracker to measure.
    """

    tcp_speed_mm_s: float = 200.0
    orient_speed_deg_s: float = 60.0
    joint_speed_pct: float = 100.0
    accel_s: float = 0.4
    settle_s: float = 1.0
    measure_s: float = 0.5


def move_durations(robot: RobotModel, q_from: np.ndarray, q_to: np.ndarray,
                   settings: MotionSettings, *, tool_mm: np.ndarray | None = None
                   ) -> np.ndarray:
    """Duration (N,) s of joint moves q_from → q_to (N, 6) rad (0 for no motion)."""
    q_from, q_to = np.atleast_2d(q_from), np.atleast_2d(q_to)
    offset = np.zeros(3) if tool_mm is None else np.asarray(tool_mm, dtype=float)
    T0, T1 = robot.fk(q_from), robot.fk(q_to)
    p0 = T0[:, :3, :3] @ offset + T0[:, :3, 3]
    p1 = T1[:, :3, :3] @ offset + T1[:, :3, 3]
    dist = np.linalg.norm(p1 - p0, axis=1)
    rel = np.einsum("nji,njk->nik", T0[:, :3, :3], T1[:, :3, :3])
    turn = np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
    speed = rated_joint_speed(robot) * settings.joint_speed_pct / 100.0
    joint_t = np.max(np.abs(q_to - q_from) / speed, axis=1)
    t = np.maximum.reduce([dist / settings.tcp_speed_mm_s,
                           turn / np.radians(settings.orient_speed_deg_s), joint_t])
    moving = np.any(np.abs(q_to - q_from) > 1e-12, axis=1)
    return np.where(moving, t + settings.accel_s, 0.0)


def mean_joint_speed(robot: RobotModel, q_from: np.ndarray, q_to: np.ndarray,
                     settings: MotionSettings, *, tool_mm: np.ndarray | None = None
                     ) -> np.ndarray:
    """Mean joint speeds (N, 6) rad/s during each move, as `move_durations` times it."""
    t = move_durations(robot, q_from, q_to, settings, tool_mm=tool_mm) - settings.accel_s
    delta = np.abs(np.atleast_2d(q_to) - np.atleast_2d(q_from))
    return np.where(t[:, None] > 0, delta / np.maximum(t, 1e-12)[:, None], 0.0)


@dataclass(frozen=True)
class Schedule:
    """When each measured pose (N) is reached, triggered and left, s from the start.

    The robot is still and settled in [trigger_s, leave_s]: that is the window in
    which the tracker's measurement of the pose must fall.
    """

    arrive_s: np.ndarray
    trigger_s: np.ndarray
    leave_s: np.ndarray

    @property
    def total_s(self) -> float:
        """The run time of the whole program."""
        return float(self.leave_s[-1]) if len(self.leave_s) else 0.0


def schedule(move_s: np.ndarray, settings: MotionSettings) -> Schedule:
    """The schedule of measured poses, each reached after `move_s[i]` seconds of motion
    (its approach included) since the previous one was left."""
    per_pose = np.asarray(move_s, dtype=float) + settings.settle_s + settings.measure_s
    leave = np.cumsum(per_pose)
    trigger = leave - settings.measure_s
    return Schedule(trigger - settings.settle_s, trigger, leave)
