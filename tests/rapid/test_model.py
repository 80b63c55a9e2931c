"""The program model: declarations evaluated, motions resolved, run-time targets flagged."""

from __future__ import annotations

import gc
import math
import weakref

import numpy as np
import pytest

from rapidfix.rapid import JointTarget, RobTarget, ToolData, WobjData, parse_program
from rapidfix.rapid import parse as parse_module
from rapidfix.rapid.fastpath import parse_text
from rapidfix.rapid.model_builder import ModelBuilder
from rapidfix.rapid.source import decode_source

UNUSED = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"


def module(data: str, body: str = "") -> str:
    return f"MODULE T\n{data}\nPROC main()\n{body}\nENDPROC\nENDMODULE\n"


# ---------------------------------------------------------------- independent maths
def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ])


def quat_axis(axis, degrees):
    half = math.radians(degrees) / 2
    v = np.zeros(3)
    v["xyz".index(axis)] = math.sin(half)
    return np.array([math.cos(half), *v])


def rotate(q, v):
    qv = np.array([0.0, *v])
    conj = q * np.array([1, -1, -1, -1])
    return quat_mul(quat_mul(q, qv), conj)[1:]


def same_rotation(q1, q2):
    return min(np.abs(np.asarray(q1) - q2).max(), np.abs(np.asarray(q1) + q2).max()) < 1e-9


# ---------------------------------------------------------------- declarations
def test_robtarget_values_with_arithmetic_and_references():
    program = parse_program(module(
        "CONST num d := 10 * 2 + -3;\n"
        "CONST num half := .5;\n"
        "CONST num h := 0x1F;\n"
        f"CONST robtarget p := [[d, -2.5e1, 3 DIV 2 + 7 MOD 4],[1,0,0,0],[-1,0,-1,1],{UNUSED}];\n"
        "CONST pos q := [half, h, d / 2];\n"
        f"CONST robtarget p2 := [q, p.rot, p.robconf, p.extax];\n"
    ))
    p = program.declaration("P")
    assert p.static and p.storage == "CONST" and p.type_name == "robtarget"
    assert p.data == RobTarget((17.0, -25.0, 4.0), (1.0, 0.0, 0.0, 0.0), (-1, 0, -1, 1),
                               (9e9,) * 6)
    p2 = program.declaration("p2")
    assert p2.data.trans == (0.5, 31.0, 8.5)
    assert p2.data.robconf == (-1, 0, -1, 1)


def test_tooldata_wobjdata_loaddata_speed_zone_jointtarget():
    program = parse_program(module(
        "PERS tooldata t := [TRUE,[[1,2,100],[0.7071068,0,0.7071068,0]],"
        "[2.5,[0,0,50],[1,0,0,0],0.1,0.2,0.3]];\n"
        "TASK PERS wobjdata w := [FALSE,TRUE,\"\",[[800,0,400],[1,0,0,0]],[[0,0,10],[1,0,0,0]]];\n"
        "CONST speeddata vs := [250, 100, 5000, 1000];\n"
        "CONST zonedata zz := [FALSE, 2, 3, 3, 0.3, 3, 0.3];\n"
        f"CONST jointtarget j := [[0,-20,30.5,0,80,-1E1],{UNUSED}];\n"
    ))
    tool = program.declaration("t").data
    assert isinstance(tool, ToolData) and tool.robhold is True
    assert tool.tframe.trans == (1.0, 2.0, 100.0) and tool.tload.mass == 2.5
    assert tool.tload.iz == 0.3
    wobj = program.declaration("w").data
    assert isinstance(wobj, WobjData) and wobj.ufprog is True and wobj.oframe.trans[2] == 10.0
    assert program.declaration("w").task
    assert program.declaration("vs").data.v_tcp == 250.0
    assert program.declaration("zz").data.pzone_tcp == 2.0
    j = program.declaration("j").data
    assert isinstance(j, JointTarget) and j.robax == (0.0, -20.0, 30.5, 0.0, 80.0, -10.0)


