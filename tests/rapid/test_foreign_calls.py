"""Targets passed to procedures rapidfix does not know as motions are found (and only those)."""

from __future__ import annotations

from rapidfix.rapid import parse_program
from rapidfix.rapid.foreign_calls import foreign_target_calls

TARGET = "[[600,0,700],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
JOINTS = "[[0,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"

PROGRAM = f"""MODULE Weld
  CONST robtarget p10 := {TARGET};
  CONST robtarget p20 := {TARGET};
  CONST robtarget ps{{2}} := [{TARGET},{TARGET}];
  CONST jointtarget jHome := {JOINTS};
  PERS tooldata tWeld := [TRUE,[[0,0,200],[1,0,0,0]],[2,[0,0,100],[1,0,0,0],0,0,0]];
  VAR pose found;
  VAR num n := 3;
  PROC main()
    MoveL p10, v100, fine, tWeld;
    Search_1D found, p10, p20, v200, tWeld;
    TPWrite "searching";
    SetDO doWeld, 1;
    go p20;
    WaitTime n;
    IF n > 2 THEN
      ArcCalcLStart Offs(p20,0,0,5), v100, seam1, weld1, fine, tWeld;
    ENDIF
    FOR i FROM 1 TO 2 DO
      OtherModuleMove ps{{i}}, v100;
    ENDFOR
    OtherModuleMove {TARGET}, v100;
    ArcMoveAbsJ jHome, v100, fine, tWeld;
    WZHomeJointDef \\Inside, zone, jHome, jHome;
  ERROR
    search_1d found, p20, RelTool(p10,0,0,5), v200, tWeld;
  ENDPROC
  PROC go(robtarget t)
    MoveL t, v100, fine, tWeld;
    Pass t;
  ENDPROC
ENDMODULE
"""


def _found(text: str) -> list[tuple[str, int, tuple[str, ...]]]:
    program = parse_program(text, "weld.mod")
    return [(c.name, program.source.line_column(c.start)[0], c.targets)
            for c in foreign_target_calls(program)]


def test_calls_passing_targets_to_unknown_procedures_are_found():
    assert _found(PROGRAM) == [
        ("Search_1D", 11, ("p10", "p20")),
        ("ArcCalcLStart", 17, ("Offs(p20,0,0,5)",)),
        ("OtherModuleMove", 20, ("ps{i}",)),
        ("OtherModuleMove", 22, (TARGET,)),
        ("ArcMoveAbsJ", 23, ("jHome",)),
        ("search_1d", 26, ("p20", "RelTool(p10,0,0,5)")),
        ("Pass", 30, ("t",)),  # a robtarget parameter handed on
    ]


def test_motions_own_routines_and_calls_without_targets_are_not():
    program = f"""MODULE Plain
  CONST robtarget p10 := {TARGET};
  CONST jointtarget jHome := {JOINTS};
  VAR num n := 3;
  PROC main()
    MoveL p10, v100, fine, tool0;
    MoveAbsJ jHome, v100, fine, tool0;
    TriggL Offs(p10,0,0,5), v100, trig, z10, tool0;
    go p10;
    TPWrite "x" \\Num:=n;
    WaitTime n;
    WZHomeJointDef \\Inside, zone, jHome, jHome;
    ReadAnyBin channel, p10;
    WriteAnyBin channel, p10;
  ENDPROC
  PROC go(robtarget t)
    MoveL t, v100, fine, tool0;
  ENDPROC
ENDMODULE
"""
    assert _found(program) == []


def test_targets_in_calls_that_share_their_text_after_the_first_argument():
    """The fast path reads repeated call tails once (`Offs(p1,0,0,5)`, `Offs(p2,0,0,5)`:
    a lazily made Call); such a target is a target all the same."""
    moves = "".join(f"    Search_1D found, Offs(p{k % 2 + 1},0,0,5), p{k % 2 + 1}, v200, tool0;\n"
                    for k in range(6))
    program = (f"MODULE Many\n  CONST robtarget p1 := {TARGET};\n  CONST robtarget p2 := "
               f"{TARGET};\n  VAR pose found;\n  PROC main()\n{moves}  ENDPROC\nENDMODULE\n")
    found = _found(program)
    assert [(line, targets) for _, line, targets in found] == [
        (6 + k, (f"Offs(p{k % 2 + 1},0,0,5)", f"p{k % 2 + 1}")) for k in range(6)]
