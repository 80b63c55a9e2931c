"""The RAPID language layer: parse ABB RAPID, model its data and motions, edit spans.

Start with `parse_program(text_or_bytes, filename)` or `load_program(path)`;
rewrite with `rapidfix.rapid.edit.Editor`; format values with
`rapidfix.rapid.format`.
"""

from rapidfix.rapid.evaluate import NotConstant
from rapidfix.rapid.instructions import MOTION_INSTRUCTIONS, MotionSpec, motion_spec
from rapidfix.rapid.parse import load_program, parse_program
from rapidfix.rapid.program import (
    Declaration,
    ModuleInfo,
    MotionInstruction,
    Operand,
    Program,
    RoutineInfo,
)
from rapidfix.rapid.source import SourceText
from rapidfix.rapid.span import Span
from rapidfix.rapid.values import (
    JointTarget,
    LoadData,
    Pose,
    RobTarget,
    SpeedData,
    ToolData,
    WobjData,
    ZoneData,
)

__all__ = [
    "MOTION_INSTRUCTIONS",
    "Declaration",
    "JointTarget",
    "LoadData",
    "ModuleInfo",
    "MotionInstruction",
    "MotionSpec",
    "NotConstant",
    "Operand",
    "Pose",
    "Program",
    "RobTarget",
    "RoutineInfo",
    "SourceText",
    "Span",
    "SpeedData",
    "ToolData",
    "WobjData",
    "ZoneData",
    "load_program",
    "motion_spec",
    "parse_program",
]
