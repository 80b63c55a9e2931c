"""Check a rewritten program the way the controller and the robot will see it.

The output is parsed again — its new statements and declarations, which is the
same check as parsing the whole of it (see `reparse_changes`); a program that does
not parse is never written. For every compensated move the target is read back
from that text, turned into the joints the controller will command (a
jointtarget as written, rounded to the controller's single precision; a
filtered robtarget through the nominal inverse kinematics on its confdata) and
pushed through the error model: the distance between the TCP the model predicts
and the intended TCP is the predicted deviation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.error_model import Context, ErrorModel
from rapidfix.exceptions import RapidfixError, RapidSemanticError
from rapidfix.kinematics import RobotModel, pose
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import ik_on_conf
from rapidfix.postprocess.reparse_changes import CheckUnits
from rapidfix.rapid import MotionInstruction, ReadBack, read_targets_full, read_targets_in_bulk


@dataclass(frozen=True)
class Expected:
    """What the output must hold, per checked pose: the motion instruction it is read
    from (`motion` (K,), an index into the list `parse_units` returns), the target
    operand of that motion (`slot` (K,): 0 the CirPoint or the only target, 1 the
    ToPoint of a circular move), the intended TCP `tcp` (K,4,4) in its work object,
    its frames and the conditions it runs in (`context`: payload, directions,
    temperature)."""

    motion: np.ndarray
    slot: np.ndarray
    tcp: np.ndarray
    placement: Placement
    context: Context


def parse_units(units: CheckUnits, filename: str) -> list[MotionInstruction]:
    """Parse the rewritten parts with the full program model; their motion
    instructions by statement id.

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


def read_back(units: CheckUnits, filename: str, expected: Expected) -> ReadBack:
    """Parse the rewritten parts and read the target of every expected pose from them.

    Rewritten parts made of simple statements only (a CAM program's) are read in
    bulk (`rapidfix.rapid.readback`: Lark parses them with the same grammar, and the
    values are read once per run); anything else, and anything the bulk reader
    does not take, goes the full route through the program model, which also
    explains a syntax error. Both give the same values (tests compare them).
    """
    text, order = units.text()
    found = read_targets_in_bulk(text, order, expected.motion, expected.slot)
    return found if found is not None else read_back_full(units, filename, expected)


def read_back_full(units: CheckUnits, filename: str, expected: Expected) -> ReadBack:
    """`read_back` through the full program model (`parse_units`)."""
    return read_targets_full(parse_units(units, filename), expected.motion, expected.slot)


def commanded_joints(robot: RobotModel, read: ReadBack, expected: Expected,
                     filename: str = "") -> np.ndarray:
    """Joints (K,6) rad the controller commands for the targets read back from the output."""
    k = expected.motion.shape[0]
    q = np.zeros((k, 6))
    if read.joint.any():
        q[read.joint] = np.radians(read.robax[read.joint].astype(np.float32).astype(float))
    rows = np.flatnonzero(~read.joint)
    if rows.size:
        trans = read.trans[rows].astype(np.float32).astype(float)
        rot = read.rot[rows].astype(np.float32).astype(float)
        conf = read.conf[rows].astype(int)
        flange = expected.placement.take(rows).flange(pose(trans, rot))
        q_rob, status = ik_on_conf(robot, flange, conf)
        if np.any(np.asarray(status) != 0):
            raise RapidSemanticError("a filtered robtarget has no solution on its confdata",
                                     file=filename or None,
                                     hint="please report this as a rapidfix bug")
        q[rows] = q_rob
    return q


def predicted_deviation(
    model: ErrorModel, robot: RobotModel, read: ReadBack, expected: Expected, filename: str = ""
) -> np.ndarray:
    """Predicted TCP position error (K,) mm of every expected pose of the output."""
    if expected.motion.shape[0] == 0:
        return np.zeros(0)
    q = commanded_joints(robot, read, expected, filename)
    flange = model.actual_flange(robot, q, expected.context)
    tcp = expected.placement.tcp(flange)
    return np.linalg.norm(tcp[:, :3, 3] - expected.tcp[:, :3, 3], axis=1)
