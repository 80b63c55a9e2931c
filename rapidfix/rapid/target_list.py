"""Every target of a program as flat rows: declarations of robtargets and
jointtargets, and motion arguments that are not a plain declared name."""

from __future__ import annotations

from dataclasses import dataclass

from rapidfix.rapid.program import Program
from rapidfix.rapid.values import Value


@dataclass(frozen=True)
class TargetRow:
    name: str  # data name, or the argument text for inline/Offs/RelTool targets
    line: int
    column: int
    kind: str  # 'robtarget' | 'jointtarget'
    source: str  # 'declaration' or the instruction (e.g. 'MoveL')
    static: bool
    value: Value | None
    reason: str | None


def target_rows(program: Program) -> list[TargetRow]:
    """Rows in source order."""
    rows = []
    for decl in program.declarations:
        if decl.is_target:
            line, column = decl.span.source.line_column(decl.name_span.start)
            rows.append(TargetRow(decl.name, line, column, decl.type_key, "declaration",
                                  decl.static, decl.value, decl.reason))
    for motion in program.motions:
        for operand in motion.targets:
            if operand.form == "name" and operand.declaration is not None:
                continue
            span = operand.value_span or operand.span
            line, column = span.source.line_column(span.start)
            kind = "jointtarget" if motion.target_kind == "jointtarget" else "robtarget"
            rows.append(TargetRow(operand.text, line, column, kind, motion.name,
                                  operand.static, operand.value, operand.reason))
    rows.sort(key=lambda r: (r.line, r.column))
    return rows
