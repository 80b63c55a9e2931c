"""Moves that share their operands besides the targets (a CAM program's tails) get the
same model as moves built one by one.

Every comparison builds the program model twice from the same text: from the
fast parser's tree (LazyCall nodes, shared tails) and from the plain grammar's
tree (every argument a node, every operand made at once), and compares every
motion's operands field by field, spans included.
"""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidfix.rapid import syntax as s
from rapidfix.rapid.fastpath import forget_texts, parse_text
from rapidfix.rapid.grammar import rapid_parser
from rapidfix.rapid.model_builder import build_program
from rapidfix.rapid.program import Operand, Program
from rapidfix.rapid.source import decode_source

TARGET = "[[1,-2.5,3E2],[1,0,0,0],[0,-1,2,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
TOOL = "[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]]"
WOBJ = "[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]"


def describe(operand: Operand) -> tuple:
    arg, decl = operand.argument, operand.declaration
    return (arg.start, arg.end, arg.kind, arg.name, operand.text, operand.form,
            operand.name, operand.type_name, operand.value, operand.static, operand.reason,
            None if decl is None else (decl.module, decl.routine, decl.syntax.start))


def model(program: Program) -> list[tuple]:
    return [
        (m.name, m.module, m.routine, m.in_loop, m.syntax.start, m.syntax.end,
         [describe(t) for t in m.targets],
         {k: describe(v) for k, v in m.arguments.items()},
         {k: describe(v) for k, v in m.optional.items()},
         [k for k in m.arguments], [k for k in m.optional])
        for m in program.motions
    ]


def both(text: str) -> tuple[Program, Program]:
    source = decode_source(text, "t.mod")
    fast = build_program(source, text.encode(), parse_text(text))
    plain = build_program(source, text.encode(), rapid_parser().parse(text))
    return fast, plain


def assert_same_model(text: str) -> Program:
    fast, plain = both(text)
    assert model(fast) == model(plain)
    for motion in fast.motions:  # the targets are the very operands of the arguments
        args = motion.arguments
        assert all(any(t is a for a in args.values()) for t in motion.targets)
    # moves with the same shared tail have equal operands besides their targets and the
    # numbers each has of its own (`\\ID:=10`: their text and value)
    seen: dict[int, tuple] = {}
    for motion in fast.motions:
        if motion.shared is None:
            continue
        rest = tuple((k, shared_part(v)) for k, v in
                     [*motion.arguments.items(), *motion.optional.items()]
                     if not any(v is t for t in motion.targets))
        assert seen.setdefault(id(motion.shared), rest) == rest
    return fast


def shared_part(operand: Operand) -> tuple:
    """What moves sharing a tail share of an operand (besides its place)."""
    text, *fields = describe(operand)[4:]
    if operand.argument.kind == "optional" and type(operand.argument.value) is s.Number:
        return (*fields[:3], *fields[4:])
    return (text, *fields)


CELL = f"""MODULE Cell
  PERS tooldata gun:={TOOL};
  PERS wobjdata table:={WOBJ};
  CONST robtarget p1:={TARGET};
  CONST robtarget p2:={TARGET};
  VAR robtarget moving:={TARGET};
  PROC main()
    MoveL p1,v100,z1,gun\\WObj:=table;
    MoveL p2,v100,z1,gun\\WObj:=table;
    MoveJ p1,v100,z1,gun\\WObj:=table;
    MoveL p2,v100,z1,gun\\WObj:=table;
    MoveL {TARGET},v100,z1,gun\\WObj:=table;
    MoveL moving,v100,z1,gun\\WObj:=table;
    MoveL nowhere,v100,z1,gun\\WObj:=table;
    MoveL \\Conc,p1,v100,fine,gun;
    MoveL p1,v100,z1,gun\\Conc;
    MoveL p2,v100,z1,gun\\Conc;
    MoveL p1,v100,z1,gun\\T:=2;
    MoveL p2,v100,z1,gun\\T:=2;
    MoveC p1,p2,v100,z1,gun;
    MoveC p2,p2,v100,z1,gun;
    MoveAbsJ [[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,z1,gun;
    FOR i FROM 1 TO 3 DO
      MoveL p1,v100,z1,gun\\WObj:=table;
    ENDFOR
    moving.trans.x:=1;
  ENDPROC
  PROC other()
    VAR tooldata gun:={TOOL};
    MoveL p1,v100,z1,gun\\WObj:=table;
    MoveL p2,v100,z1,gun\\WObj:=table;
  ENDPROC
ENDMODULE
"""


