"""Program shapes neither program_shapes.py nor more_shapes.py writes, for checking that
speed holds (and grows linearly) on layouts the fast paths were not tuned on:

- many_procs:  a routine every three moves, each with its own VAR and a call chain
- frames:      a hundred tools, work objects and loads, moves cycling through them
- stacked:     several statements on one line, one-line IF around moves
- deep:        IF / ELSEIF / ELSE, TEST / CASE and WHILE nested five deep
- expressions: targets and offsets written with named num constants and arithmetic
- modules:     a .prg of many small modules
- wide:        long comment lines with non-ASCII text, long identifiers, `\\Conc`, `\\ID`
- assign:      targets assigned in code (`pCur := Offs(...)`, `pCur.trans.z := ...`), counters
- io:          I/O, waits and messages with strings between the moves
- loops:       FOR loops around moves to `Offs` of the loop variable
- failing:     a third of the targets out of reach, a third on a branch nothing is on
- records:     offsets written with record components of tools and targets
- messages:    strings holding commas, semicolons and brackets, strings in sums and in
               parentheses, between the moves
- conditions:  IF / ELSEIF / WHILE heads with relations and logic, WaitUntil with
               conditions, a FUNC that RETURNs
- feeds:       a robot-offline-programming post: `ConfL\\Off`, inline targets and inline
               speeddata whose speed changes with every move, one move a line
- tails:       named targets, every move with its own `\\V:=` and `\\Z:=` (no two tails alike)
- five_axis:   targets whose orientation changes with every point (a tool tilted along
               the surface), declared and inline
- track:       a robot on a track: the first external axis changes with every target
- remarks:     a comment after every statement on its line, declarations and moves
- spaced:      a space after every comma and around `:=` (hand-written and some posts'
               style), declared and inline targets, some declarations over three lines
- latin1:      a Swedish or German cell: targets, tool, work object, speed and routines
               named with the letters of ISO 8859-1 RAPID allows (`pÖver`, `tFräs`)
- concurrent:  a handling cell: switches before the target (`MoveJ \\Conc, p1, ...`,
               `MoveL \\Conc, Offs(p1,0,0,50), ...`), some with `\\ID`, and
               `WaitTime \\InPos` between the moves
- flips:       pick and place from joint targets: `MoveAbsJ` to a jointtarget 50 mm
               above each point, then `MoveL` down to it. Each line starts where the
               MoveAbsJ (written as it is) leaves the robot, off the intended start;
               every third jointtarget has the wrist flipped, so its line down swings
               through the wrist singularity: the path check's hopeless segments
- lone_cr:     a file from an old Mac editor: every line ends in a lone CR (no LF
               anywhere), with comments on their own lines and after statements
- arc_weld:    an arc-welding cell (the Arc option's instructions): `ArcLStart`, `ArcL`
               with `\\Weave` between its welddata and zone, `ArcC` with its circle
               point, `ArcLEnd`, seam, weld and weave data; MoveJ between the seams
- wrapped:     a post that wraps long lines: every inline target goes on over a second
               line, so a statement spans two
- hand_offs:   a hand-written pick and place: MoveJ above each point by `Offs`, MoveL down
               to it and up again, every call spaced after its commas
- reltool:     a deburring post: every target turned and drawn back by
               `RelTool(p, 0, 0, -2 \\Rz:=30)`, spaced or tight
- lower:       a program typed in lower case: keywords, instructions, type names, TRUE
               and FALSE, `\\wobj:=`
- upper:       the same in upper case throughout, names and all
- exponent:    positions written in exponent form (`-1.495000E+02`)
- data_last:   the routines first, the targets declared after them
- elements:    targets in arrays of a hundred declared over lines, every move to one element
               (`MoveL seam3{17}, ...`)
- routine_targets: a pick routine taking its target as a parameter, called once per
               point after a move above it, with `MoveLDO` (its moves are known only at
               run time)
- scoped:      a system module (`MODULE m(SYSMODULE, NOSTEPIN)`) of LOCAL, TASK PERS and
               VAR targets, LOCAL routines, moves with `\\TLoad` (some with `load0`, the
               tool's own load) and GripLoad between them
- nested_calls: targets moved by a call of a call, `RelTool(Offs(p, 0, 0, 5), 0, 0, 0
               \\Rz:=30)` or `Offs(RelTool(...), ...)`, tight or spaced
- spaced_brackets: targets spaced inside their brackets (`[ [x, y, z], [ ... ], ... ]`),
               declared for half the moves, inline in the others
- one_routine: a CAM post that writes every move into one routine, inline targets
               (no routine ever ends before the file does)
- compact_ifs: every other statement a compact IF (`IF bOn AND n >= 0 MoveL ...;`,
               `IF DInput(diReady) = 1 SetDO doGo, 1;`), no THEN
- paren_calls: function calls inside parentheses (`WaitUntil (DInput(di) = 1)
               \\MaxTime:=(nWait * 2);`, `TPWrite "x=" + (NumToStr(n, 1) + " mm");`)
- grids:       targets in two-dimensional arrays of 100 rows of 10, a row to a line,
               every move to one element (`MoveL grid3{17,4}, ...`)
- record_tables: arrays of a RECORD type, a row (`[17,"S17",3.5,[2,1,0]]`) to a line,
               four rows for each move
- inline_data: declared targets whose numbers carry all the digits a double holds
               (`-149.50012345678901`, `0.2588190451025207`), moves with inline
               speeddata and zonedata aggregates, `\\T:=` times
- one_line:    `hand_offs` with every statement on one line, MODULE to ENDMODULE (a
               program written by another program); its "lines" are those of `hand_offs`

`odd_program(shape, lines)` gives about `lines` lines of that shape (`odd_lines` counts
them).
"""

from __future__ import annotations

import functools
import re

import numpy as np
from cam_program import ROBOT, ROT, TOOL, WOBJ, _frame, cam_positions
from program_shapes import EXTAX, _head, _robtarget, _targets
from scipy.spatial.transform import Rotation

from rapidfix.kinematics import load_robot

ODD_SHAPES = ("many_procs", "frames", "stacked", "deep", "expressions", "modules", "wide",
              "assign", "io", "loops", "failing", "records", "messages", "conditions",
              "feeds", "tails", "five_axis", "track", "remarks", "spaced", "latin1",
              "concurrent", "flips", "lone_cr", "arc_weld", "wrapped", "scoped", "hand_offs",
              "reltool", "lower", "upper", "exponent", "data_last", "elements",
              "routine_targets", "nested_calls", "spaced_brackets", "one_routine",
              "inline_data", "long_names", "deep_calls", "compact_ifs", "paren_calls", "grids",
              "record_tables", "multimove", "one_line", "labels", "computed", "pallet",
              "callers", "guards")


