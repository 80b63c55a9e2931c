"""Where each move starts: the motion instruction executed just before it.

A MoveL or MoveC draws its line or arc from wherever the robot is. That is the
previous motion instruction when both sit in the same statement list with
nothing in between that could move the robot or jump: a call of a routine of
the program, a compound statement (IF, FOR, WHILE, TEST), a label, GOTO,
RETURN, RAISE, a late-bound call. The first move of a routine, of a loop body
or of an IF branch has no known start (it depends on the caller or the
previous iteration); the rewrite treats it accordingly.
"""

from __future__ import annotations

from rapidfix.rapid import MotionInstruction, Program
from rapidfix.rapid import syntax as s


def predecessors(program: Program) -> dict[int, MotionInstruction | None]:
    """id(motion.syntax) -> the motion instruction executed just before it, or None."""
    by_call = {id(m.syntax): m for m in program.motions}
    user_routines = {r.name.lower() for r in program.routines}
    result: dict[int, MotionInstruction | None] = {}
    stack: list[list[s.Statement]] = []
    for module in program.syntax.modules:
        for item in module.items:
            if isinstance(item, s.Routine):
                stack.append(item.body)
                stack.extend(h.body for h in item.handlers)
    while stack:
        previous: MotionInstruction | None = None
        for statement in stack.pop():
            motion = by_call.get(id(statement))
            if motion is not None:
                result[id(statement)] = previous
                previous = motion
                continue
            nested = list(statement.bodies())
            if nested:
                stack.extend(nested)
                previous = None
            elif isinstance(statement, s.ProcedureCall):
                if statement.key in user_routines:
                    previous = None
            elif not isinstance(statement, s.Assignment):
                previous = None
    return result