def test_a_cell_program_builds_the_same_model_from_shared_tails():
    program = assert_same_model(CELL)
    shared = [m for m in program.motions if m.shared is not None]
    assert len(shared) > 8  # the tails were shared, not all built one by one
    # the first call with a tail is made in full; a later one in its routine shares it
    for k, motion in enumerate(program.motions):
        if motion.shared is not None:
            assert any(m.syntax.tail is motion.syntax.tail and m.routine == motion.routine
                       and m.name == motion.name for m in program.motions[:k])
    main = [m for m in shared if m.routine == "main" and "wobj" in m.optional]
    other = [m for m in shared if m.routine == "other"]
    # the same tail text in another routine names another tool (a local one)
    assert main[0].shared is not other[0].shared
    assert main[0].tool.declaration is not other[0].tool.declaration


def test_asking_for_the_arguments_makes_them_once():
    fast, _ = both(CELL)
    motion = next(m for m in fast.motions if m.shared is not None and m._arguments is None)
    assert motion.arguments is motion.arguments and motion.optional is motion.optional
    assert motion.syntax.args[0] is motion.targets[0].argument


def test_moves_whose_second_argument_varies_share_their_tail():
    # MoveC's two targets: the text after the first is new on every line, after the
    # second it recurs; the moves then share what follows their two targets
    lines = [f"CONST robtarget {n}{i}:={TARGET};" for i in range(4) for n in "cd"]
    moves = [f"    MoveC c{i},d{i},v100,z1,gun\\WObj:=table;" for i in range(4)]
    text = CELL.replace("  PROC main()\n", "  " + "\n  ".join(lines) + "\n  PROC main()\n"
                        + "\n".join(moves) + "\n")
    forget_texts()  # the first MoveC then reads its tails, the others find the second one
    program = assert_same_model(text)
    circles = [m for m in program.motions if m.name == "MoveC" and m.syntax.start
               < text.index("MoveL p1,v100")]
    assert len(circles) == 4
    # the second is the first with its two leading arguments: made in full, then shared
    assert circles[1].shared is None
    assert all(m.shared is circles[2].shared is not None for m in circles[2:])
    assert [len(m.syntax.heads) for m in circles] == [1, 2, 2, 2]
    assert [[t.name for t in m.targets] for m in circles] == [
        ["c0", "d0"], ["c1", "d1"], ["c2", "d2"], ["c3", "d3"]]


def test_moves_with_switches_before_their_target_share_them_and_their_tail():
    # `MoveJ \\Conc, p1, ...`: the switch and what follows the target recur, the target
    # changes; each part is read once and the moves share both
    lines = [f"CONST robtarget c{i}:={TARGET};" for i in range(5)]
    moves = [f"    MoveJ \\Conc, c{i}, v100, z1, gun\\WObj:=table;" for i in range(5)]
    text = CELL.replace("  PROC main()\n", "  " + "\n  ".join(lines) + "\n  PROC main()\n"
                        + "\n".join(moves) + "\n")
    forget_texts()
    program = assert_same_model(text)
    conc = [m for m in program.motions if m.syntax.start < text.index("MoveL p1,v100")]
    assert [m.target.name for m in conc] == [f"c{i}" for i in range(5)]
    assert all(m.syntax.lead is conc[0].syntax.lead is not None for m in conc)
    assert conc[0].shared is None and all(m.shared is conc[1].shared is not None
                                          for m in conc[1:])
    assert all(list(m.optional) == ["conc", "wobj"] for m in conc)
    # a lone `\\Conc,p1,...` (another lead text, another tail) has its own
    lone = next(m for m in program.motions if m.syntax.start == text.index("MoveL \\Conc"))
    assert lone.syntax.lead not in (None, conc[0].syntax.lead)
    assert lone.syntax.tail is not conc[0].syntax.tail and lone.shared is None