def test_arrays_and_indexing():
    program = parse_program(module(
        "CONST num n := 2;\n"
        "CONST num grid{n, 3} := [[1,2,3],[4,5,6]];\n"
        "CONST num pick := grid{2, n + 1} * 10;\n"
        f"CONST robtarget ps{{2}} := [[[1,2,3],[1,0,0,0],[0,0,0,0],{UNUSED}],"
        f"[[4,5,6],[1,0,0,0],[0,0,0,0],{UNUSED}]];\n"
    ))
    assert program.declaration("grid").dims == (2, 3)
    assert program.declaration("pick").value == 60.0
    assert program.declaration("ps").value[1][0] == (4.0, 5.0, 6.0)


def test_names_are_case_insensitive_and_keep_spelling():
    program = parse_program(module(
        "CONST num Speed_A := 5;\nCONST num b := SPEED_a * 2;", "MoveL pX, V100, Z10, TOOL0;"))
    assert program.declaration("speed_a").name == "Speed_A"
    assert program.declaration("B").value == 10.0
    motion = program.motions[0]
    assert motion.speed.value[0] == 100.0 and motion.tool.static


def test_declaration_spans():
    text = module("  CONST num a := 1 + 2;  ! three")
    program = parse_program(text)
    decl = program.declaration("a")
    assert decl.span.text == "CONST num a := 1 + 2;"
    assert decl.value_span.text == "1 + 2"
    assert decl.name_span.text == "a"
    assert (decl.span.line, decl.span.column) == (2, 3)
    assert (decl.span.end_line, decl.span.end_column) == (2, 24)


# ---------------------------------------------------------------- motions
def test_motion_arguments_spans_and_optional():
    text = module(
        f"CONST robtarget p10 := [[1,2,3],[1,0,0,0],[0,0,0,0],{UNUSED}];\n"
        "PERS wobjdata w1 := [FALSE,TRUE,\"\",[[1,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];",
        "  MoveL \\Conc, p10, v100 \\T:=2, z10, tool0 \\WObj:=w1 \\TLoad:=load0;",
    )
    program = parse_program(text, "cell.mod")
    (m,) = program.motions
    assert m.name == "MoveL" and m.routine == "main" and m.module == "T"
    assert m.span.text.startswith("MoveL \\Conc") and m.span.text.endswith(";")
    assert m.span.file == "cell.mod" and m.span.line == 5
    assert m.target.name == "p10" and m.target.form == "name" and m.target.static
    assert m.target.declaration is program.declaration("p10")
    assert m.target.value_span.text == "p10"
    assert m.speed.text == "v100" and m.zone.data.pzone_tcp == 10.0
    assert m.tool.data.tframe.trans == (0.0, 0.0, 0.0)
    assert m.wobj.text == "w1" and m.wobj.span.text == "\\WObj:=w1"
    assert m.wobj.data.uframe.trans == (1.0, 0.0, 0.0)
    assert set(m.optional) == {"conc", "t", "wobj", "tload"}
    assert m.optional["conc"].form == "switch"
    assert m.optional["t"].value == 2.0


def test_every_operand_text_is_its_source_text_and_an_inline_target_keeps_no_copy():
    # the text of each operand against the source slice of its expression, on moves the
    # fast path reads (shared tails, inline targets, Offs, nested calls) and on a move
    # with a comment inside, which the plain grammar reads
    inline = f"[[1,2,3],[1,0,0,0],[0,0,0,0],{UNUSED}]"
    text = module(
        f"CONST robtarget p10 := {inline};",
        f"  MoveL {inline}, v100, z10, tool0;\n"
        f"  MoveL [[4,5,6],[1,0,0,0],[0,0,0,0],{UNUSED}], v100, z10, tool0;\n"
        "  MoveL Offs(p10, 0, 0, 5), v200, fine, tool0 \\WObj:=wobj0;\n"
        "  MoveJ Offs(RelTool(p10,0,0,1),0,0,2), v100, z10, tool0;\n"
        "  MoveL p10, ! a comment\n    v100, z1 ,  tool0;\n"
        "  MoveL \\Conc, p10, v100 \\T:=2, z10, tool0;",
    )
    program = parse_program(text, "cell.mod")
    assert len(program.motions) == 6
    seen = 0
    for motion in program.motions:
        for operand in [*motion.arguments.values(), *motion.optional.values()]:
            value = operand.argument.value
            expected = "" if value is None else text[value.start:value.end]
            assert operand.text == expected, (motion.name, expected)
            seen += 1
    assert seen == 27
    first = program.motions[0].target
    assert first.form == "inline" and first.given_text is None
    assert first.text == inline
    assert program.motions[2].target.text == "Offs(p10, 0, 0, 5)"
    assert program.motions[3].target.text == "Offs(RelTool(p10,0,0,1),0,0,2)"