def _decls(n: int, prefix: str = "p") -> list[str]:
    trans, confs = _targets(n)
    return [f"  CONST robtarget {prefix}{i}:={_robtarget(trans[i], confs[i])};"
            for i in range(n)]


def _many_procs(n: int) -> list[str]:
    out = [*_head("ManyProcs"), *_decls(n)]
    procs = (n + 2) // 3
    for r in range(procs):
        out += [f"  PROC R{r}()", "    VAR num k:=0;"]
        for k in range(3 * r, min(n, 3 * r + 3)):
            out.append(f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;")
        out += ["    k:=k + 1;", *([f"    R{r + 1};"] if r + 1 < procs else []), "  ENDPROC"]
    return [*out, "  PROC main()", "    R0;", "  ENDPROC", "ENDMODULE"]


def _frames(n: int) -> list[str]:
    out = [*_head("Frames")]
    count = 100
    for i in range(count):
        out.append(f"  PERS tooldata tool{i}:=[TRUE,[[{i % 7},{i % 5},{100 + i}],[1,0,0,0]],"
                   f"[{1 + i % 4},[0,0,{40 + i}],[1,0,0,0],0,0,0]];")
        out.append(f'  PERS wobjdata wobj{i}:=[FALSE,TRUE,"",[[{850 + i % 3},{80 + i % 5},450],'
                   "[0.923879533,0.0,-0.382683432,0.0]],[[0,0,0],[1,0,0,0]]];")
        out.append(f"  PERS loaddata load{i}:=[{0.5 + i % 6},[0,0,{10 + i}],[1,0,0,0],0,0,0];")
    out += _decls(n)
    moves = []
    for k in range(n):
        if k % 10 == 0:
            moves.append(f"    GripLoad load{(k // 10) % count};")
        moves.append(f"    MoveL p{k},v100,z1,tool{k % count}\\WObj:=wobj{(k * 7) % count};")
    for first in range(0, len(moves), 400):
        out += [f"  PROC Part{first // 400}()", *moves[first:first + 400], "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _stacked(n: int) -> list[str]:
    out = [*_head("Stacked"), "  PERS bool bOn:=TRUE;", *_decls(n), "  PROC main()"]
    for k in range(0, n, 3):
        group = [f"MoveL p{j}, v100, z1, tMill\\WObj:=wPlate;" for j in range(k, min(n, k + 3))]
        if k % 2:
            out.append("    IF bOn THEN " + " ".join(group) + " ENDIF")
        else:
            out.append("    " + " ".join(group))
    return [*out, "  ENDPROC", "ENDMODULE"]


def _deep(n: int) -> list[str]:
    out = [*_head("Deep"), "  VAR num nMode:=1;", "  VAR num i:=0;", *_decls(n)]
    blocks = []
    for k in range(0, n, 5):
        moves = [f"MoveL p{j},v100,z1,tMill\\WObj:=wPlate;" for j in range(k, min(n, k + 5))]
        blocks.append(["    IF nMode > 0 THEN", "      TEST nMode", "      CASE 1, 2:",
                       "        WHILE i < 1 DO", "          IF i = 0 THEN",
                       *(f"            {m}" for m in moves[:3]),
                       "          ELSEIF i = 2 THEN", "            i:=3;", "          ELSE",
                       *(f"            {m}" for m in moves[3:]),
                       "          ENDIF", "          i:=i + 1;", "        ENDWHILE",
                       "      DEFAULT:", "        nMode:=1;", "      ENDTEST", "    ENDIF",
                       "    i:=0;"])
    for first in range(0, len(blocks), 50):
        out += [f"  PROC Job{first // 50}()",
                *(line for block in blocks[first:first + 50] for line in block), "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _expressions(n: int) -> list[str]:
    trans, confs = _targets(n)
    out = [*_head("Expressions"), "  CONST num nStep:=0.5;", "  CONST num nLift:=2*nStep;",
           "  CONST num nHalf:=nStep/2;"]
    for i in range(n):
        x, y, z = (float(v) for v in trans[i].strip("[]").split(","))
        out.append(f"  CONST robtarget p{i}:=[[{x + 1:.3f}-1,{y:.3f}+0*nStep,{z:.3f}],"
                   f"{_robtarget('[0,0,0]', confs[i])[9:]};")
    moves = []
    for k in range(n):
        if k % 2:
            moves.append(f"    MoveL Offs(p{k},nStep-nHalf*2,0,-nLift+2*nStep),v100,z1,"
                         "tMill\\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL p{k},[100+nStep*2,500,5000,1000],z1,tMill\\WObj:=wPlate;")
    for first in range(0, n, 500):
        out += [f"  PROC Part{first // 500}()", *moves[first:first + 500], "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _modules(n: int) -> list[str]:
    out = ["%%%", "  VERSION:1", "  LANGUAGE:ENGLISH", "%%%", ""]
    trans, confs = _targets(n)
    per = 20
    for m, first in enumerate(range(0, n, per)):
        ks = range(first, min(n, first + per))
        out += [*_head(f"Mod{m}"),
                *(f"  LOCAL CONST robtarget q{k}:={_robtarget(trans[k], confs[k])};" for k in ks),
                f"  PROC Run{m}()",
                *(f"    MoveL q{k},v100,z1,tMill\\WObj:=wPlate;" for k in ks),
                "  ENDPROC", "ENDMODULE", ""]
    return out[:-1]


def _wide(n: int) -> list[str]:
    name = "pWeldSeamStartApproachPositionOfTheLeftHandBracket"
    out = [*_head("Wide"), "  VAR syncident sync1;", *_decls(n, name)]
    moves = []
    for k in range(n):
        if k % 3 == 0:
            moves.append(f"    ! Schweißnaht Nr. {k} — Übergang zur nächsten Spur, Ø 12 mm, "
                         "Düse 45°, " + "Ausrichtung prüfen " * 20)
        if k % 4 == 0:
            moves.append(f"    MoveL {name}{k},v100\\V:=1200,z1\\Z:=5,tMill\\WObj:=wPlate;")
        elif k % 4 == 1:
            moves.append(f"    MoveJ\\Conc,{name}{k},v200,z10,tMill\\WObj:=wPlate;")
        elif k % 4 == 2:
            moves.append(f"    MoveL\\Conc,{name}{k},v100,fine\\Inpos:=inpos50,tMill"
                         "\\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL {name}{k},v100,z1,tMill\\WObj:=wPlate;")
    for first in range(0, len(moves), 500):
        out += [f"  PROC Part{first // 500}()", *moves[first:first + 500], "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _parts(moves: list[str], per: int = 500) -> list[str]:
    out = []
    for first in range(0, len(moves), per):
        out += [f"  PROC Part{first // per}()", *moves[first:first + per], "  ENDPROC"]
    return out


def _labels(n: int) -> list[str]:
    """Routines of blocks with a label inside a WHILE (a retry point, and a compact IF's
    GOTO to it): the statements a compound-statement reader does not take stand deep in
    every routine."""
    out = [*_head("Labels"), "  VAR num i:=0;", "  VAR num nTry:=0;", *_decls(n)]
    for first in range(0, n, 6):
        moves = [f"MoveL p{j},v100,z1,tMill\\WObj:=wPlate;"
                 for j in range(first, min(n, first + 6))]
        out += [f"  PROC Part{first // 6}()", "    i:=0;", "    WHILE i < 2 DO",
                "      IF i = 0 THEN", *(f"        {m}" for m in moves[:3]), "      ENDIF",
                "      lRetry:", *(f"      {m}" for m in moves[3:]), "      i:=i + 1;",
                "      nTry:=nTry + 1;", "      IF nTry < 0 GOTO lRetry;", "    ENDWHILE",
                "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _computed(n: int) -> list[str]:
    """Hand-written arithmetic the runs of calls do not take: a target's position set
    from sums with parentheses before a move to it (left as written: its target is set
    at run time), then a WaitUntil of a relation to an aggregate of strings, or an
    assignment of a call of parenthesised sums, and a move to a declared target."""
    out = [*_head("Computed"), "  VAR robtarget pCur;", "  VAR num nX:=1;", "  VAR num nY:=2;",
           "  VAR num nZ:=3;", "  VAR num nDx:=0.5;", "  VAR string stReact{3};",
           "  VAR num i:=0;", *_decls(n), "  PROC main()", "    pCur:=p0;"]
    for k in range(n):
        out += [f"    pCur.trans:=[nX+({k % 100}*nDx),nY-(2*nDx),nZ];",
                "    MoveL pCur,v100,z1,tMill\\WObj:=wPlate;",
                '    WaitUntil stReact=["Ready","Ready","Ready"];' if k % 2 == 0
                else "    i:=Trunc((nX-nY)*1000);",
                f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;"]
    return [*out, "  ENDPROC", "ENDMODULE"]


def _pallet(n: int) -> list[str]:
    """Palletising: each layer above its first point, then rows and columns in FOR loops,
    each place an Offs of parenthesised sums of the loop variables (left as written: the
    loop sets them at run time), then the layer's other points by name."""
    out = [*_head("Pallet"), "  VAR num nPitch:=0.5;", "  VAR num nH:=10;", *_decls(n)]
    for first in range(0, n, 20):
        out += [f"  PROC Layer{first // 20}()",
                f"    MoveJ Offs(p{first},0,0,50),v1000,z50,tMill\\WObj:=wPlate;",
                "    FOR i FROM 1 TO 3 DO", "      FOR j FROM 1 TO 3 DO",
                f"        MoveL Offs(p{first}, (i-1)*nPitch, (j-1)*nPitch, nH), v500, z10, "
                "tMill\\WObj:=wPlate;",
                f"        MoveL Offs(p{first}, (i-1)*nPitch, (j-1)*nPitch, 0), v100, fine, "
                "tMill\\WObj:=wPlate;",
                "        WaitTime 0.1;", "      ENDFOR", "    ENDFOR",
                *(f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;"
                  for k in range(first + 1, min(n, first + 20))),
                "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _callers(n: int) -> list[str]:
    """A cell that calls a station's routine by a name built at run time after every
    other move (`%"Station" + NumToStr(n, 0)%;`, `CallByVar`), and a routine of its own
    with a target and optional arguments (`Place p4 \\Speed:=v200, 20;`)."""
    out = [*_head("Callers"), "  VAR num nStation:=1;", *_decls(n),
           "  PROC Place(robtarget pT \\speeddata Speed, num nLift)",
           "    MoveL Offs(pT,0,0,nLift),v500,z10,tMill\\WObj:=wPlate;",
           "    MoveL pT,v100,fine,tMill\\WObj:=wPlate;", "  ENDPROC",
           "  PROC Station1()", "    Stop;", "  ENDPROC"]
    for first in range(0, n, 100):
        out.append(f"  PROC Run{first // 100}()")
        for k in range(first, min(n, first + 100)):
            move = f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;"
            out += ([f"    Place p{k} \\Speed:=v200, 20;"], [f"    Place p{k}, {10 + k % 7};"],
                    [move, '    %"Station" + NumToStr(nStation, 0)%;'],
                    [move, '    CallByVar "Station", nStation;'])[k % 4]
        out.append("  ENDPROC")
    return [*out, "ENDMODULE"]


def _guards(n: int) -> list[str]:
    """Guards written with parentheses, as a cell's programmer writes them: IF, ELSEIF and
    WHILE conditions in brackets, compact IFs that RAISE, RETURN or assign, and a compact
    IF whose call follows an aggregate's bracket straight away."""
    out = [*_head("Guards"), "  VAR num nMode:=1;", "  VAR num nCount:=0;",
           "  VAR num nWait:=0;", "  VAR bool bSkip:=FALSE;", "  VAR bool bReady:=TRUE;",
           "  VAR string stReact{2};", "  VAR errnum ERR_COUNT:=-1;", *_decls(n)]
    for first in range(0, n, 4):
        moves = [f"MoveL p{k},v100,z1,tMill\\WObj:=wPlate;"
                 for k in range(first, min(n, first + 4))]
        out += [f"  PROC Part{first // 4}()", "    IF (nMode = 1 AND NOT bSkip) THEN",
                *(f"      {m}" for m in moves[:2]), "    ELSEIF (nMode > 2) OR bSkip THEN",
                "      nCount := (nCount + 1) MOD 10;", "    ENDIF",
                "    IF (nCount >= 1000) RAISE ERR_COUNT;", "    IF (bSkip) RETURN;",
                '    IF stReact=["Stop","Stop"]Stop;',
                "    WHILE (nWait < 0) AND NOT bReady DO", "      nWait := nWait + 1;",
                "    ENDWHILE", *(f"    {m}" for m in moves[2:]), "  ENDPROC"]
    return [*out, "ENDMODULE"]


def _assign(n: int) -> list[str]:
    moves = []
    for k in range(n):
        moves += [f"    pCur := Offs(p{k}, 0.5, 0, 0);", "    pCur.trans.z := pCur.trans.z + 1;",
                  "    MoveL pCur, v100, z1, tMill\\WObj:=wPlate;", "    nDone:=nDone+1;",
                  f"    MoveL p{k}, v100, z1, tMill\\WObj:=wPlate;"]
    return [*_head("Assign"), "  VAR robtarget pCur;", "  VAR num nDone:=0;", *_decls(n),
            *_parts(moves, 800), "ENDMODULE"]


def _io(n: int) -> list[str]:
    moves = []
    for k in range(n):
        moves.append(f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;")
        moves.append(("    SetDO doGlue, 1;", "    WaitTime 0.2;",
                      f'    TPWrite "Point {k} reached, count " \\Num:=nCount;',
                      "    WaitDI diReady, 1;")[k % 4])
    return [*_head("Io"), "  VAR num nCount:=0;", *_decls(n), *_parts(moves, 1000), "ENDMODULE"]


def _loops(n: int) -> list[str]:
    moves = []
    for k in range(0, n, 2):
        moves += ["    FOR i FROM 0 TO 3 DO",
                  f"      MoveL Offs(p{k}, i*0.1, 0, 0), v100, z1, tMill\\WObj:=wPlate;",
                  "    ENDFOR", f"    MoveL p{k + 1}, v100, z1, tMill\\WObj:=wPlate;"]
    return [*_head("Loops"), "  VAR num i;", *_decls(n + 1), *_parts(moves, 800), "ENDMODULE"]


def _failing(n: int) -> list[str]:
    trans, confs = _targets(n)
    out = [*_head("Failing")]
    for i in range(n):
        t, c = trans[i], confs[i]
        if i % 3 == 1:  # out of reach
            x, y, z = (float(v) for v in t.strip("[]").split(","))
            t = f"[{x + 4000:.3f},{y:.3f},{z:.3f}]"
        elif i % 3 == 2:  # a branch no solution is on
            c = "[3,-4,5,0]"
        out.append(f"  CONST robtarget p{i}:={_robtarget(t, c)};")
    moves = [f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;" for k in range(n)]
    return [*out, *_parts(moves), "ENDMODULE"]


def _records(n: int) -> list[str]:
    moves = [f"    MoveL Offs(p{k},tMill.tframe.trans.x*0,p{k}.trans.x*0,0),v100,z1,"
             "tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("Records"), *_decls(n), *_parts(moves), "ENDMODULE"]


def _messages(n: int) -> list[str]:
    moves = []
    for k in range(n):
        moves.append(f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;")
        moves.append((f'    TPWrite "Point {k}, reached; next [p{k + 1}] (ok)";',
                      '    TPWrite "Count: " + NumToStr(nCount, 0) + "; of " + sTotal;',
                      f'    TPWrite("Drilling hole {k} of {n}!");',
                      '    sLast := "say ""done""" + sLast;')[k % 4])
    return [*_head("Messages"), "  VAR num nCount:=0;", '  VAR string sLast:="";',
            '  CONST string sTotal:="all, of them";', *_decls(n), *_parts(moves, 1000),
            "ENDMODULE"]


def _conditions(n: int) -> list[str]:
    blocks = []  # one string per block: a block stays in one routine
    for k in range(n):
        move = f"MoveL Offs(p{k},0,0,nLift),v100,z1,tMill\\WObj:=wPlate;"
        lines = ((f"    IF nCount > {k % 5} AND NOT bStop OR sMode = \"fast\" THEN",
                  f"      {move}", "    ELSEIF (nCount MOD 2 = 0) XOR bStop THEN",
                  f"      MoveJ p{k},v200,z5,tMill\\WObj:=wPlate;", "    ENDIF"),
                 ("    WHILE nCount < 2 AND DInput(diReady) = 1 DO",
                  "      nCount := Lift(nCount) + 1;", "    ENDWHILE", f"    {move}"),
                 ("    WaitUntil nCount >= 0 AND bStop = FALSE \\MaxTime:=5;",
                  f"    {move}"))[k % 3]
        blocks.append("\n".join(lines))
    return [*_head("Conditions"), "  VAR num nCount:=0;", "  VAR bool bStop:=FALSE;",
            '  VAR string sMode:="fast";', "  CONST num nLift:=0.5;", *_decls(n),
            "  FUNC num Lift(num level)", "    IF level <= 0 THEN", "      RETURN 0;",
            "    ENDIF", "    RETURN level * 0.5;", "  ENDFUNC", *_parts(blocks, 300),
            "ENDMODULE"]


def _feeds(n: int) -> list[str]:
    trans, confs = _targets(n)
    moves = ["    ConfL\\Off;", "    ConfJ\\Off;"] + [
        f"    MoveL {_robtarget(trans[k], confs[k])},[{20 + k % 97}.5,500,5000,1000],z1,"
        "tMill,\\WObj:=wPlate;" for k in range(n)]
    return [*_head("Feeds"), *_parts(moves, 2000), "ENDMODULE"]


def _one_routine(n: int) -> list[str]:
    trans, confs = _targets(n)
    moves = [f"    MoveL {_robtarget(trans[k], confs[k])},v100,z1,tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*_head("CamOne"), "  PROC main()", *moves, "  ENDPROC", "ENDMODULE"]


def _inline_data(n: int) -> list[str]:
    digits = [re.sub(r"(-?\d+\.\d{3})(?=[],])", rf"\g<1>{k % 97:02d}345678901",
                     line.replace("0.258819045", "0.2588190451025207")
                     .replace("0.965925826", "0.9659258262890683"))
              for k, line in enumerate(_decls(n))]
    timed = (" \\T:=0.5", "", "", "")
    moves = [f"    MoveL p{k}, [{100 + k % 50},500,5000,1000]{timed[k % 4]}, "
             f"[FALSE,{k % 5 + 1},{1.5 * (k % 5 + 1):g},0.3,0.3,0.03,0.3], tMill"
             "\\WObj:=wPlate;" for k in range(n)]
    return [*_head("InlineData"), *digits, *_parts(moves), "ENDMODULE"]


def _long_names(n: int) -> list[str]:
    """Targets named as a cell's programmer names them, near RAPID's 32 characters
    (`pPickPositionStationA_Slot00017`): `jt_` and such a name is cut, and the cut names
    of a hundred targets at a time are alike."""
    name = [f"pPickPositionStationA_Slot{k:05d}" for k in range(n)]
    decls = [line.replace(f"robtarget p{k}:=", f"robtarget {name[k]}:=")
             for k, line in enumerate(_decls(n))]
    moves = [f"    MoveL {name[k]}, v200, z1, tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("LongNames"), *decls, *_parts(moves), "ENDMODULE"]


def _tails(n: int) -> list[str]:
    moves = [f"    MoveL p{k},v100\\V:={100 + k % 997},z1\\Z:={1 + k % 13},"
             "tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("Tails"), *_decls(n), *_parts(moves), "ENDMODULE"]


@functools.lru_cache(maxsize=4)
def _tilted(n: int) -> tuple[str, ...]:
    """n reachable robtarget texts whose orientation turns from point to point."""
    robot = load_robot(ROBOT)
    k = np.arange(n)
    tilt = Rotation.from_euler("xy", np.c_[np.radians(8 * np.sin(k * 0.05)),
                                           np.radians(6 * np.cos(k * 0.03))])
    w, x, y, z = ROT
    rot = tilt * Rotation.from_quat([x, y, z, w])
    target = np.tile(np.eye(4), (n, 1, 1))
    target[:, :3, :3] = rot.as_matrix()
    target[:, :3, 3] = cam_positions(n)
    flange = _frame(*WOBJ) @ target @ np.linalg.inv(_frame(*TOOL))
    q, status = robot.ik_nearest(flange, np.radians([[8, 28, 35, 20, -20, 12]]))
    if not np.all(status == 0):  # pragma: no cover
        raise RuntimeError("a generated target is out of reach")
    quat = rot.as_quat()[:, [3, 0, 1, 2]]
    conf = robot.confdata(q).tolist()
    return tuple(f"[[{p[0]:.3f},{p[1]:.3f},{p[2]:.3f}],[{r[0]:.6f},{r[1]:.6f},{r[2]:.6f},"
                 f"{r[3]:.6f}],[{c[0]},{c[1]},{c[2]},{c[3]}],[{EXTAX}]]"
                 for p, r, c in zip(target[:, :3, 3].tolist(), quat.tolist(), conf))


def _five_axis(n: int) -> list[str]:
    targets = _tilted(n)
    half = n // 2
    decls = [f"  CONST robtarget p{k}:={targets[k]};" for k in range(half)]
    moves = [f"    MoveL {f'p{k}' if k < half else targets[k]},v100,z1,tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*_head("FiveAxis"), *decls, *_parts(moves), "ENDMODULE"]


def _track(n: int) -> list[str]:
    decls = [line.replace(f"[{EXTAX}]", f"[{1000 + 0.5 * k:.1f},9E+09,9E+09,9E+09,9E+09,"
                          "9E+09]") for k, line in enumerate(_decls(n))]
    moves = [f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("Track"), *decls, *_parts(moves), "ENDMODULE"]


def _remarks(n: int) -> list[str]:
    decls = [f"{line} ! point {k}, pass {k // 600}" for k, line in enumerate(_decls(n))]
    moves = [f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate; ! to point {k}; [x,y]"
             for k in range(n)]
    return [*_head("Remarks"), *decls, *_parts(moves), "ENDMODULE"]


def _spaced(n: int) -> list[str]:
    trans, confs = _targets(n)
    targets = [_robtarget(trans[k], confs[k]).replace(",", ", ") for k in range(n)]
    half = n // 2

    def over_lines(target: str) -> str:
        return "[\n    " + target[1:-1].replace("], [", "],\n    [") + "\n  ]"

    decls = [f"  CONST robtarget p{k} := {targets[k] if k % 7 else over_lines(targets[k])};"
             for k in range(half)]
    moves = [f"    MoveL {f'p{k}' if k < half else targets[k]}, v100, z1, tMill \\WObj := wPlate;"
             for k in range(n)]
    return [*_head("Spaced"), *decls, *_parts(moves), "ENDMODULE"]


def _latin1(n: int) -> list[str]:
    renamed = {"tMill": "tFräs", "wPlate": "wBänk", "vFeed": "vMatning_Å"}

    def swedish(line: str) -> str:
        for old, new in renamed.items():
            line = line.replace(old, new)
        return line

    decls = [line.replace(" p", " pÖver", 1) for line in _decls(n)]
    moves = [f"    Move{'LJ'[k % 2]} pÖver{k},{'vMatning_Å' if k % 3 else 'v200'},z1,tFräs"
             "\\WObj:=wBänk;" for k in range(n)]
    parts = [line.replace("PROC Part", "PROC Hämta") for line in _parts(moves)]
    calls = [f"    Hämta{k};" for k in range((n + 499) // 500)]
    return [*map(swedish, _head("Svets")), *decls, *parts, "  PROC Kör()", *calls,
            "  ENDPROC", "ENDMODULE"]


def _concurrent(n: int) -> list[str]:
    moves = []
    for k in range(n):
        if k % 3 == 0:
            moves.append(f"    MoveJ \\Conc, p{k}, v1000, z50, tMill\\WObj:=wPlate;")
        elif k % 3 == 1:
            moves.append(f"    MoveL \\Conc, Offs(p{k},0,0,50), v500, z10, tMill\\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL \\Conc \\ID:={k % 7}, p{k}, v200, fine, tMill\\WObj:=wPlate;")
        if k % 10 == 9:
            moves.append("    WaitTime \\InPos, 0.1;")
    return [*_head("Handling"), *_decls(n), *_parts(moves), "ENDMODULE"]


def _flips(n: int) -> list[str]:
    robot = load_robot(ROBOT)
    above = np.tile(_frame((0, 0, 0), ROT), (n, 1, 1))
    above[:, :3, 3] = cam_positions(n) + np.array([0.0, 0.0, 50.0])
    flange = _frame(*WOBJ) @ above @ np.linalg.inv(_frame(*TOOL))
    q, status = robot.ik_nearest(flange, np.radians([[8, 28, 35, 20, -20, 12]]))
    if not np.all(status == 0):  # pragma: no cover
        raise RuntimeError("a generated target is out of reach")
    flip = np.arange(n) % 3 == 2  # the same pose with the other wrist
    q[flip, 3] = np.angle(np.exp(1j * (q[flip, 3] + np.pi)))
    q[flip, 4] = -q[flip, 4]
    q[flip, 5] = np.angle(np.exp(1j * (q[flip, 5] + np.pi)))
    joints = [",".join(f"{v:.4f}" for v in row) for row in np.degrees(q).tolist()]
    decls = [f"  CONST jointtarget jAbove{k}:=[[{joints[k]}],[{EXTAX}]];" for k in range(n)]
    moves = []
    for k in range(n):
        moves += [f"    MoveAbsJ jAbove{k}\\NoEOffs,v1000,z50,tMill\\WObj:=wPlate;",
                  f"    MoveL p{k},v200,fine,tMill\\WObj:=wPlate;"]
    return [*_head("Flips"), *decls, *_decls(n), *_parts(moves), "ENDMODULE"]


def _lone_cr(n: int) -> list[str]:
    moves = [f"    MoveL p{k}, v100, z1, tMill\\WObj:=wPlate;"
             + (" ! approach" if k % 4 == 0 else "") for k in range(n)]
    for k in range(0, n, 25):
        moves[k] = f"    ! pass {k // 25}\n{moves[k]}"
    return [*_head("LoneCr"), "  ! every line of this file ends in a lone CR", *_decls(n),
            *_parts(moves), "ENDMODULE"]


def _arc_weld(n: int) -> list[str]:
    data = ["  PERS seamdata seam1:=[0.5,0.5,[5,0,24,120,0,0,0,0,0],0.5,1,10,0,5,"
            "[5,0,24,120,0,0,0,0,0],0,1,[5,0,24,120,0,0,0,0,0],0,0,[0,0,0,0,0,0,0,0,0],0];",
            "  PERS welddata weld1:=[10,0,[5,0,24,120,0,0,0,0,0],[0,0,0,0,0,0,0,0,0]];",
            "  PERS weavedata weave1:=[1,0,3,4,0,0,0,0,0,0,0,0,0,0,0];"]
    moves = []
    for k in range(n):
        step = k % 12
        if step == 0:
            moves.append(f"    MoveJ Offs(p{k},0,0,30),v1000,z20,tMill\\WObj:=wPlate;")
        elif step == 1:
            moves.append(f"    ArcLStart p{k},v100,seam1,weld1,fine,tMill\\WObj:=wPlate;")
        elif step == 6:  # an arc: its circle point, then its end
            moves.append(f"    ArcC p{k},p{k + 1},v100,seam1,weld1\\Weave:=weave1,z1,"
                         "tMill\\WObj:=wPlate;")
        elif step == 7:
            continue
        elif step == 11:
            moves.append(f"    ArcLEnd p{k},v100,seam1,weld1,fine,tMill\\WObj:=wPlate;")
        else:
            moves.append(f"    ArcL p{k},v100,seam1,weld1\\Weave:=weave1,z1,tMill\\WObj:=wPlate;")
    return [*_head("ArcWeld"), *data, *_decls(n), *_parts(moves), "ENDMODULE"]


def _wrapped(n: int) -> list[str]:
    trans, confs = _targets(n)
    moves = []
    for k in range(n):
        first, rest = _robtarget(trans[k], confs[k]).rsplit("],[", 1)
        moves += [f"    MoveL {first}],", f"        [{rest},v100,z1,tMill\\WObj:=wPlate;"]
    return [*_head("Wrapped"), *_parts(moves, 1000), "ENDMODULE"]


def _scoped(n: int) -> list[str]:
    head = _head("Scoped")
    head[0] = "MODULE Scoped(SYSMODULE, NOSTEPIN)"
    loads = ["  PERS loaddata lBox:=[2.5,[0,0,80],[1,0,0,0],0,0,0];",
             "  TASK PERS loaddata lPart:=[1.2,[0,10,40],[1,0,0,0],0,0,0];"]
    decls = [("  LOCAL CONST", "  TASK PERS", "  VAR")[i % 3] + line[len("  CONST"):]
             for i, line in enumerate(_decls(n))]
    moves = []
    for k in range(n):
        if k % 40 == 0:
            moves.append(f"    GripLoad {('lBox', 'load0', 'lPart')[(k // 40) % 3]};")
        load = ("", "\\TLoad:=lBox", "\\TLoad:=load0", "\\TLoad:=lPart")[k % 4]
        moves.append(f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate{load};")
    routines = [line.replace("  PROC ", "  LOCAL PROC ") for line in _parts(moves, 400)]
    return [*head, *loads, *decls, *routines, "ENDMODULE"]


def _hand_offs(n: int) -> list[str]:
    """A hand-written pick-and-place: above each point by Offs, down to it, up again,
    every call spaced after its commas, as RobotStudio's editor and people write."""
    moves = []
    points = max(1, n // 3)
    for k in range(points):
        lift = 20 + 10 * (k % 5)
        moves += [f"    MoveJ Offs(p{k}, 0, 0, {lift}), v1000, z50, tMill\\WObj:=wPlate;",
                  f"    MoveL p{k}, v200, fine, tMill\\WObj:=wPlate;",
                  f"    MoveL Offs(p{k}, 0, 0, {lift}), v1000, z10, tMill\\WObj:=wPlate;"]
    return [*_head("HandOffs"), *_decls(points), *_parts(moves, 300), "ENDMODULE"]


def _reltool(n: int) -> list[str]:
    """A deburring post: every target turned about the tool's z axis and drawn back along
    it by RelTool with `\\Rz`, spaced or tight."""
    moves = [f"    MoveL RelTool(p{k}, 0, 0, -{k % 4} \\Rz:={(k * 7) % 90 - 45}), v100, z1, "
             "tMill\\WObj:=wPlate;" if k % 2 else
             f"    MoveL RelTool(p{k},0,0,-5\\Rz:={k % 30}),v100,z1,tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*_head("RelTool"), *_decls(n), *_parts(moves), "ENDMODULE"]


def _lower(n: int) -> list[str]:
    """A program typed in lower case (RAPID's words are case-insensitive): keywords,
    instructions, type names, TRUE/FALSE and optional argument names."""
    moves = [f"    {('movel', 'movej')[k % 2]} p{k},v100,z1,tMill\\wobj:=wPlate;" for k in range(n)]
    words = re.compile(r"\b(MODULE|ENDMODULE|PROC|ENDPROC|CONST|PERS|VAR|robtarget|tooldata|"
                       r"wobjdata|speeddata|TRUE|FALSE)\b")
    return [words.sub(lambda m: m.group().lower(), line)
            for line in [*_head("Lower"), *_decls(n), *_parts(moves), "ENDMODULE"]]


def _upper(n: int) -> list[str]:
    """A program in upper case throughout, names and all (`MOVEL P1,V100,...`)."""
    moves = [f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;" for k in range(n)]
    return [line.upper() for line in [*_head("Upper"), *_decls(n), *_parts(moves), "ENDMODULE"]]


def _exponent(n: int) -> list[str]:
    """Positions written in exponent form (`-1.495000E+02`), integer orientations."""
    trans, confs = _targets(n)
    decls = []
    for i in range(n):
        x, y, z = (float(v) for v in trans[i].strip("[]").split(","))
        decls.append(f"  CONST robtarget p{i}:=[[{x:.6E},{y:.6E},{z:.6E}],"
                     f"{_robtarget('[0,0,0]', confs[i])[9:]};")
    moves = [f"    MoveJ p{k},v500,z10,tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("Exponent"), *decls, *_parts(moves), "ENDMODULE"]


def _data_last(n: int) -> list[str]:
    """The routines first, the targets they move to declared after them."""
    moves = [f"    MoveL p{k}, v100, z1, tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("DataLast"), *_parts(moves), *_decls(n), "ENDMODULE"]


def _elements(n: int) -> list[str]:
    """Targets held in arrays of a hundred (declared over lines), every move to one
    element by its index (`MoveL seam3{17}, ...`)."""
    trans, confs = _targets(n)
    out = [*_head("Elements")]
    for a in range(0, n, 100):
        items = ",\n    ".join(_robtarget(trans[i], confs[i]) for i in range(a, min(n, a + 100)))
        out.append(f"  CONST robtarget seam{a // 100}{{{min(n, a + 100) - a}}}:=[\n    {items}];")
    moves = [f"    MoveL seam{k // 100}{{{k % 100 + 1}}}, v100, z1, tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*out, *_parts(moves), "ENDMODULE"]


def _routine_targets(n: int) -> list[str]:
    """A pick routine that takes its target as a parameter, called once per point after
    a move above it, and `MoveLDO` setting the gripper: the routine's moves are known only
    at run time, the moves above the points before it."""
    calls = [line for k in range(n) for line in (
        f"    MoveJ Offs(p{k}, 0, 0, 100), v1000, z50, tMill\\WObj:=wPlate;",
        f"    Pick p{k}, {10 + k % 5 * 10};")]
    pick = ["  PROC Pick(robtarget pPos, num nHeight)",
            "    MoveJ Offs(pPos, 0, 0, nHeight), v1000, z50, tMill\\WObj:=wPlate;",
            "    MoveLDO pPos, v200, fine, tMill\\WObj:=wPlate, doGrip, 1;",
            "    MoveL Offs(pPos, 0, 0, nHeight), v1000, z10, tMill\\WObj:=wPlate;",
            "  ENDPROC"]
    return [*_head("RoutineTargets"), *_decls(n), *pick, *_parts(calls), "ENDMODULE"]


def _nested_calls(n: int) -> list[str]:
    """Targets moved by a call of a call: lifted by Offs and turned by RelTool
    (`RelTool(Offs(p7,0,0,10),0,0,0\\Rz:=30)`), or the other way round, tight or spaced."""
    moves = [f"    MoveL RelTool(Offs(p{k},0,0,{k % 4 * 5}),0,0,0\\Rz:={k % 30}),v100,z1,"
             "tMill\\WObj:=wPlate;" if k % 2 else
             f"    MoveL Offs(RelTool(p{k}, 0, 0, -5), 0, 0, {k % 3}), v100, z1, "
             "tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("NestedCalls"), *_decls(n), *_parts(moves), "ENDMODULE"]


def _deep_calls(n: int) -> list[str]:
    """Targets moved by calls two levels deep, as a hand-written cell composes them
    (`Offs(RelTool(Offs(p7,0,0,-5),0,0,0\\Rz:=30),nDx*2,0,10)`), a third of them spaced."""
    moves = [f"    MoveL Offs(RelTool(Offs(p{k},0,0,-5),0,0,0\\Rz:={k % 30}),nDx*{k % 3},0,10),"
             "v100,z1,tMill\\WObj:=wPlate;" if k % 3 else
             f"    MoveJ RelTool( Offs( RelTool(p{k}, 0, 0, 5), 0, {k % 4}, 0), 0, 0, -5), v200,"
             " z5, tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("DeepCalls"), "  CONST num nDx:=0.5;", *_decls(n), *_parts(moves),
            "ENDMODULE"]


def _spaced_brackets(n: int) -> list[str]:
    """Targets spaced inside their brackets too, as some people and generators write
    them (`[ [x, y, z], [q1, q2, q3, q4], ... ]`): declared for half the moves, inline in
    the others."""
    trans, confs = _targets(n)
    targets = ["[ " + _robtarget(trans[k], confs[k])[1:-1].replace(",", ", ").replace(
        "[", "[ ").replace("]", " ]") + " ]" for k in range(n)]
    half = n // 2
    decls = [f"  CONST robtarget p{k} := {targets[k]};" for k in range(half)]
    moves = [f"    MoveL {f'p{k}' if k < half else targets[k]}, v100, z1, tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*_head("SpacedBrackets"), *decls, *_parts(moves), "ENDMODULE"]


def _compact_ifs(n: int) -> list[str]:
    """A hand-written cell's guards without THEN (`IF bOn MoveL ...;`, `IF DInput(diReady)
    = 1 SetDO doGo, 1;`): every other statement a compact IF, some around a move."""
    moves = []
    for k in range(n):
        move = f"MoveL p{k},v100,z1,tMill\\WObj:=wPlate;"
        moves.append(f"    {move}" if k % 4 != 2 else f"    IF bOn AND nCount >= 0 {move}")
        moves.append(("    IF nCount > 3 Incr nCount;",
                      "    IF DInput(diReady) = 1 SetDO doGo, 1;", "    IF NOT bOn nCount := 0;",
                      '    IF nCount MOD 50 = 0 TPWrite "Row";')[k % 4])
    return [*_head("CompactIfs"), "  VAR num nCount:=0;", "  PERS bool bOn:=TRUE;",
            *_decls(n), *_parts(moves, 1000), "ENDMODULE"]


def _paren_calls(n: int) -> list[str]:
    """Conditions and values with function calls inside parentheses, as people write
    them (`WaitUntil (DInput(diReady) = 1) \\MaxTime:=(nWait * 2);`)."""
    blocks = []
    for k in range(n):
        lines = (("    IF (DInput(diReady) = 1) AND (nCount < 5) THEN",
                  f"      MoveL p{k},v100,z1,tMill\\WObj:=wPlate;", "    ENDIF",
                  "    nCount := (nCount + 1) MOD 10;") if k % 2 else
                 ("    WaitUntil (DInput(diReady) = 1) \\MaxTime:=(nWait * 2);",
                  f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;",
                  '    TPWrite "x=" + (NumToStr(nCount, 1) + " mm");'))
        blocks.append("\n".join(lines))
    return [*_head("ParenCalls"), "  VAR num nCount:=0;", "  CONST num nWait:=2;", *_decls(n),
            *_parts(blocks, 300), "ENDMODULE"]


def _grids(n: int) -> list[str]:
    """Targets in two-dimensional arrays (a pallet's rows and columns), a hundred rows
    of ten to an array, a row to a line; every move to one element (`grid3{17,4}`)."""
    rows, cols = 100, 10
    trans, confs = _targets(n)
    targets = [_robtarget(trans[i], confs[i]) for i in range(n)]
    per = rows * cols
    out = [*_head("Grids")]
    for g, first in enumerate(range(0, n, per)):
        items = targets[first:first + per]
        items += items[-1:] * (per - len(items))
        lines = ["[" + ",".join(items[r * cols:(r + 1) * cols]) + "]" for r in range(rows)]
        out.append(f"  CONST robtarget grid{g}{{{rows},{cols}}}:=[" + ",\n    ".join(lines) + "];")
    moves = [f"    MoveL grid{k // per}{{{k % per // cols + 1},{k % cols + 1}}},v100,z1,"
             "tMill\\WObj:=wPlate;" for k in range(n)]
    return [*out, *_parts(moves), "ENDMODULE"]


def _record_tables(n: int) -> list[str]:
    """A cell's data tables: arrays of a RECORD type (`[17,"S17",3.5,[2,1,0]]`) a row to a
    line, a hundred rows to a table, four rows for each of the moves after them."""
    rows = [f'[{k},"S{k}",{k % 50 + 0.5},[{k % 7},{k % 3},0]]' for k in range(4 * n)]
    tables = [f"  CONST seam table{a // 100}{{{len(rows[a:a + 100])}}}:=[\n    "
              + ",\n    ".join(rows[a:a + 100]) + "];" for a in range(0, len(rows), 100)]
    moves = [f"    MoveL p{k},v100,z1,tMill\\WObj:=wPlate;" for k in range(n)]
    return [*_head("RecordTables"), "  RECORD seam", "    num id;", "    string name;",
            "    num speed;", "    pos offset;", "  ENDRECORD", *tables, *_decls(n),
            *_parts(moves), "ENDMODULE"]


def _one_line(n: int) -> list[str]:
    """`hand_offs` with MODULE to ENDMODULE on one line (its comments left out)."""
    return [" ".join(line.strip() for line in _hand_offs(n)
                     if line.strip() and not line.strip().startswith("!"))]


def _multimove(n: int) -> list[str]:
    """A MultiMove task's coordinated program: every move numbered with `\\ID:=` (ten
    apart, as RobotStudio writes them), some arcs and joint moves among them, between
    SyncMoveOn and SyncMoveOff."""
    moves = ["    SyncMoveOn sync1, tasks;"]
    for k in range(n):
        number = f"\\ID:={10 * k + 10}"
        if k % 5 == 4:
            moves.append(f"    MoveC {number}, Offs(p{k},-0.25,0.3,0), p{k}, v100, z1, "
                         "tMill\\WObj:=wPlate;")
        elif k % 7 == 0:
            moves.append(f"    MoveJ {number}, p{k}, v500, z10, tMill\\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL {number}, p{k}, v100, z1, tMill\\WObj:=wPlate;")
    moves.append("    SyncMoveOff sync2;")
    return [*_head("Coordinated"), '  PERS tasks tasks{2}:=[["T_ROB1"],["T_ROB2"]];',
            "  VAR syncident sync1;", "  VAR syncident sync2;", *_decls(n),
            "  PROC Coordinated()", *moves, "  ENDPROC", "ENDMODULE"]


#: the line ending a shape's lines are joined with, where it is not LF
_NEWLINES = {"lone_cr": "\r"}

_BUILDERS = {"many_procs": _many_procs, "frames": _frames, "stacked": _stacked,
             "deep": _deep, "expressions": _expressions, "modules": _modules, "wide": _wide,
             "assign": _assign, "io": _io, "loops": _loops, "failing": _failing,
             "records": _records, "messages": _messages, "conditions": _conditions,
             "feeds": _feeds, "tails": _tails, "five_axis": _five_axis, "track": _track,
             "remarks": _remarks, "spaced": _spaced,
             "latin1": _latin1, "concurrent": _concurrent, "flips": _flips,
             "lone_cr": _lone_cr, "arc_weld": _arc_weld, "wrapped": _wrapped,
             "scoped": _scoped, "hand_offs": _hand_offs, "reltool": _reltool,
             "lower": _lower, "upper": _upper, "exponent": _exponent, "data_last": _data_last,
             "elements": _elements, "routine_targets": _routine_targets,
             "nested_calls": _nested_calls, "spaced_brackets": _spaced_brackets,
             "one_routine": _one_routine, "inline_data": _inline_data,
             "long_names": _long_names, "deep_calls": _deep_calls,
             "compact_ifs": _compact_ifs, "paren_calls": _paren_calls, "grids": _grids,
             "record_tables": _record_tables, "multimove": _multimove, "one_line": _one_line,
             "labels": _labels, "computed": _computed, "pallet": _pallet,
             "callers": _callers, "guards": _guards}
#: shapes whose statements share one line: their lines are counted as those of the shape
#: written a statement to a line
_PACKED = {"one_line": "hand_offs"}


def odd_moves(shape: str, n_moves: int) -> str:
    """The program text of `shape` with about n_moves moves."""
    newline = _NEWLINES.get(shape, "\n")
    return "\n".join(_BUILDERS[shape](n_moves)).replace("\n", newline) + newline


@functools.lru_cache(maxsize=16)
def _lines_per_move(shape: str) -> float:
    shape = _PACKED.get(shape, shape)
    return odd_moves(shape, 1000).count(_NEWLINES.get(shape, "\n")) / 1000


def odd_lines(shape: str, data: bytes) -> int:
    """The lines of a program of `shape` (of the shape unpacked, for a packed one)."""
    if shape in _PACKED:
        return round(data.count(b";") * _lines_per_move(_PACKED[shape])
                     / _statements_per_move(_PACKED[shape]))
    return data.count(b"\n") or data.count(b"\r")  # (lone_cr: CR line ends)


@functools.lru_cache(maxsize=4)
def _statements_per_move(shape: str) -> float:
    return odd_moves(shape, 1000).count(";") / 1000


def odd_program(shape: str, lines: int) -> str:
    """The program text of `shape` with about `lines` lines."""
    return odd_moves(shape, max(3, round(lines / _lines_per_move(shape))))
