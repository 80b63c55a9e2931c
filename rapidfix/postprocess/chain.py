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

from rapidfix.rapid import Assignment, CompactIf, ProcedureCall, Program, Routine, Statement


def predecessors(program: Program) -> list[int]:
    """Per motion of `program.motions`: the index of the motion instruction executed
    just before it, or -1 when that is not known before run time."""
    index_of = {id(m.syntax): k for k, m in enumerate(program.motions)}
    user_routines = {r.name.lower() for r in program.routines}
    result = [-1] * len(program.motions)
    stack = _routine_bodies(program)
    while stack:
        previous = -1
        for statement in stack.pop():
            k = index_of.get(id(statement))
            if k is not None:
                result[k] = previous
                previous = k
                continue
            nested = list(statement.bodies())
            if nested:
                stack.extend(nested)
                previous = -1
            elif isinstance(statement, ProcedureCall):
                if statement.key in user_routines:
                    previous = -1
            elif not isinstance(statement, Assignment):
                previous = -1
    return result


def compact_if_moves(program: Program) -> set[int]:
    """The motions (indices in `program.motions`) that are a compact IF's one statement
    (`IF bPick MoveJ p1, ...;`): nothing may be put before one, since the IF would then
    guard only what was put there, and the move itself would run whatever the
    condition."""
    index_of = {id(m.syntax): k for k, m in enumerate(program.motions)}
    found: set[int] = set()
    stack = _routine_bodies(program)
    while stack:
        for statement in stack.pop():
            if isinstance(statement, CompactIf):
                k = index_of.get(id(statement.statement))
                if k is not None:
                    found.add(k)
            stack.extend(statement.bodies())
    return found


def _routine_bodies(program: Program) -> list[list[Statement]]:
    """The statement lists of every routine of `program` and of its handlers."""
    bodies: list[list[Statement]] = []
    for module in program.syntax.modules:
        for item in module.items:
            if isinstance(item, Routine):
                bodies.append(item.body)
                bodies.extend(h.body for h in item.handlers)
    return bodies