@pytest.mark.parametrize("instruction,args,targets,kind", [
    ("MoveJ", "p1, v100, z10, tool0", ["p1"], "robtarget"),
    ("MoveC", "p1, p2, v100, z10, tool0", ["p1", "p2"], "robtarget"),
    ("MoveAbsJ", "j1\\NoEOffs, v100, z10, tool0", ["j1"], "jointtarget"),
    ("MoveLDO", "p1, v100, z10, tool0, do1, 1", ["p1"], "robtarget"),
    ("MoveCDO", "p1, p2, v100, z10, tool0, do1, 1", ["p1", "p2"], "robtarget"),
    ("MoveJSync", "p1, v100, z10, tool0, \"proc\"", ["p1"], "robtarget"),
    ("TriggL", "p1, v100, trigg1, z10, tool0", ["p1"], "robtarget"),
    ("TriggC", "p1, p2, v100, trigg1, z10, tool0", ["p1", "p2"], "robtarget"),
    ("SearchL", "\\Stop, di1, sp, p1, v100, tool0", ["p1"], "robtarget"),
    ("ArcL", "\\On, p1, v100, seam1, weld1, weave1, z10, tool0", ["p1"], "robtarget"),
    ("ArcC", "p1, p2, v100, seam1, weld1, weave1, fine, tool0", ["p1", "p2"], "robtarget"),
])
def test_motion_variants(instruction, args, targets, kind):
    program = parse_program(module("", f"  {instruction} {args};"))
    (m,) = program.motions
    assert [t.text for t in m.targets] == targets
    assert m.target_kind == kind
    assert m.tool.text == "tool0"
    if instruction.startswith("Trigg"):
        assert m.arguments["trigg1"].text == "trigg1"
    if instruction != "SearchL":
        assert m.zone is not None


def test_offs_evaluated():
    program = parse_program(module(
        f"CONST robtarget p := [[100,200,300],[0,0,1,0],[0,0,0,0],{UNUSED}];\nCONST num dz := 50;",
        "  MoveL Offs(p, 10, -20, dz * 2), v100, z10, tool0;"))
    target = program.motions[0].target
    assert target.form == "offs" and target.name == "p" and target.static
    assert target.data.trans == (110.0, 180.0, 400.0)
    assert target.data.rot == (0.0, 0.0, 1.0, 0.0)


@pytest.mark.parametrize("rot,d,angles", [
    ((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 100.0), (0.0, 0.0, 0.0)),
    ((0.0, 0.0, 1.0, 0.0), (10.0, 20.0, 30.0), (0.0, 0.0, 90.0)),
    ((0.7071068, 0.0, 0.7071068, 0.0), (5.0, -7.0, 11.0), (30.0, -45.0, 60.0)),
    ((0.5, 0.5, 0.5, 0.5), (0.0, 0.0, 0.0), (15.0, 25.0, 35.0)),
])
def test_reltool_against_quaternion_algebra(rot, d, angles):
    rx, ry, rz = angles
    program = parse_program(module(
        f"CONST robtarget p := [[100,200,300],[{','.join(map(str, rot))}],[0,0,0,0],{UNUSED}];",
        f"  MoveL RelTool(p, {d[0]}, {d[1]}, {d[2]} \\Rx:={rx} \\Ry:={ry} \\Rz:={rz}), "
        "v100, z10, tool0;"))
    target = program.motions[0].target
    assert target.form == "reltool" and target.static
    q = np.asarray(rot) / np.linalg.norm(rot)
    expected_trans = np.array([100.0, 200.0, 300.0]) + rotate(q, d)
    # intrinsic: first about x, then the new y, then the new z
    expected_rot = quat_mul(quat_mul(quat_mul(q, quat_axis("x", rx)), quat_axis("y", ry)),
                            quat_axis("z", rz))
    assert np.allclose(target.data.trans, expected_trans, atol=1e-9)
    assert same_rotation(target.data.rot, expected_rot)
    assert target.data.rot[0] >= 0