def test_moves_numbered_for_multimove_share_their_tail_each_with_its_number():
    # `MoveL \\ID:=10, p1, ...`: a MultiMove program numbers every move, so each lead is
    # new; the moves share what follows their targets and the lead's argument, and each
    # has its own number (the plain grammar's model, field by field)
    lines = [f"CONST robtarget c{i}:={TARGET};" for i in range(6)]
    moves = [f"    MoveL \\ID:={10 * i + 10}, c{i}, v100, z1, gun\\WObj:=table;"
             for i in range(6)]
    text = CELL.replace("  PROC main()\n", "  " + "\n  ".join(lines) + "\n  PROC main()\n"
                        + "\n".join(moves) + "\n")
    forget_texts()
    program = assert_same_model(text)
    numbered = [m for m in program.motions if m.syntax.start < text.index("MoveL p1,v100")]
    assert [m.optional["id"].value for m in numbered] == [10.0 * i + 10 for i in range(6)]
    assert [m.optional["id"].text for m in numbered] == [str(10 * i + 10) for i in range(6)]
    assert numbered[0].shared is None and all(m.shared is numbered[1].shared is not None
                                              for m in numbered[1:])
    assert all(list(m.optional) == ["id", "wobj"] for m in numbered)


MOVES = [
    "MoveL p1,v100,z1,gun\\WObj:=table;",
    "MoveL p2,v100,z1,gun\\WObj:=table;",
    "MoveJ p1,v100,z1,gun\\WObj:=table;",
    "MoveL p1,v100,z1,gun;",
    "MoveL p2, v100, z1, gun;",
    "MoveL undeclared,v100,z1,gun;",
    "MoveL p1,v100,z1,gun\\Conc;",
    "MoveL p1,v100,z1,gun\\T:=2;",
    "MoveL p2,v100,z1,gun\\T:=2;",
    f"MoveL {TARGET},v100,z1,gun;",
    "MoveC p1,p2,v100,z1,gun;",
    "MoveC p2,p1,v100,z1,gun;",
    "MoveC Offs(p1,0,1,0),p2,v100,z1,gun\\WObj:=table;",
    "MoveC p2,RelTool(p1,0,0,1),v100,z1,gun\\WObj:=table;",
    "MoveL p1,v200,z1,gun\\WObj:=table;",
    "MoveL Offs(p2,0,0,-1),v200,z1,gun\\WObj:=table;",
    "MoveL p1,v100,z1,gun\\TLoad:=load0;",
    "MoveL p1,v100\\V:=120,z10\\Z:=-5,gun;",
    "MoveL p2,v100\\V:=120,z10\\Z:=-5,gun;",
    "MoveL p2,v100\\V:=undeclared,z1,gun\\WObj:=[1,2];",
    "MoveL p1,v100\\V:=undeclared,z1,gun\\WObj:=[1,2];",
    "SetDO do1, 1;",
    "gun.tframe.trans.z:=1;",
    "MoveJ \\Conc,p1,v100,z1,gun\\WObj:=table;",
    "MoveJ \\Conc, p2, v100, z1, gun\\WObj:=table;",
    "MoveL \\Conc \\ID:=5,p2,v100,z1,gun;",
    "MoveL \\Conc,Offs(p1,0,0,-1),v100,z1,gun;",
    "MoveC \\Conc,p1,p2,v100,z1,gun;",
    "MoveL \\ID:=10,p1,v100,z1,gun\\WObj:=table;",
    "MoveL \\ID:=11, p2, v100, z1, gun\\WObj:=table;",
    "MoveL \\Conc \\ID:=12,p1,v100\\V:=150,z1,gun;",
    "MoveL \\ID:=nId,p1,v100,z1,gun\\WObj:=table;",
    "MoveL \\ID:=-13,p1,v100,z1,gun\\WObj:=table;",
    "MoveC \\ID:=14,p1,p2,v100,z1,gun;",
]


@st.composite
def cam_program(draw: st.DrawFn) -> str:
    routines = []
    for r in range(draw(st.integers(1, 3))):
        # local names the moves' tails hold (gun) or not (k), a parameter shadowing a target
        local = draw(st.sampled_from(["", f"    VAR tooldata gun:={TOOL};\n",
                                      "    VAR num k:=1;\n"]))
        params = draw(st.sampled_from(["", "robtarget p1", "num k"]))
        body = draw(st.lists(st.sampled_from(MOVES), min_size=1, max_size=12))
        routines.append(f"  PROC r{r}({params})\n{local}" + "".join(f"    {b}\n" for b in body)
                        + "  ENDPROC\n")
    return (f"MODULE M\n  PERS tooldata gun:={TOOL};\n  PERS wobjdata table:={WOBJ};\n"
            f"  CONST robtarget p1:={TARGET};\n  CONST robtarget p2:={TARGET};\n"
            + "".join(routines) + "ENDMODULE\n")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cam_program())
