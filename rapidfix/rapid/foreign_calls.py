"""Targets handed to procedures that are not motion instructions rapidfix knows.

A process option's instruction (SmarTac's `Search_1D`, `ArcCalcLStart`, ...) or a
routine of another module may move the robot to a robtarget it is given. What it
does with it cannot be known from this file, so such a target is left as written;
`foreign_target_calls` finds those calls, so that a rewrite can say so rather than
leave them silently. Routines of the program itself are not foreign: the moves in
their bodies are the program's own motions.
"""

from __future__ import annotations

from dataclasses import dataclass

from rapidfix.rapid import syntax as s
from rapidfix.rapid.instructions import NON_MOVING_PROCEDURES
from rapidfix.rapid.program import Program
from rapidfix.rapid.values import TARGET_TYPES, fits_type

#: functions whose value is a robtarget made from a target argument
_TARGET_FUNCTIONS = frozenset({"offs", "reltool"})


@dataclass(frozen=True)
class ForeignCall:
    """A call of procedure `name` at offset `start` passing `targets` (as written)."""

    name: str
    start: int
    targets: tuple[str, ...]


def _is_target(expr: s.Expr | None, program: Program, routine: s.Routine) -> bool:
    if isinstance(expr, s.Index):
        return _is_target(expr.base, program, routine)
    if isinstance(expr, s.NameRef):
        key = expr.name.lower()
        for param in routine.parameters:
            if param.name.lower() == key:
                return param.type_name.lower() in TARGET_TYPES
        decl = program.declaration(expr.name, routine.name)
        return decl is not None and decl.type_key in TARGET_TYPES
    if isinstance(expr, s.Call):  # LazyFunctionCall too
        return expr.name.lower() in _TARGET_FUNCTIONS
    if isinstance(expr, s.NumericAggregate):
        return any(fits_type(t, expr.value) for t in TARGET_TYPES)
    return False


def foreign_target_calls(program: Program) -> list[ForeignCall]:
    """Every call, in text order, of a procedure that is neither a motion instruction
    rapidfix knows nor a routine of this program (nor one known to take targets without
    moving to them, `instructions.NON_MOVING_PROCEDURES`), and that passes a robtarget or a
    jointtarget (a named one, `Offs`/`RelTool` of one, or one written inline)."""
    own = {item.name.lower() for module in program.syntax.modules for item in module.items
           if isinstance(item, s.Routine)}
    foreign: dict[str, bool] = {}  # call name -> not a routine of the program's own
    found: list[ForeignCall] = []
    text = program.text
    for statement, routine in program.other_calls:  # the calls of no motion instruction
        name = statement.name
        other = foreign.get(name)
        if other is None:
            key = name.lower()
            other = foreign[name] = key not in own and key not in NON_MOVING_PROCEDURES
        if not other:
            continue
        targets = tuple(text[a.value.start:a.value.end] for a in statement.args
                        if _is_target(a.value, program, routine))
        if targets:
            found.append(ForeignCall(name, statement.start, targets))
    found.sort(key=lambda call: call.start)
    return found


__all__ = ["ForeignCall", "foreign_target_calls"]
