"""The RAPID language layer: parse ABB RAPID, model its data and motions, edit spans.

Start with `parse_program(text_or_bytes, filename)` or `load_program(path)`;
rewrite with `Editor`; format values with the `format_*` functions (all exported here).
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.rapid.evaluate import NotConstant
from rapidfix.rapid.instructions import MOTION_INSTRUCTIONS, STOPS_SHORT, MotionSpec, motion_spec
from rapidfix.rapid.parse import load_program, parse_owned, parse_program
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

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.rapid.edit import Editor, ends_its_line
    from rapidfix.rapid.fastpath import blank_comments
    from rapidfix.rapid.foreign_calls import foreign_target_calls
    from rapidfix.rapid.format import (
        format_declaration,
        format_jointtarget,
        format_num,
        format_robtarget,
        format_string,
        format_tooldata,
        format_value,
    )
    from rapidfix.rapid.readback import (
        ReadBack,
        one_per_shape,
        read_jointtarget_declarations,
        read_robtarget_declarations,
        read_robtarget_literals,
        read_targets_full,
        read_targets_in_bulk,
    )
    from rapidfix.rapid.syntax import (
        Assignment,
        CompactIf,
        NameRef,
        Node,
        Number,
        ProcedureCall,
        Routine,
        Statement,
        String,
    )
    from rapidfix.rapid.syntax_errors import placeholders_in
    from rapidfix.rapid.system_data import SYSTEM_DATA
    from rapidfix.rapid.target_list import target_rows
    from rapidfix.rapid.values import typed_value

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "SYSTEM_DATA": "system_data",
    "Assignment": "syntax",
    "CompactIf": "syntax",
    "Editor": "edit",
    "ends_its_line": "edit",
    "blank_comments": "fastpath",
    "NameRef": "syntax",
    "Node": "syntax",
    "Number": "syntax",
    "ProcedureCall": "syntax",
    "ReadBack": "readback",
    "Routine": "syntax",
    "Statement": "syntax",
    "String": "syntax",
    "foreign_target_calls": "foreign_calls",
    "format_declaration": "format",
    "format_jointtarget": "format",
    "format_num": "format",
    "format_robtarget": "format",
    "format_string": "format",
    "format_tooldata": "format",
    "format_value": "format",
    "one_per_shape": "readback",
    "placeholders_in": "syntax_errors",
    "read_jointtarget_declarations": "readback",
    "read_robtarget_declarations": "readback",
    "read_robtarget_literals": "readback",
    "read_targets_full": "readback",
    "read_targets_in_bulk": "readback",
    "target_rows": "target_list",
    "typed_value": "values",
}

__all__ = [
    "MOTION_INSTRUCTIONS",
    "STOPS_SHORT",
    "SYSTEM_DATA",
    "Assignment",
    "CompactIf",
    "Declaration",
    "Editor",
    "JointTarget",
    "LoadData",
    "ModuleInfo",
    "MotionInstruction",
    "MotionSpec",
    "NameRef",
    "Node",
    "NotConstant",
    "Number",
    "Operand",
    "Pose",
    "ProcedureCall",
    "Program",
    "ReadBack",
    "RobTarget",
    "Routine",
    "RoutineInfo",
    "SourceText",
    "Span",
    "SpeedData",
    "Statement",
    "String",
    "ToolData",
    "WobjData",
    "ZoneData",
    "blank_comments",
    "ends_its_line",
    "foreign_target_calls",
    "format_declaration",
    "format_jointtarget",
    "format_num",
    "format_robtarget",
    "format_string",
    "format_tooldata",
    "format_value",
    "load_program",
    "motion_spec",
    "one_per_shape",
    "parse_owned",
    "parse_program",
    "placeholders_in",
    "read_jointtarget_declarations",
    "read_robtarget_declarations",
    "read_robtarget_literals",
    "read_targets_full",
    "read_targets_in_bulk",
    "target_rows",
    "typed_value",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