def test_random_cam_programs_build_the_same_model(text):
    program = assert_same_model(text)
    assert all(isinstance(m.syntax, s.LazyCall) for m in program.motions)


def test_function_calls_of_a_name_read_in_one_step_give_the_general_model():
    # Offs / RelTool / any function of a data name and literals (Evaluator.named_call):
    # every kind of name and every refusal gives the plain grammar's operands and reasons
    text = f"""MODULE M
  PERS tooldata gun:={TOOL};
  CONST robtarget p1:={TARGET};
  VAR robtarget moving:={TARGET};
  CONST jointtarget j1:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget bent:=[[1,2,3],[1,0,0,0],[0,0.5,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget flat:=[[1,2,3],[0,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST num dz:=5;
  PROC r(robtarget given)
    MoveL Offs(p1,0,0,-1),v100,z1,gun;
    MoveL RelTool(p1,0,0,1\\Rz:=90),v100,z1,gun;
    MoveL Offs(moving,0,0,1),v100,z1,gun;
    MoveL Offs(nowhere,0,0,1),v100,z1,gun;
    MoveL Offs(given,0,0,1),v100,z1,gun;
    MoveL Offs(j1,0,0,1),v100,z1,gun;
    MoveL Offs(bent,0,0,1),v100,z1,gun;
    MoveL RelTool(flat,0,0,1),v100,z1,gun;
    MoveL Offs(p1,0,0),v100,z1,gun;
    MoveL Offs(p1,0,0,dz),v100,z1,gun;
    MoveL Offs(p1,0,0,-dz),v100,z1,gun;
    MoveL Shifted(p1,0,0,1),v100,z1,gun;
    MoveL CRobT(p1,0,0,1),v100,z1,gun;
    MoveL p1,v100,z1,gun\\WObj:=Pick(p1,1);
    MoveL RelTool(p1,0,0,1\\Rx:=1.5\\Ry:=-2),v100,z1,gun;
    MoveL RelTool(p1,0,0,1\\Rz),v100,z1,gun;
    MoveL Offs({TARGET},0,0,1),v100,z1,gun;
    MoveL RelTool({TARGET},0,0,1\\Rx:=1.5\\Rz:=90),v100,z1,gun;
    MoveL Offs([[1,2,3],[0,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],0,0,1),
      v100,z1,gun;
    MoveL RelTool([[1,2,3],[0,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],0,0,1),
      v100,z1,gun;
    MoveL Offs([1,2,3],0,0,1),v100,z1,gun;
    MoveL Offs(RelTool({TARGET},0,0,1),0,0,2),v100,z1,gun;
    FOR i FROM 1 TO 2 DO
      MoveL Offs(i,0,0,1),v100,z1,gun;
    ENDFOR
    moving.trans.x:=1;
  ENDPROC
ENDMODULE
"""
    program = assert_same_model(text)
    calls = [m.target for m in program.motions if m.target.form in ("offs", "reltool")]
    assert sum(t.static for t in calls) >= 5 and sum(not t.static for t in calls) >= 5
    assert any(isinstance(m.syntax.args[0].value, s.LazyFunctionCall) for m in program.motions)


def test_call_tails_that_hold_names_are_evaluated_once_per_scope_as_the_general_route_does():
    # `Offs(p1,0,0,nLift)`: the tail's names are the same in every move of a routine, its
    # values kept per scope once the names settle; every failure gives the plain
    # grammar's reason, and a routine's own name shadows the module's in its tails
    text = f"""MODULE M
  PERS tooldata gun:={TOOL};
  CONST robtarget p1:={TARGET};
  CONST robtarget p2:={TARGET};
  CONST num nLift:=50;
  CONST num nTurn:=nLift*2-10;
  VAR num nRun:=1;
  CONST string sName:="x";
  PROC main()
    MoveL Offs(p1,0,0,nLift),v100,z1,gun;
    MoveL Offs(p2,0,0,nLift),v100,z1,gun;
    MoveL Offs(p1,nLift/2,-nLift,nTurn+1),v100,z1,gun;
    MoveL Offs(p2,nLift/2,-nLift,nTurn+1),v100,z1,gun;
    MoveL RelTool(p1,0,0,nLift\\Rz:=nTurn),v100,z1,gun;
    MoveL RelTool(p2,0,0,nLift\\Rz:=nTurn),v100,z1,gun;
    MoveL RelTool(p2,0,0,1\\Rz:=nRun),v100,z1,gun;
    MoveL Offs(p1,0,0,nRun),v100,z1,gun;
    MoveL Offs(p2,0,nRun,nowhere),v100,z1,gun;
    MoveL Offs(p1,0,0,sName),v100,z1,gun;
    MoveL Offs(p2,0,0,nLift/0),v100,z1,gun;
    MoveL Offs(moving,0,0,nLift),v100,z1,gun;
    MoveL Offs(p1,0,0,nLift,nLift),v100,z1,gun;
  ENDPROC
  PROC other(num nLift)
    MoveL Offs(p1,0,0,nLift),v100,z1,gun;
    MoveL Offs(p2,0,0,nTurn),v100,z1,gun;
  ENDPROC
  PROC more()
    CONST num nTurn:=7;
    MoveL Offs(p1,0,0,nTurn),v100,z1,gun;
    MoveL Offs(p2,0,0,nLift),v100,z1,gun;
  ENDPROC
ENDMODULE
"""
    program = assert_same_model(text)
    calls = [m.target for m in program.motions]
    assert sum(t.static for t in calls) >= 8 and sum(not t.static for t in calls) >= 6
    by_line = {m.syntax.start: m.target for m in program.motions}
    values = [t.value[0][2] for t in by_line.values() if t.static and t.form == "offs"]
    assert 350.0 in values and 307.0 in values  # the target's z + nLift; + nTurn in `more`


