"""The program-level plan of a rewrite: every target resolved, solved and compensated.

`plan_program` is the rewrite's first step after parsing. It resolves every motion
target with its tool and work object (`resolve`), takes the program's run conditions
(`ProgramConditions`), plans approach points before compensated MoveJ fine points when
asked, solves and compensates all targets at once (`plan.plan_targets`) and decides how
each compensated move is emitted. Path refinement (`refinement`) and emission
(`emission`) take its `ProgramPlan` from there; nothing here edits text.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rapidfix.postprocess.chain import compact_if_moves
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.conditions import ProgramConditions
from rapidfix.postprocess.plan import Plan, plan_targets
from rapidfix.postprocess.resolve import Declarations, Site, Targets, operand_label, resolve
from rapidfix.rapid import MotionInstruction, Program

#: an approach point stands this far beyond twice a joint's play (rad)
APPROACH_EXTRA_RAD = np.radians(0.01)
#: why a move keeps its instruction where a program displacement may be active
DISPLACED = ("a program displacement (PDispOn/PDispSet) may be active: a MoveAbsJ would "
             "not be displaced")


@dataclass(frozen=True)
class ProgramPlan:
    """What the rewrite will do with each motion, before any path is refined.

    `sites` and `targets` are the resolved motions and their target rows (a site the
    plan cannot compensate has its `reason` set); `conditions` the program's run
    conditions; `solved` the solved and compensated targets; `mode` each compensated
    site's emission mode, 'joint' (MoveAbsJ) or 'filtered' (a filtered robtarget);
    `approach` the arrival direction (6,) of each site given an approach point and
    `approach_margin` how far (rad, per joint) the approach points stand off;
    `outside` the data of the other modules it was resolved against.
    """

    sites: list[Site]
    targets: Targets
    conditions: ProgramConditions
    solved: Plan
    mode: dict[int, str]
    approach: dict[int, np.ndarray] = field(default_factory=dict)
    approach_margin: np.ndarray = field(default_factory=lambda: np.zeros(6))
    outside: Declarations = field(default_factory=lambda: Declarations([]))


def is_fine(program: Program, motion: MotionInstruction) -> bool:
    """Whether a motion ends at a fine point (its zone argument is `fine`)."""
    zone = motion.zone
    value = zone.argument.value if zone is not None else None
    return value is not None and program.text[value.start:value.end].strip().lower() == "fine"


def plan_program(program: Program, comp: Compensator, emit: str, *,
                 temperature_c: float | None = None, approach: bool = False,
                 static_external_axes: bool = False) -> ProgramPlan:
    """Resolve, solve and compensate every target; decide each move's emission mode.

    `emit` is 'jointtargets' or 'robtargets'; `temperature_c` the cell temperature the
    program runs at (None: not known); `approach` asks for approach points;
    `static_external_axes` says the external axes carry neither the robot nor the work
    (else a target with one standing anywhere but 0 is left as it was)."""
    model, robot = comp.model, comp.robot
    outside = Declarations(comp.decls)
    sites, targets = resolve(program, outside, emit,
                             static_external_axes=static_external_axes)
    t = targets
    conditions = ProgramConditions(
        program, sites, t, outside, temperature_c,
        model.context_fields(), joint_moves=emit == "jointtargets")
    if emit == "jointtargets":
        for i in np.flatnonzero(conditions.displaced).tolist():
            if sites[i].kept is None:
                sites[i].kept = DISPLACED
    solved: Plan | None = None
    approach_dir: dict[int, np.ndarray] = {}
    margin = np.zeros(6)
    if approach and emit == "jointtargets":
        found = _plan_approach(program, comp, sites, targets, conditions)
        if found is not None:
            solved, approach_dir, margin = found
    if solved is None:
        solved = plan_targets(model, robot, t.pose, t.conf, t.placement,
                              conditions, conditions.free_configuration())
    # rows are in site order: the first failed row of each site names its reason
    for row in np.flatnonzero(~solved.ok).tolist():
        site = sites[int(t.site[row])]
        if site.reason is None:
            label = operand_label(site.targets, t.operand[row])
            site.reason = label + solved.reason[row]
    # emission mode of each compensated site: 'joint' (MoveAbsJ) or 'filtered' (its own
    # instruction kept: robtargets emitted, or no MoveAbsJ can stand for it)
    joint_kinds = "LJC" if emit == "jointtargets" else ""
    mode = {i: "joint" if site.kind in joint_kinds and site.kept is None else "filtered"
            for i, site in enumerate(sites) if site.reason is None}
    return ProgramPlan(sites, targets, conditions, solved, mode, approach_dir, margin, outside)


def _plan_approach(program: Program, comp: Compensator, sites: list[Site], targets: Targets,
                   conditions: ProgramConditions
                   ) -> tuple[Plan | None, dict[int, np.ndarray], np.ndarray] | None:
    """Every joint with play reaches a compensated MoveJ fine point moving up (down
    where its lower limit is too close): compensate those rows in that direction.
    A MoveL or MoveC keeps its path: its joints arrive the way the path takes them. A
    synchronized move (`\\ID`) takes no approach point: the other tasks of its MultiMove
    program would have to take one too. Nor does a compact IF's move (`IF b MoveJ p1,
    ...;`): the IF would guard the approach point only (`compact_if_moves`).

    Returns (plan, site -> direction, margin), the plan None when no site qualifies;
    None when no joint has play."""
    model, robot = comp.model, comp.robot
    play = model.play()
    if not np.any(play > 0):
        return None
    margin = np.where(play > 0, 2.0 * play + APPROACH_EXTRA_RAD, 0.0)
    guarded = compact_if_moves(program)
    chosen = [i for i, site in enumerate(sites) if site.rows and site.kind == "J"
              and not site.synchronized and site.index not in guarded
              and is_fine(program, site.motion)]
    if not chosen:
        return None, {}, margin
    rows = np.array([sites[i].rows[-1] for i in chosen], dtype=np.int64)
    up = np.broadcast_to((play > 0).astype(float), (len(rows), 6))
    direction = up.copy()
    t = targets
    for _ in range(2):  # once with all up, once more if a limit turned some down
        conditions.force_arrival(rows, direction)
        solved = plan_targets(model, robot, t.pose, t.conf, t.placement,
                              conditions, conditions.free_configuration())
        start = solved.q_cmd[rows] - direction * margin
        low = np.asarray(robot.limits, dtype=float)[:, 0]
        down = (start < low) & (direction > 0)
        if not down.any():
            break
        direction = np.where(down, -up, direction)
    return solved, dict(zip(chosen, direction)), margin


__all__ = ["APPROACH_EXTRA_RAD", "DISPLACED", "ProgramPlan", "is_fine", "plan_program"]
