"""Programs of random mixes of a cell's statements, for shapes nobody wrote by hand.

Each seed draws its own weight for every statement template below (moves of every kind
and target form, assignments, waits and I/O, messages, guards, loops, tests, late-bound
and user routine calls, settings, labels, comments), its routine length (5 to 1,000
statements) and how deep each routine's statements stand in IF / WHILE / FOR blocks. A
seed is one shape: most seeds lean on a few templates, as real programs do, and no two
seeds lean on the same ones. The named shapes (program_shapes.py) and the odd ones
(odd_shapes.py) each stand for one layout a person chose; these are what a generator
of "other shapes" makes.

    mixed_program(seed, lines) -> str
"""

from __future__ import annotations

import random

from program_shapes import _head, _robtarget, _targets

#: statement templates: {k} and {k1} a declared point, {r} 1..9, {r1} 1..19, {g} a label
TEMPLATES = (
    "MoveL p{k},v100,z1,tMill\\WObj:=wPlate;",
    "MoveJ p{k}, v1000, z50, tMill \\WObj:=wPlate;",
    "MoveL Offs(p{k},0,0,{r}),v200,z5,tMill\\WObj:=wPlate;",
    "MoveL RelTool(p{k},0,0,-{r}\\Rz:={r}),v200,z5,tMill\\WObj:=wPlate;",
    "MoveL Offs(p{k}, (nI-1)*nDx, {r}*nDy, 0), v100, z1, tMill\\WObj:=wPlate;",
    "MoveC p{k}, p{k1}, v100, z1, tMill\\WObj:=wPlate;",
    "MoveL p{k},v100\\V:=120,z1\\Z:=2,tMill\\WObj:=wPlate\\TLoad:=lPart;",
    "MoveL \\Conc, p{k},v100,z1,tMill\\WObj:=wPlate;",
    "TriggL p{k},v150,trOn,z1,tMill\\WObj:=wPlate;",
    "SearchL \\Stop, diS, pF, Offs(p{k},0,0,-{r}), v50, tMill\\WObj:=wPlate;",
    "MoveAbsJ [[{r},-10,20,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\\NoEOffs,v1000,z50,tMill;",
    "MoveL pArr{{{r1}}},v100,z1,tMill\\WObj:=wPlate;",
    "nI := nI + 1;",
    "nI := (nI MOD {r1}) + 1;",
    "bOk := (nI > {r}) AND NOT bStop;",
    "pT := Offs(p{k}, 0, 0, (nI*{r}) / 2);",
    "pT.trans.z := pT.trans.z + {r};",
    "WaitTime 0.{r};",
    "WaitDI diReady, 1 \\MaxTime:={r1} \\TimeFlag:=bTo;",
    "WaitUntil DInput(diA)=1 AND (nI < {r1}) \\MaxTime:=3;",
    "SetDO doGrip, 1;",
    "SetDO \\SDelay:=0.{r}, doGrip, 0;",
    "PulseDO \\PLength:=0.2, doCount;",
    'TPWrite "Point {k} " + NumToStr(nI, 0) \\Num:=nI;',
    'ErrWrite \\W, "Warn", "p{k}";',
    "Incr nI;",
    "Decr nI;",
    "IF bStop RETURN;",
    "IF (nI > {r1}) nI := 0;",
    "IF nI = {r} THEN\n  SetDO doA, 1;\nELSE\n  SetDO doA, 0;\nENDIF",
    "IF (bOk) THEN\n  MoveL p{k},v100,fine,tMill\\WObj:=wPlate;\nENDIF",
    "FOR i FROM 1 TO {r1} DO\n  nSum := nSum + aVal{{i}};\nENDFOR",
    "WHILE (nI < 0) AND bOk DO\n  Incr nI;\nENDWHILE",
    "TEST nI\nCASE 1, 2:\n  SetDO doA, 1;\nCASE {r1}:\n  SetDO doA, 0;\nDEFAULT:\n  Stop;\n"
    "ENDTEST",
    '%"Tool" + NumToStr(nTool, 0)%;',
    "Pick p{k} \\Speed:=v200, {r};",
    "! point {k}: Jörg's seam, approach",
    "ConfL\\Off;",
    "SingArea\\Wrist;",
    "AccSet {r1}0, 100;",
    "VelSet 50, {r1}00;",
    "nAng := ATan2(pT.trans.y, pT.trans.x);",
    "pCur := CRobT(\\Tool:=tMill\\WObj:=wPlate);",
    "lNext{g}:",
)

_DATA = (
    "  VAR num nI:=0;", "  VAR num nSum:=0;", "  VAR num aVal{20};", "  VAR bool bOk:=TRUE;",
    "  VAR bool bStop:=FALSE;", "  VAR bool bTo:=FALSE;", "  VAR robtarget pT;",
    "  VAR robtarget pF;", "  VAR robtarget pCur;", "  VAR num nDx:=0.5;",
    "  VAR num nDy:=0.5;", "  VAR num nTool:=1;", "  VAR num nAng:=0;",
    "  VAR triggdata trOn;", "  PERS loaddata lPart:=[1.5,[0,0,40],[1,0,0,0],0,0,0];",
    "  PROC Tool1()", "    Stop;", "  ENDPROC",
    "  PROC Pick(robtarget pP \\speeddata Speed, num nL)",
    "    MoveL pP,v100,fine,tMill\\WObj:=wPlate;", "  ENDPROC",
)
_BLOCKS = (("IF bOk THEN", "ENDIF"), ("WHILE nI < 0 DO", "ENDWHILE"),
           ("FOR j FROM 1 TO 2 DO", "ENDFOR"))


def mixed_program(seed: int, lines: int) -> str:
    """A program of about `lines` lines (a few more: the last routine is finished) of
    the mix of statements that `seed` draws; a third of its lines declare its points."""
    rnd = random.Random(seed)
    weights = [rnd.random() ** 3 for _ in TEMPLATES]
    points = max(20, lines // 3)
    trans, confs = _targets(points)
    targets = [_robtarget(trans[i], confs[i]) for i in range(points)]
    out = [*_head(f"Mix{seed}"),
           *(f"  CONST robtarget p{i}:={t};" for i, t in enumerate(targets)),
           f"  VAR robtarget pArr{{20}}:=[{','.join(targets[:20])}];", *_DATA]
    per = rnd.choice((5, 20, 100, 1000))
    k = labels = routines = 0
    while len(out) < lines:
        out.append(f"  PROC R{routines}()")
        routines += 1
        blocks = [rnd.choice(_BLOCKS) for _ in range(rnd.choice((0, 0, 1, 2)))]
        out += [f"    {'  ' * d}{head}" for d, (head, _) in enumerate(blocks)]
        indent = "    " + "  " * len(blocks)
        for template in rnd.choices(TEMPLATES, weights, k=per):
            text = template.format(k=k % points, k1=(k + 1) % points, r=1 + k % 9,
                                   r1=1 + k % 19, g=labels)
            labels += template.startswith("lNext")
            out += [indent + line for line in text.split("\n")]
            k += 1
        out += [f"    {'  ' * d}{end}" for d, (_, end) in reversed(list(enumerate(blocks)))]
        out.append("  ENDPROC")
    return "\n".join([*out, "ENDMODULE"]) + "\n"
