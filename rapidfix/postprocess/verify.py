"""Check a rewritten program the way the controller and the robot will see it.

The output is parsed again — its new statements and declarations, which is the
same check as parsing the whole of it (see `check_units`); a program that does
not parse is never written. For every compensated move the target is read back
from that text, turned into the joints the controller will command (a
jointtarget as written, rounded to the controller's single precision; a
filtered robtarget through the nominal inverse kinematics on its confdata) and
pushed through the error model: the distance between the TCP the model predicts
and the intended TCP is the predicted deviation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rapidfix.errors.context import Context
from rapidfix.errors.model import ErrorModel
from rapidfix.exceptions import RapidfixError, RapidSemanticError
from rapidfix.kinematics.frames import pose
from rapidfix.postprocess.check_units import CheckUnits
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import ik_on_conf
from rapidfix.postprocess.resolve import motion_targets
from rapidfix.rapid import MotionInstruction


@dataclass(frozen=True)
class Expected:
    """What the output must hold, per checked pose: the motion instruction it is read
    from (`motion` (K,), an index into the list `parse_units` returns), the target
    operand of that motion (`slot` (K,): 0 the CirPoint or the only target, 1 the
    ToPoint of a circular move), the intended TCP `tcp` (K,4,4) in its work object,
    its frames and payload."""

    motion: np.ndarray
    slot: np.ndarray
    tcp: np.ndarray
    placement: Placement
    payload_kg: np.ndarray


def parse_units(units: CheckUnits, filename: str) -> list[MotionInstruction]:
    """Parse the rewritten parts; their motion instructions by statement id.

    An error here is a bug of the rewrite: it is reported and nothing is written.
    """
    try:
        return units.parse(filename)[1]
    except (RapidfixError, ValueError) as err:
        raise RapidSemanticError(
            f"the rewritten program does not parse ({err}); nothing was written",
            file=filename,
            hint="please report this as a rapidfix bug",
        ) from None


def commanded_joints(
    robot: Any, motions: list[MotionInstruction], expected: Expected
) -> np.ndarray:
    """Joints (K,6) rad the controller commands for the expected targets of the output."""
    k = expected.motion.shape[0]
    q = np.zeros((k, 6))
    joint_rows, joint_vals = [], []
    rob_rows, rob_vals = [], []
    for i, (m, slot) in enumerate(zip(expected.motion.tolist(), expected.slot.tolist())):
        operand = motion_targets(motions[m])[slot]
        value = operand.value if operand.static else None
        if value is None or operand.type_name not in ("jointtarget", "robtarget"):
            raise RapidSemanticError(
                f"rewritten target {operand.text!r} cannot be read back: {operand.reason}",
                file=motions[m].span.file, line=motions[m].span.line,
                hint="please report this as a rapidfix bug")
        # raw values, already checked against their type by the RAPID layer
        if operand.type_name == "jointtarget":
            joint_rows.append(i)
            joint_vals.append(value[0])
        else:
            rob_rows.append(i)
            rob_vals.append(value[:3])
    if joint_rows:
        single = np.asarray(joint_vals, dtype=np.float32).astype(float)
        q[joint_rows] = np.radians(single)
    if rob_rows:
        rows = np.asarray(rob_rows)
        trans = np.array([v[0] for v in rob_vals], dtype=np.float32).astype(float)
        rot = np.array([v[1] for v in rob_vals], dtype=np.float32).astype(float)
        conf = np.array([v[2] for v in rob_vals], dtype=int)
        flange = expected.placement.take(rows).flange(pose(trans, rot))
        q_rob, status = ik_on_conf(robot, flange, conf)
        bad = np.flatnonzero(np.asarray(status) != 0)
        if bad.size:
            m = motions[int(expected.motion[rows[bad[0]]])]
            raise RapidSemanticError("a filtered robtarget has no solution on its confdata",
                                     file=m.span.file, line=m.span.line,
                                     hint="please report this as a rapidfix bug")
        q[rows] = q_rob
    return q


def predicted_deviation(
    model: ErrorModel, robot: Any, motions: list[MotionInstruction], expected: Expected
) -> np.ndarray:
    """Predicted TCP position error (K,) mm of every expected pose of the output."""
    if expected.motion.shape[0] == 0:
        return np.zeros(0)
    q = commanded_joints(robot, motions, expected)
    flange = model.actual_flange(robot, q, Context(payload_kg=expected.payload_kg))
    tcp = expected.placement.tcp(flange)
    return np.linalg.norm(tcp[:, :3, 3] - expected.tcp[:, :3, 3], axis=1)
