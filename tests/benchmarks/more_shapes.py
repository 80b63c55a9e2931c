"""More generated program shapes, beyond the eight of program_shapes.py, for checking
that the parser's speed and equivalence hold on layouts it was not tuned on:

- var_pers:   VAR / PERS / LOCAL robtargets in mixed-case keywords, \\V and \\Z speeds
- absj:       jointtargets and MoveAbsJ, exponent-form numbers (1.5E+02)
- arrays:     arrays of robtargets, moves to path{i}
- trigg:      TriggL / SearchL / MoveLDO with signals and triggers
- nested:     Offs(RelTool(p, ...), ...) nested calls, RelTool with \\Rz
- inside:     comments inside statements, statements split over lines
- calls:      several routines with parameters calling each other, moves to parameters
- mixed:      issue 18's mixed program: half named, a quarter inline, a quarter
              `Offs(p,0,0,0)`, MoveJ/MoveL, `\\WObj`, a comment every 50 moves, CRLF,
              `%%%` header

`more_program(shape, lines)` gives about `lines` lines of that shape.
"""

from __future__ import annotations

import functools

from program_shapes import _head, _robtarget, _targets

MORE_SHAPES = ("var_pers", "inline_exp", "absj", "arrays", "trigg", "nested", "inside",
               "calls", "mixed")
PER_PROC = 400


def _procs(moves: list[str], per: int = PER_PROC) -> list[str]:
    out, names = [], []
    for k in range(0, len(moves), per):
        names.append(f"Part_{k // per + 1}")
        out += [f"  PROC {names[-1]}()", *moves[k:k + per], "  ENDPROC"]
    return [*out, "  PROC main()", *(f"    {name};" for name in names), "  ENDPROC"]


def _exp(text: str) -> str:
    """Numbers in exponent form: '[1.5,2,3]' -> '[1.5E+00,...]'."""
    return "[" + ",".join(f"{float(v):.6E}" for v in text.strip("[]").split(",")) + "]"


def _var_pers(n: int) -> list[str]:
    trans, confs = _targets(n)
    storage = ("VAR", "pers", "LOCAL CONST", "Var", "LOCAL PERS")
    decls = [f"  {storage[i % 5]} robtarget Pt_{i}:={_robtarget(trans[i], confs[i])};"
             for i in range(n)]
    speeds = ("v100 \\V:=120", "vmax", "v200\\T:=2", "v50")
    zones = ("fine", "z10 \\Z:=5", "z10 \\Z:=5")
    moves = [f"    {'movel' if k % 2 else 'MoveJ'} Pt_{k}, {speeds[k % 4]}, "
             f"{zones[k % 3]}, tMill \\WObj:=wPlate;" for k in range(n)]
    return [*_head("VarPers"), *decls, *_procs(moves), "ENDMODULE"]