def test_pieces_that_distinct_tails_share_are_read_once_per_scope_as_the_general_route_does():
    # `Offs(p1,gun.tframe.trans.z*2+nLift,p1.trans.x,0)`: every move its own tail (it
    # names its target), the first offset one piece in all; a piece's value, or its
    # refusal, is its scope's (a routine's parameter of the same name shadows it)
    text = f"""MODULE M
  PERS tooldata gun:={TOOL};
  CONST robtarget p1:={TARGET};
  CONST robtarget p2:={TARGET};
  CONST num nLift:=50;
  VAR num nRun:=1;
  PROC main()
    nRun := nRun + 1;
    MoveL Offs(p1,gun.tframe.trans.z*2+nLift,p1.trans.x,0),v100,z1,gun;
    MoveL Offs(p2,gun.tframe.trans.z*2+nLift,p2.trans.x,0),v100,z1,gun;
    MoveL Offs(p1,nRun*2,p1.trans.y,0),v100,z1,gun;
    MoveL Offs(p2,nRun*2,p2.trans.y,0),v100,z1,gun;
  ENDPROC
  PROC other(num nLift)
    MoveL Offs(p1,gun.tframe.trans.z*2+nLift,p1.trans.x,0),v100,z1,gun;
    MoveL Offs(p2,gun.tframe.trans.z*2+nLift,p2.trans.x,0),v100,z1,gun;
  ENDPROC
ENDMODULE
"""
    program = assert_same_model(text)
    targets = [m.target for m in program.motions]
    assert [t.static for t in targets[:2]] == [True, True]
    assert targets[0].value[0] == (251.0, -1.5, 300.0)  # x 1 + 100*2 + 50, y -2.5 + 1
    assert not any(t.static for t in targets[4:])  # nLift is a parameter there
    assert "nRun" in targets[2].reason and targets[3].reason == targets[2].reason


def test_calls_of_calls_read_in_one_step_give_the_general_model():
    """A call whose first argument is itself such a call (`Offs(RelTool(p1,0,0,1),0,0,2)`),
    nested up to the limit and past it, with every refusal at each level: the plain
    grammar's operands, values and reasons."""
    deep = "p1"
    for level in range(12):
        deep = f"Offs({deep},0,0,{level})"
    text = f"""MODULE M
  PERS tooldata gun:={TOOL};
  CONST robtarget p1:={TARGET};
  VAR robtarget moving:={TARGET};
  CONST jointtarget j1:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST num dz:=5;
  PROC r(robtarget given)
    MoveL Offs(RelTool(p1,0,0,1),0,0,2),v100,z1,gun;
    MoveL RelTool(Offs(p1,1,2,3),0,0,1\\Rz:=90),v100,z1,gun;
    MoveL Offs(RelTool(Offs(p1,0,0,1),0,0,1),-1,0,0),v100,z1,gun;
    MoveL Offs(RelTool(moving,0,0,1),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(nowhere,0,0,1),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(given,0,0,1),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(j1,0,0,1),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(p1,0,0),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(p1,0,0,1),0,0),v100,z1,gun;
    MoveL Offs(RelTool(p1,0,0,dz),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(p1,0,0,1),0,0,dz),v100,z1,gun;
    MoveL Offs(Shifted(p1,0,0,1),0,0,2),v100,z1,gun;
    MoveL Offs(CRobT(\\Tool:=gun),0,0,2),v100,z1,gun;
    MoveL Shifted(Offs(p1,0,0,1),0,0,2),v100,z1,gun;
    MoveL Offs(RelTool(p1,0,0,1\\Rz),0,0,2),v100,z1,gun;
    MoveL {deep},v100,z1,gun;
    MoveL Offs(RelTool(p1,0,0,1),0,0,2),v100,z1,gun;
  ENDPROC
ENDMODULE
"""
    program = assert_same_model(text)
    targets = [m.target for m in program.motions]
    assert sum(t.static for t in targets) >= 5 and sum(not t.static for t in targets) >= 8
    assert targets[0].value == targets[-1].value and targets[0].form == "offs"
    nested = [m for m in program.motions if isinstance(m.syntax.args[0].value, s.LazyFunctionCall)
              and isinstance(m.syntax.args[0].value.head.value, s.LazyFunctionCall)]
    assert len(nested) >= 10