def test_reltool_turns_kept_per_orientation_equal_fresh_ones_to_the_bit():
    from rapidfix.rapid import poses

    rot = (0.0, 0.258819045, 0.965925826, 0.0)
    other = (0.5, 0.5, 0.5, 0.5)
    angles = [(0.0, 0.0, 90.0), (-0.0, 0.0, 90.0), (0.0, -0.0, 90.0), (30.0, -45.0, 60.0),
              (0.0, 0.0, 90.0), (-0.0, 0.0, 90.0)]
    cases = [(((1.0, 2.0, 3.0), r, (0.0, 0.0, 0.0, 0.0), (9e9,) * 6), a)
             for r in (rot, other, rot) for a in angles]
    poses._TURNED.clear()
    kept = [poses.reltool(target, 1.0, -2.0, 3.0, *a) for target, a in cases]
    assert len(poses._TURNED) == 4  # two turns per orientation: none with a -0.0
    fresh = []
    for target, a in cases:
        poses._TURNED.clear()
        fresh.append(poses.reltool(target, 1.0, -2.0, 3.0, *a))
    assert repr(kept) == repr(fresh)  # the sign of every zero too


def test_reltool_of_offs_nested():
    program = parse_program(module(
        f"CONST robtarget p := [[0,0,0],[0,0,1,0],[0,0,0,0],{UNUSED}];",
        "  MoveL RelTool(Offs(p, 10, 0, 0), 0, 0, -30), v100, z10, tool0;"))
    # the tool z axis of [0,0,1,0] (180 deg about y) points down: -30 in tool z is +30 in z
    assert np.allclose(program.motions[0].target.data.trans, (10.0, 0.0, 30.0))


@pytest.mark.parametrize("data,body,reason", [
    ("VAR robtarget pv;", "  pv := CRobT();\n  MoveL pv, v100, z10, tool0;",
     "assigned at line 4"),
    (f"VAR robtarget pv := [[0,0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];",
     "  FOR i FROM 1 TO 3 DO\n    pv.trans.x := i;\n    MoveL pv, v100, z10, tool0;\n  ENDFOR",
     "in a loop"),
    ("", "  MoveL CRobT(), v100, z10, tool0;", "CRobT is read from the controller"),
    (f"VAR robtarget pf := [[0,0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];\nVAR iodev f;",
     "  ReadAnyBin f, pf;\n  MoveL pf, v100, z10, tool0;", "written by ReadAnyBin"),
    (f"CONST robtarget p0 := [[0,0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];",
     "  FOR i FROM 1 TO 3 DO\n    MoveL Offs(p0, i * 10, 0, 0), v100, z10, tool0;\n  ENDFOR",
     "FOR loop variable"),
    ("", "  MoveL pMissing, v100, z10, tool0;", "not declared in this file"),
    ("VAR robtarget pNone;", "  MoveL pNone, v100, z10, tool0;", "declared without a value"),
])
def test_runtime_targets_have_reasons(data, body, reason):
    program = parse_program(module(data, body))
    target = program.motions[-1].target
    assert not target.static and target.value is None
    assert reason in target.reason


def test_routine_parameter_and_inout_writes():
    text = (
        "MODULE T\n"
        f"VAR robtarget pa := [[0,0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];\n"
        f"VAR robtarget pb := [[0,0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];\n"
        "PROC Go(robtarget p)\n  MoveL p, v100, z10, tool0;\nENDPROC\n"
        "PROC Shift(INOUT robtarget p)\n  p.trans.z := p.trans.z + 1;\nENDPROC\n"
        "PROC main()\n  Shift pa;\n  Go pb;\n  MoveL pa, v100, z10, tool0;\n"
        "  MoveL pb, v100, z10, tool0;\nENDPROC\nENDMODULE\n"
    )
    program = parse_program(text)
    go, pa_move, pb_move = program.motions
    assert "parameter of routine Go" in go.target.reason
    assert not pa_move.target.static and "written by Shift" in pa_move.target.reason
    assert pb_move.target.static  # passed by value only


