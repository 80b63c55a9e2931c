"""Motion instructions as data: the required parameters of each, in order.

A parameter named ToPoint or CirPoint is a robtarget; ToJointPos is a
jointtarget; Speed, Zone and Tool have their usual roles; the work object is
always the optional argument `\\WObj`. To support another instruction, add a
line to `_TABLE` (names as in ABB's technical reference manual).

A parameter in brackets was required in an older RobotWare and is optional
since: arc welding's Weave is written `\\Weave:=w` in RobotWare 6 and later
(`ArcL p, v100, seam, weld \\Weave:=w, z1, tWeld;`) and as a required argument
after Weld before (`ArcL p, v100, seam, weld, w, z1, tWeld;`). A call with one
required argument more than the table's short form is read with the long one
(MotionSpec.legacy).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

_TABLE = """
MoveL       ToPoint Speed Zone Tool
MoveJ       ToPoint Speed Zone Tool
MoveC       CirPoint ToPoint Speed Zone Tool
MoveAbsJ    ToJointPos Speed Zone Tool
MoveExtJ    ToJointPos Speed Zone
MoveLDO     ToPoint Speed Zone Tool Signal Value
MoveJDO     ToPoint Speed Zone Tool Signal Value
MoveCDO     CirPoint ToPoint Speed Zone Tool Signal Value
MoveLAO     ToPoint Speed Zone Tool Signal Value
MoveJAO     ToPoint Speed Zone Tool Signal Value
MoveCAO     CirPoint ToPoint Speed Zone Tool Signal Value
MoveLGO     ToPoint Speed Zone Tool Signal Value
MoveJGO     ToPoint Speed Zone Tool Signal Value
MoveCGO     CirPoint ToPoint Speed Zone Tool Signal Value
MoveLSync   ToPoint Speed Zone Tool ProcName
MoveJSync   ToPoint Speed Zone Tool ProcName
MoveCSync   CirPoint ToPoint Speed Zone Tool ProcName
MoveLFF     ToPoint Speed Zone Tool
TriggL      ToPoint Speed Trigg1 Zone Tool
TriggJ      ToPoint Speed Trigg1 Zone Tool
TriggC      CirPoint ToPoint Speed Trigg1 Zone Tool
TriggLIOs   ToPoint Speed Zone Tool
TriggJIOs   ToPoint Speed Zone Tool
SearchL     Signal SearchPoint ToPoint Speed Tool
SearchC     Signal SearchPoint CirPoint ToPoint Speed Tool
SearchExtJ  Signal SearchJointPos ToJointPos Speed
ArcL        ToPoint Speed Seam Weld [Weave] Zone Tool
ArcC        CirPoint ToPoint Speed Seam Weld [Weave] Zone Tool
ArcLStart   ToPoint Speed Seam Weld [Weave] Zone Tool
ArcLEnd     ToPoint Speed Seam Weld [Weave] Zone Tool
ArcCStart   CirPoint ToPoint Speed Seam Weld [Weave] Zone Tool
ArcCEnd     CirPoint ToPoint Speed Seam Weld [Weave] Zone Tool
CapL        ToPoint Speed Cdata Weavestart Weave Zone Tool
CapC        CirPoint ToPoint Speed Cdata Weavestart Weave Zone Tool
PaintL      ToPoint Speed Zone Tool
PaintC      CirPoint ToPoint Speed Zone Tool
DispL       ToPoint Speed Zone Tool
DispC       CirPoint ToPoint Speed Zone Tool
"""

ROBTARGET_PARAMETERS = frozenset({"topoint", "cirpoint"})
JOINTTARGET_PARAMETERS = frozenset({"tojointpos"})

# Procedures that write into one of their required arguments: parameter index.
# (User routines in the same file are analysed from their parameter modes.)
WRITING_PROCEDURES: dict[str, tuple[int, ...]] = {
    "searchl": (1,),
    "searchc": (1,),
    "searchextj": (1,),
    "readanybin": (1,),
    "getdataval": (1,),
    "unpackrawbytes": (2,),
    "rmqgetmsgdata": (1,),
    "readcfgdata": (2,),
    "readvararr": (2,),
}


# Motion instructions that may stop short of their target: a search stops where its
# signal changes, so where the robot is after one is known only at run time.
STOPS_SHORT = frozenset({"searchl", "searchc", "searchextj"})


# Procedures that take targets without moving the robot to them: a world zone's
# joint limits, the recorded positions of a tool calibration, the points a program or
# external axes displacement is measured from, data read, written, packed or sent (and
# every procedure of WRITING_PROCEDURES).
NON_MOVING_PROCEDURES = frozenset({
    "wzhomejointdef", "wzlimjointdef", "mtooltcpcalib", "mtoolrotcalib", "stooltcpcalib",
    "stoolrotcalib", "pdispon", "eoffson", "writeanybin", "setdataval", "setalldataval",
    "packrawbytes", "rmqsendmessage", "rmqsendwait", "writevar", "writecfgdata",
    *WRITING_PROCEDURES,
})

# Functions whose value is known only at run time (a reason, not a guess).
RUNTIME_FUNCTIONS = frozenset({
    "crobt", "cjointt", "calcrobt", "calcjointt", "readnum", "readstr", "readbin",
    "readmotor", "cpos", "ctool", "cwobj", "readstrbin", "readvar",
})


@dataclass(frozen=True)
class MotionSpec:
    """One motion instruction: its name and its required parameters in order.

    `legacy` is the same instruction with the required parameters of an older
    RobotWare (one more: see the module's docstring), or None.
    """

    name: str
    parameters: tuple[str, ...]
    legacy: MotionSpec | None = field(default=None, compare=False)

    def for_call(self, required: int) -> MotionSpec:
        """The form of this instruction a call with `required` required arguments uses."""
        legacy = self.legacy
        if legacy is not None and required == len(legacy.parameters):
            return legacy
        return self

    # The derived attributes are cached: they are asked for once per move of a
    # program (a frozen dataclass still has an instance dict for cached_property).
    @cached_property
    def target_parameters(self) -> tuple[str, ...]:
        """Parameters that are targets (CirPoint before ToPoint), as written."""
        return tuple(p for p in self.parameters
                     if p.lower() in ROBTARGET_PARAMETERS | JOINTTARGET_PARAMETERS)

    @cached_property
    def target_keys(self) -> tuple[str, ...]:
        """`target_parameters` in lower case, as MotionInstruction.arguments keys them."""
        return tuple(p.lower() for p in self.target_parameters)

    @cached_property
    def target_kind(self) -> str:
        """'jointtarget' for joint moves (MoveAbsJ, MoveExtJ, ...), else 'robtarget'."""
        keys = {p.lower() for p in self.parameters}
        return "jointtarget" if keys & JOINTTARGET_PARAMETERS else "robtarget"

    def position_of(self, parameter: str) -> int | None:
        """Index of a required parameter (case-insensitive), or None."""
        key = parameter.lower()
        for i, name in enumerate(self.parameters):
            if name.lower() == key:
                return i
        return None


def _load(table: str) -> dict[str, MotionSpec]:
    specs = {}
    for line in table.strip().splitlines():
        name, *params = line.split()
        short = tuple(p for p in params if not p.startswith("["))
        legacy = None
        if len(short) != len(params):
            legacy = MotionSpec(name, tuple(p.strip("[]") for p in params))
        specs[name.lower()] = MotionSpec(name, short, legacy)
    return specs


MOTION_INSTRUCTIONS: dict[str, MotionSpec] = _load(_TABLE)


def motion_spec(name: str) -> MotionSpec | None:
    """The spec of a motion instruction by (case-insensitive) name, or None."""
    return MOTION_INSTRUCTIONS.get(name.lower())