def test_forgetting_the_texts_empties_every_memo_the_fast_path_keeps():
    """forget_texts gives back the memory of every text kept across files (tails, their
    values, expressions, aggregate rests, number groups)."""
    from rapidfix.rapid import fastpath

    memos = [value for value in vars(fastpath).values() if isinstance(value, fastpath.Memo)]
    assert len(memos) >= 6
    parse_text(CELL.replace("v100,z1", "v100\\V:=120,z1") + "\n")
    assert fastpath._TAILS and fastpath._ENTRIES  # tails and their values were kept
    forget_texts()
    assert not any(memos)


def test_tails_share_across_routines_unless_the_routine_declares_a_name_in_them():
    """A routine without parameters, data or FOR variables sees its module's names, so
    its moves share operands with every such routine; so do the moves of a routine
    whose declarations (here a parameter shadowing a target) the tail does not name.
    A routine that declares a name its tail holds (a local VAR, a FOR variable, both
    shadowing the module's) keeps its own, as the general route reads them."""
    plain = "    MoveL p1,v100,z1,gun\\WObj:=table;\n    MoveL p2,v100,z1,gun\\WObj:=table;\n"
    text = f"""MODULE M
  PERS tooldata gun:={TOOL};
  PERS wobjdata table:={WOBJ};
  CONST robtarget p1:={TARGET};
  CONST robtarget p2:={TARGET};
  CONST num i:=1;
  PROC a()
{plain}  ENDPROC
  PROC b(robtarget p1)
{plain}  ENDPROC
  PROC c()
    VAR tooldata gun:={TOOL};
{plain}  ENDPROC
  PROC d()
    FOR table FROM 1 TO 2 DO
{plain}    ENDFOR
  ENDPROC
  PROC e()
{plain}  ENDPROC
  PROC f()
    MoveL \\Conc \\ID:=i, p1,v100,z1,gun;
    MoveL \\Conc \\ID:=i, p2,v100,z1,gun;
  ENDPROC
  PROC g()
    VAR num i:=2;
    MoveL \\Conc \\ID:=i, p1,v100,z1,gun;
    MoveL \\Conc \\ID:=i, p2,v100,z1,gun;
  ENDPROC
ENDMODULE
"""
    program = assert_same_model(text)
    by_routine: dict[str, set[int]] = {}
    for motion in program.motions:  # (the first move with a tail is made in full)
        if motion.shared is not None:
            by_routine.setdefault(motion.routine, set()).add(id(motion.shared))
    assert len(by_routine["e"]) == 1 and by_routine["a"] == by_routine["e"]  # one tail
    assert by_routine["b"] == by_routine["a"]  # b declares p1, which its tail does not hold
    for own in ("c", "d"):
        assert not by_routine.get(own, set()) & by_routine["a"]
    # a name in the lead (`\\ID:=i`) counts too: g's own i, f's the module's
    assert not by_routine["f"] & by_routine["g"]
    ids = {m.routine: m.optional["id"].value for m in program.motions if m.routine in "fg"}
    assert ids == {"f": 1.0, "g": 2.0}
    assert not program.motions[2].targets[0].static  # b's p1 is its parameter
    assert program.motions[4].arguments["tool"].declaration.routine == "c"  # its own gun