def test_local_declarations_shadow_module_ones():
    program = parse_program(
        "MODULE T\nCONST num k := 1;\n"
        f"PROC main()\n  CONST robtarget q := [[k,0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];\n"
        "  CONST num k := 5;\n  MoveL Offs(q, k, 0, 0), v100, z10, tool0;\nENDPROC\nENDMODULE")
    assert program.motions[0].target.data.trans == (10.0, 0.0, 0.0)
    assert program.declaration("q", routine="main").routine == "main"


def test_self_reference_is_not_static():
    program = parse_program(module("CONST num a := b + 1;\nCONST num b := a;"))
    assert not program.declaration("a").static
    assert "itself" in (program.declaration("a").reason + program.declaration("b").reason)


def test_value_that_does_not_fit_type():
    program = parse_program(module("CONST robtarget p := [[1,2],[1,0,0,0]];"))
    decl = program.declaration("p")
    assert not decl.static and "does not fit robtarget" in decl.reason


def test_division_by_zero_is_a_reason_not_a_crash():
    program = parse_program(module("CONST num a := 1 / 0;\nCONST num b := 5 DIV (2 - 2);"))
    assert "division by zero" in program.declaration("a").reason
    assert "division by zero" in program.declaration("b").reason


def test_module_declaration_area():
    text = "MODULE T\n  CONST num a := 1;\n  VAR num b;\n  PROC main()\n  ENDPROC\nENDMODULE\n"
    program = parse_program(text)
    module_info = program.modules[0]
    assert text[:module_info.declarations_end].endswith("VAR num b;")
    assert text[:module_info.header_end].endswith("MODULE T")


def test_confdata_beyond_any_whole_number_is_a_reason_not_a_crash():
    program = parse_program(module(
        f"CONST robtarget p := [[1,2,3],[1,0,0,0],[0,1e999,0,0],{UNUSED}];",
        "  MoveL p, v100, z10, tool0;"))
    decl = program.declaration("p")
    assert not decl.static and decl.value is None
    assert "does not fit robtarget" in decl.reason and "confdata" in decl.reason
    assert not program.motions[0].target.static


# ---------------------------------------------------------------- memory
def test_the_builder_is_freed_by_reference_counting_alone():
    source = decode_source(module(
        f"CONST robtarget p := [[1,2,3],[1,0,0,0],[0,0,0,0],{UNUSED}];\nCONST num d := 2;",
        "  MoveL Offs(p, d, 0, 0), v100, z10, tool0;\n  MoveL p, v100, z10, tool0;"))
    builder = ModelBuilder(source, source.encode(), parse_text(source.text))
    program = builder.build()
    assert program.motions[0].target.data.trans == (3.0, 2.0, 3.0)
    gone = weakref.ref(builder)
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        del builder
        assert gone() is None  # no reference cycle keeps it (and its tables) alive
    finally:
        if was_enabled:
            gc.enable()


