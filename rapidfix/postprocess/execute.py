"""Run a RAPID program's motions on a robot model: the joints a nominal controller commands.

For every motion instruction whose target is known before run time, in program
order: a MoveAbsJ commands its jointtarget (as the controller stores it, in
single precision); a Cartesian move commands the nominal inverse kinematics of
its robtarget on the branch its confdata names, with its tool and work object.
Pushing these joints through a virtual robot's true errors shows where the real
robot would go — before compensation (the original program) and after (the
rewritten one). Used by the demo and the acceptance tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.kinematics import IKStatus, RobotModel
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import ik_on_conf
from rapidfix.postprocess.resolve import Declarations, operand_data, resolve
from rapidfix.rapid import Program


@dataclass(frozen=True)
class Execution:
    """Per executed motion (K): its index in program.motions, the commanded joints
    `q_cmd` (K,6) rad, the destination's name as written, and the frames of the move
    (`placement`; tool0 in wobj0 for MoveAbsJ)."""

    motion: np.ndarray
    q_cmd: np.ndarray
    target: list[str]
    placement: Placement


def commanded_motions(program: Program, robot: RobotModel, decls: list[Program] | None = None
                      ) -> Execution:
    """The joints the controller commands for every static motion, in program order."""
    outside = Declarations(decls or [])
    sites, targets = resolve(program, outside, "robtargets")
    q_cart = np.zeros((0, 6))
    status = np.zeros(0, dtype=int)
    if len(targets.site):
        q_cart, status = ik_on_conf(robot, targets.placement.flange(targets.pose), targets.conf)
    site_of = {id(site.motion.syntax): site for site in sites}
    rows, motions, names, q_rows, joint_rows = [], [], [], [], []
    for index, motion in enumerate(program.motions):
        site = site_of.get(id(motion.syntax))
        if site is not None:
            if site.reason is not None:
                continue
            row = site.rows[-1]
            if int(status[row]) != IKStatus.OK:
                continue
            motions.append(index)
            names.append(motion.target.text)
            rows.append(row)
            q_rows.append(q_cart[row])
            continue
        if motion.name.lower() == "moveabsj" and motion.target is not None:
            data, _ = operand_data(motion.target, "jointtarget", outside)
            if data is None:
                continue
            motions.append(index)
            names.append(motion.target.text)
            rows.append(-1)
            joint_rows.append(len(q_rows))
            single = np.asarray(data.robax, dtype=np.float32).astype(float)
            q_rows.append(np.radians(single))
    k = len(motions)
    rows_a = np.array(rows, dtype=int)
    ident = Placement.identity(k)
    if len(targets.site) and k:
        taken = targets.placement.take(np.maximum(rows_a, 0))
        cart = rows_a >= 0
        placement = Placement(
            np.where(cart[:, None, None], taken.tool, ident.tool),
            np.where(cart[:, None, None], taken.wobj, ident.wobj),
            np.where(cart, taken.stationary, False),
        )
    else:
        placement = ident
    q = np.array(q_rows, dtype=float).reshape(k, 6)
    return Execution(np.array(motions, dtype=int), q, names, placement)


def align_axis1(robot: RobotModel, actual: np.ndarray, intended: np.ndarray) -> np.ndarray:
    """`actual` positions (K,3) turned about axis 1 and moved along it by the angle and
    height that fit `intended` best.

    A constant joint-1 error, and the arm's height along axis 1, cannot be told from
    the robot's placement in the cell: targets taught or measured in the cell absorb
    them, and neither a tracker fitted with the points nor a model can see them.
    Positions are therefore compared in the best gauge of the base (a closed-form
    rotation about the axis-1 line and a shift along it, two parameters per run).
    """
    actual = np.asarray(actual, dtype=float)
    intended = np.asarray(intended, dtype=float)
    if actual.shape[0] == 0:
        return actual.copy()
    w = np.asarray(robot.axis_dirs[0], dtype=float)
    a = np.asarray(robot.axis_points[0], dtype=float)
    u = np.cross(w, [1.0, 0.0, 0.0] if abs(w[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    pa, pi = actual - a, intended - a
    xa, ya = pa @ u, pa @ v
    xi, yi = pi @ u, pi @ v
    angle = np.arctan2(np.sum(xa * yi - ya * xi), np.sum(xa * xi + ya * yi))
    c, s = np.cos(angle), np.sin(angle)
    height = float(np.mean((pi - pa) @ w))
    return (a + np.outer(c * xa - s * ya, u) + np.outer(s * xa + c * ya, v)
            + np.outer(pa @ w + height, w))
