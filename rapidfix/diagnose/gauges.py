"""What the measurements cannot see, set by the physical size of each term.

Points measured on a single target ball by a tracker whose pose is fitted with
them leave some changes of a model invisible: they move no measured point. The
least-squares fit leaves these directions wherever its parameterisation happens
to put them, yet a program feels them. The data cannot decide, so physics does:
the model is moved along each such direction to its most probable point under
Gaussian priors of the terms' physical sizes (maximum a posteriori), checking
that no measured point moves.

- **The flange's turn about the ball** (`resolve_flange_gauge`). When the
  diagnosis frees a translation in the flange (a `tool_offset`, or tool0's home
  pose in `link_geometry`), turning joint 6's zero by t together with moving the
  ball by −t a₆ × b, and (with link geometry) turning tool0's home by ω together
  with moving it by −ω × b, are invisible. The per-joint sweeps, analysed with the
  declared ball, put a ball's tangential error into joint 6's zero; a program's
  tools sit elsewhere on the flange and feel that turn in full (0.1° is 0.3 mm at
  a 160 mm TCP). Two or more ball positions on the flange measure it instead:
  with two nests only the turn about the line through both stays unseen (a rigid
  body held at two points can still turn about the line joining them), with three
  not in a line nothing does, and the directions left are found from the balls the
  rows measured, so with several nests there is less (or nothing) to set.

Not set here: with link geometry, moving every joint axis (2–6) and tool0 along
axis 1, and the tracker the other way, is invisible too (the arm's height above
its base); it is a gauge of the base like joint 1's zero, which work objects
taught or measured in the cell absorb.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from rapidfix.error_model import (
    OFFSET_JOINTS,
    ErrorModel,
    JointReference,
    LinkGeometry,
    MeasuredPoints,
    ToolOffset,
    predict,
)
from rapidfix.kinematics import RobotModel

#: a joint's zero after the maker's calibration (1σ, rad)
JOINT_ZERO_SIGMA_RAD = np.radians(0.03)
#: a target-ball nest or adapter against its drawing (1σ per axis, mm)
BALL_SIGMA_MM = 0.5
#: tool0's home position against the nominal model (1σ per axis, mm)
HOME_SHIFT_SIGMA_MM = 0.2
#: tool0's home orientation against the nominal model (1σ per axis, rad)
HOME_TURN_SIGMA_RAD = np.radians(0.02)
#: the measured points may move by at most this much (mm, max) when the gauge is set:
#: the directions are null to first order; more means the model is not near linear there
MAX_POINT_CHANGE_MM = 2e-3
_J6 = OFFSET_JOINTS.index(5)


@dataclass(frozen=True)
class GaugeChange:
    """What was moved: joint 6's zero (rad), tool0's home turn and shift and the
    ball's offset (flange frame, rad and mm; zeros where the model has no such term),
    and the largest move of a measured point it caused (mm)."""

    joint6_rad: float
    home_turn_rad: np.ndarray
    home_shift_mm: np.ndarray
    ball_mm: np.ndarray
    point_change_mm: float
    #: how many distinct ball positions the measured rows had
    balls: int = 1

    def describe(self) -> str:
        """One sentence for the report."""
        parts = [f"joint 6's zero by {np.degrees(self.joint6_rad):+.4f}°"]
        if np.any(self.home_turn_rad):
            parts.append(f"tool0's home turned by {np.degrees(self.home_turn_rad).round(4)}° "
                         f"and shifted by {self.home_shift_mm.round(3)} mm")
        if np.any(self.ball_mm):
            parts.append(f"the ball's offset by {self.ball_mm.round(3)} mm")
        if self.balls == 1:
            unseen = "One target ball does not show how the flange turns about it"
            advice = " Two ball positions would measure most of it, three all of it."
        else:
            unseen = (f"{self.balls} target balls in a line do not show how the flange turns "
                      "about that line")
            advice = " A third ball off that line would measure it."
        return (unseen + "; that part was set by the physical sizes of the terms (maximum "
                "a posteriori): " + ", ".join(parts) + f" (measured points moved by at most "
                f"{self.point_change_mm:.1e} mm)." + advice)


def _first(model: ErrorModel, kind: type) -> Any:
    return next((e for e in model.effects if isinstance(e, kind) and e.free), None)


def _joint6_zero(model: ErrorModel, data: MeasuredPoints) -> float:
    """Mean error of joint 6 (rad) of the per-joint terms over the measured poses."""
    total = np.zeros(len(data))
    for eff in model.effects:
        if eff.adds_joint_delta and eff.separable and not eff.measurement_only:
            total += eff.joint_delta(data.q, data.ctx)[:, 5]
    return float(total.mean())


def resolve_flange_gauge(model: ErrorModel, robot: RobotModel,
                         data: MeasuredPoints) -> GaugeChange | None:
    """Move `model` (its effects are replaced) to the most probable point of its unseen flange turn.

    Does nothing (returns None) unless the model frees a flange translation and
    re-references joint 6, when the balls the rows measured leave no such turn unseen
    (three nests not in a line; two, with only a tool offset), or when the move would
    change a measured point.
    """
    reference = _first(model, JointReference)
    geometry = _first(model, LinkGeometry)
    ball_offset = _first(model, ToolOffset)
    if reference is None or (geometry is None and ball_offset is None):
        return None
    home_r = np.asarray(robot.home, dtype=float)[:3, :3]
    a6 = home_r.T @ np.asarray(robot.axis_dirs, dtype=float)[5]
    p6 = home_r.T @ (np.asarray(robot.axis_points, dtype=float)[5] - robot.home[:3, 3])
    balls = data.distinct_balls_mm
    if ball_offset is not None:
        balls = balls + ball_offset.params()

    # unknowns x: t (1), then home turn ω (3) and shift u (3) if geometry, ball v (3) if
    # tool offset; no ball may move: t a6×(b−p6) + ω×b + u + v = 0 for every ball b
    rows, current, sigma = [], [_joint6_zero(model, data)], [JOINT_ZERO_SIGMA_RAD]
    for ball in balls:
        blocks = [np.cross(a6, ball - p6)[:, None]]
        if geometry is not None:
            blocks += [-_skew(ball), np.eye(3)]
        if ball_offset is not None:
            blocks.append(np.eye(3))
        rows.append(np.hstack(blocks))
    if geometry is not None:
        errors = geometry.errors()
        current += [*(home_r.T @ errors[23:26]), *(home_r.T @ errors[20:23])]
        sigma += [HOME_TURN_SIGMA_RAD] * 3 + [HOME_SHIFT_SIGMA_MM] * 3
    if ball_offset is not None:
        current += list(ball_offset.params())
        sigma += [BALL_SIGMA_MM] * 3
    constraint = np.vstack(rows)
    weight = 1.0 / np.asarray(sigma)
    # only what moves a program's flange counts as unseen: the swap of joint 6's zero
    # with tool0's turn about the same axis changes nothing anywhere
    null = scipy.linalg.null_space(constraint)
    if not np.any(np.abs(_flange_motion(null, geometry is not None, a6, p6)) > 1e-9):
        return None
    z, *_ = np.linalg.lstsq(weight[:, None] * null, -weight * np.asarray(current), rcond=None)
    x = null @ z

    trial = copy.deepcopy(model)
    reference, geometry, ball_offset = (_first(trial, k)
                                        for k in (JointReference, LinkGeometry, ToolOffset))
    p = reference.params()
    p[_J6] += x[0]
    reference.set_fitted(p)
    turn, shift, ball_move = np.zeros(3), np.zeros(3), np.zeros(3)
    if geometry is not None:
        turn, shift = x[1:4], x[4:7]
        columns = np.zeros((geometry.modes.shape[0], 6))
        columns[20:26] = np.eye(6)
        geometry.add_modes(columns, np.concatenate([home_r @ shift, home_r @ turn]),
                           [HOME_SHIFT_SIGMA_MM] * 3 + [HOME_TURN_SIGMA_RAD] * 3)
    if ball_offset is not None:
        ball_move = x[-3:]
        ball_offset.set_fitted(ball_offset.params() + ball_move)
    change = float(np.abs(predict(trial, robot, data) - predict(model, robot, data)).max())
    if not np.isfinite(change) or change > MAX_POINT_CHANGE_MM:
        return None
    model.effects = trial.effects
    return GaugeChange(float(x[0]), turn, shift, ball_move, change, balls=len(balls))


def _flange_motion(null: np.ndarray, geometry: bool, a6: np.ndarray,
                   p6: np.ndarray) -> np.ndarray:
    """How each null direction (columns) turns and shifts the flange (6, k): joint 6's
    zero t and tool0's turn ω and shift u together, in the flange frame."""
    if null.size == 0:
        return np.zeros((6, 0))
    t = null[0]
    turn = np.outer(a6, t)
    shift = -np.cross(a6, p6)[:, None] * t  # a turn about axis 6 moves the origin
    if geometry:
        turn = turn + null[1:4]
        shift = shift + null[4:7]
    return np.vstack([turn, shift])


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])