@pytest.mark.parametrize("body", [
    "  MoveL target, v100, z10, tool0;",  # a parameter: not known before run time
    "  MoveL Offs(target, 0, 0, 1), v100, z10, tool0;",
    "  MoveL Offs(RelTool(target, 0, 0, 1), 0, 0, 1), v100, z10, tool0;",
    "  MoveL Offs(nowhere, d, 0, 0), v100, z10, tool0;",  # not declared
    "  MoveL Offs(p, target.trans.x, 0, 0), v100, z10, tool0;",  # a parameter's component
    "  FOR i FROM 1 TO 2 DO\n    MoveL path{i}, v100, z10, tool0;\n  ENDFOR",
])
def test_a_model_with_values_unknown_before_run_time_holds_no_cycle(body):
    """What the evaluator cannot know raises NotConstant, whose traceback holds the
    builder's frames: a reason kept from one (the lookups' cache, a call's first
    argument) is kept without it, or the builder and the program it made would stand
    in a cycle until a collection (never, once a large build is frozen)."""
    target = f"[[1,2,3],[1,0,0,0],[0,0,0,0],{UNUSED}]"
    text = (f"MODULE M\nCONST robtarget p := {target};\nCONST num d := 2;\n"
            f"CONST robtarget path{{2}} := [{target},{target}];\n"
            f"PROC r(robtarget target)\n{body}\n{body}\nENDPROC\nENDMODULE\n")
    was_enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        program = parse_program(text, "unknown.mod")
        assert not program.motions[0].target.static and program.motions[0].target.reason
        del program
        assert gc.collect() == 0  # everything went with the last reference
    finally:
        if was_enabled:
            gc.enable()


def _large_program(n: int = 300) -> str:
    data = "\n".join(f"CONST robtarget p{i} := [[{i},0,0],[1,0,0,0],[0,0,0,0],{UNUSED}];"
                     for i in range(n))
    body = "\n".join(f"  MoveL p{i}, v100, z10, tool0;" for i in range(n))
    return module(data, body)


@pytest.fixture
def collector_state():
    """The collector as a test found it: enabled, nothing frozen (restored after)."""
    was_enabled = gc.isenabled()
    gc.enable()
    gc.unfreeze()
    yield
    gc.unfreeze()
    if not was_enabled:
        gc.disable()


def test_a_large_build_keeps_its_objects_out_of_later_collections(monkeypatch,
                                                                  collector_state):
    monkeypatch.setattr(parse_module, "_MANY_OBJECTS", 1000)
    text = _large_program()
    full_collections = gc.get_stats()[2]["collections"]
    program = parse_program(text)
    assert len(program.motions) == 300
    assert gc.get_stats()[2]["collections"] == full_collections  # nothing walked
    assert gc.get_count()[0] < 1000  # the young generation starts empty
    assert gc.get_freeze_count() > 300 * 5  # the model's objects, and all before them
    frozen = gc.get_freeze_count()
    del program
    assert gc.get_freeze_count() < frozen - 300 * 3  # reference counting still frees it


class _Cyclic:
    """An object in a reference cycle: only the cyclic collector frees it."""

    def __init__(self) -> None:
        self.me = self


def test_cyclic_garbage_frozen_by_a_build_is_collected_by_a_later_one(monkeypatch,
                                                                      collector_state):
    monkeypatch.setattr(parse_module, "_MANY_OBJECTS", 1000)
    garbage = _Cyclic()
    gone = weakref.ref(garbage)
    del garbage  # cyclic garbage the collector has not seen yet
    first = parse_program(_large_program())  # frozen with the model
    assert gone() is not None
    gc.collect()
    assert gone() is not None  # frozen objects are not collected
    # while the first model stands, what was frozen outnumbers a small build's objects:
    # that build collects everything once before it freezes
    second = parse_program(_large_program(150))
    assert gone() is None
    assert len(first.motions) == 300 and len(second.motions) == 150


def test_a_subclass_of_a_node_is_evaluated_as_its_base():
    """Evaluator.typed looks a node's evaluation up by its exact type; a subclass (none
    is made by rapidfix) falls back to its nearest base's, and a node of no known type
    is refused with a reason."""
    from rapidfix.rapid import syntax as s
    from rapidfix.rapid.evaluate import Evaluator, NotConstant

    class Sum(s.Binary):
        pass

    class Odd(s.Node):
        pass

    names = {"n": (2.0, "num")}
    evaluator = Evaluator(names.__getitem__)
    tree = Sum(0, 5, "*", s.NameRef(0, 1, "n"),
               s.Paren(2, 5, s.Unary(3, 4, "-", s.Number(3, 4, 3.0, "3"))))
    assert evaluator.typed(tree) == (-6.0, "num")
    with pytest.raises(NotConstant, match="cannot evaluate Odd"):
        evaluator.typed(Odd(0, 1))