def _inline_exp(n: int) -> list[str]:
    trans, confs = _targets(n)
    moves = [f"    MoveL {_robtarget(_exp(trans[k]), confs[k])},v100,z1,tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*_head("InlineExp"), *_procs(moves), "ENDMODULE"]


def _absj(n: int) -> list[str]:
    decls, moves = [], []
    for i in range(n):
        joints = ",".join(f"{(i * 7 % 60 - 30) + j * 1.25:.4E}" for j in range(6))
        decls.append(f"  CONST jointtarget j{i}:=[[{joints}],[9E+09,9E+09,9E+09,9E+09,"
                     "9E+09,9E+09]];")
        moves.append(f"    MoveAbsJ j{i}\\NoEOffs, v{100 * (1 + i % 3)}, z5, tMill;")
    return [*_head("AbsJ"), *decls, *_procs(moves), "ENDMODULE"]


def _arrays(n: int) -> list[str]:
    trans, confs = _targets(n)
    size = 50
    decls = []
    for a in range(0, n, size):
        items = [_robtarget(trans[i], confs[i]) for i in range(a, min(n, a + size))]
        decls.append(f"  CONST robtarget path{a // size}{{{len(items)}}}:=[" + ",".join(items)
                     + "];")
    moves = [f"    MoveL path{k // size}{{{k % size + 1}}},v100,z1,tMill\\WObj:=wPlate;"
             for k in range(n)]
    return [*_head("Arrays"), *decls, *_procs(moves), "ENDMODULE"]


def _trigg(n: int) -> list[str]:
    trans, confs = _targets(n)
    decls = [f"  CONST robtarget p{i}:={_robtarget(trans[i], confs[i])};" for i in range(n)]
    head = [*_head("Trigg"), "  VAR triggdata gunon;", "  VAR robtarget found;"]
    moves = []
    for k in range(n):
        r = k % 4
        if r == 0:
            moves.append(f"    TriggL p{k}, v100, gunon, z1, tMill \\WObj:=wPlate;")
        elif r == 1:
            moves.append(f"    MoveLDO p{k}, v100, z1, tMill, do1, 1 \\WObj:=wPlate;")
        elif r == 2:
            moves.append(f"    SearchL \\Stop, di1, found, p{k}, v100, tMill \\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL p{k}, v100, z1, tMill \\WObj:=wPlate;")
    return [*head, *decls, *_procs(moves), "ENDMODULE"]


def _nested(n: int) -> list[str]:
    trans, confs = _targets(n)
    bases = max(1, n // 5)
    decls = [f"  CONST robtarget p{i}:={_robtarget(trans[i], confs[i])};" for i in range(bases)]
    moves = []
    for k in range(n):
        p, d = f"p{k % bases}", (k % 7) * 0.25
        if k % 3 == 0:
            moves.append(f"    MoveL Offs(RelTool({p},0,0,{d:g}),{d:g},0,0),v100,z1,tMill"
                         "\\WObj:=wPlate;")
        elif k % 3 == 1:
            moves.append(f"    MoveL RelTool({p},0,{d:g},-{d:g}\\Rz:={k % 5}),v100,z1,tMill"
                         "\\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL Offs({p}, -{d:g}, 1.5E-01, 0), v100, z1, tMill"
                         "\\WObj:=wPlate;")
    return [*_head("Nested"), *decls, *_procs(moves), "ENDMODULE"]


def _inside(n: int) -> list[str]:
    trans, confs = _targets(n)
    decls = [f"  CONST robtarget p{i}:={_robtarget(trans[i], confs[i])};" for i in range(n)]
    moves = []
    for k in range(n):
        if k % 3 == 0:
            moves.append(f"    MoveL p{k}, ! to point {k}, {'long comment ' * (k % 4)}\n"
                         "      v100, z1, tMill \\WObj:=wPlate;")
        elif k % 3 == 1:
            moves.append(f"    MoveL p{k},\n      v100,\n      z1, tMill \\WObj:=wPlate;")
        else:
            moves.append(f"    MoveL p{k}, v100, z1, tMill \\WObj:=wPlate; ! done {k}")
    return [*_head("Inside"), *decls, *_procs(moves), "ENDMODULE"]


def _calls(n: int) -> list[str]:
    trans, confs = _targets(n)
    decls = [f"  CONST robtarget p{i}:={_robtarget(trans[i], confs[i])};" for i in range(n)]
    out = [*_head("Calls"), *decls,
           "  PROC Visit(robtarget target, speeddata speed)",
           "    MoveL target, speed, z1, tMill \\WObj:=wPlate;",
           "  ENDPROC",
           "  PROC Approach(robtarget target)",
           "    MoveJ Offs(target, 0, 0, 50), v200, z10, tMill \\WObj:=wPlate;",
           "    Visit target, v100;",
           "  ENDPROC"]
    names = []
    for first in range(0, n, PER_PROC):
        names.append(f"Job_{first // PER_PROC + 1}")
        out.append(f"  PROC {names[-1]}()")
        for k in range(first, min(n, first + PER_PROC)):
            r = k % 5
            if r == 0:
                out.append(f"    Approach p{k};")
            elif r == 1:
                out.append(f"    Visit p{k}, vFeed;")
            else:
                out.append(f"    MoveL p{k}, v100, z1, tMill \\WObj:=wPlate;")
        out.append("  ENDPROC")
    return [*out, "  PROC main()", *(f"    {name};" for name in names), "  ENDPROC",
            "ENDMODULE"]


def _mixed(n: int) -> list[str]:
    trans, confs = _targets(n)
    decls = [f"  CONST robtarget p{k}:={_robtarget(trans[k], confs[k])};"
             for k in range(n) if k % 4 != 2]
    moves = []
    for k in range(n):
        if k % 50 == 0:
            moves.append(f"    ! pass {k // 50}")
        target = (f"p{k}", f"p{k}", _robtarget(trans[k], confs[k]), f"Offs(p{k},0,0,0)")[k % 4]
        moves.append(f"    {'MoveJ' if k % 10 == 0 else 'MoveL'} {target}, v100, z1, "
                     "tMill\\WObj:=wPlate;")
    lines = ["%%%", "  VERSION:1", "  LANGUAGE:ENGLISH", "%%%", *_head("Mixed"), *decls,
             *_procs(moves, 500), "ENDMODULE"]
    return [line + "\r" for line in lines]  # CRLF, as RobotStudio writes


_BUILDERS = {"var_pers": _var_pers, "inline_exp": _inline_exp, "absj": _absj,
             "arrays": _arrays, "trigg": _trigg, "nested": _nested, "inside": _inside,
             "calls": _calls, "mixed": _mixed}


def more_moves(shape: str, n_moves: int) -> str:
    """The program text of `shape` with about n_moves moves."""
    return "\n".join(_BUILDERS[shape](n_moves)) + "\n"


@functools.lru_cache(maxsize=16)
def _lines_per_move(shape: str) -> float:
    return more_moves(shape, 1000).count("\n") / 1000


def more_program(shape: str, lines: int) -> str:
    """The program text of `shape` with about `lines` lines."""
    return more_moves(shape, max(3, round(lines / _lines_per_move(shape))))
