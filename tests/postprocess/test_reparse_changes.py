"""The rewrite's verification parses only the new statements and declarations.

Checked against the independent route, a full parse of the whole output: every
statement or declaration the output changed is among the check units, and the
targets read back from them are those the whole output commands. A unit that
does not parse stops the rewrite and nothing is written.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidfix.exceptions import RapidSemanticError
from rapidfix.postprocess import emission as emission_module
from rapidfix.postprocess import rewrite as rewrite_module
from rapidfix.postprocess import verify as verify_module
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_file, rewrite_source
from rapidfix.postprocess.verify import parse_units, read_back_full
from rapidfix.rapid import parse_program
from rapidfix.rapid.readback import read_bulk

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from cam_program import cam_program
from odd_shapes import odd_program
from program_shapes import shape_program

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
PROGRAMS = sorted(p.name for p in SAMPLES.iterdir() if p.suffix.lower() in (".mod", ".prg"))


def _rewrite_capturing_units(monkeypatch, data, name, comp, options):
    captured = {}
    original = rewrite_module.read_back

    def spy(units, filename, expected):
        captured["units"], captured["expected"] = units, expected
        captured["motions"] = parse_units(units, filename)  # the full route, on its own
        captured["read"] = original(units, filename, expected)
        return captured["read"]

    monkeypatch.setattr(rewrite_module, "read_back", spy)
    return rewrite_source(data, name, comp, options), captured


def _same_read(a, b):
    for field in ("joint", "robax", "trans", "rot", "conf"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


def _text(program, node):
    return program.text[node.span.start:node.span.end]


@pytest.mark.parametrize("emit", ["jointtargets", "robtargets"])
@pytest.mark.parametrize("name", PROGRAMS)
def test_check_units_hold_every_change_and_read_back_what_the_output_commands(
        monkeypatch, comp, name, emit):
    data = (SAMPLES / name).read_bytes()
    result, captured = _rewrite_capturing_units(monkeypatch, data, name, comp,
                                                RewriteOptions(emit=emit))
    before = parse_program(data, name)
    after = parse_program(result.data, name)
    check_text, _ = captured["units"].text()
    check = parse_program(check_text, "check")
    check_decls = {_text(check, d) for d in check.declarations}
    check_motions = {_text(check, m): m for m in captured["motions"]}

    old_decls = {_text(before, d) for d in before.declarations}
    new_decls = [_text(after, d) for d in after.declarations if _text(after, d) not in old_decls]
    assert set(new_decls) <= check_decls
    old_motions = {_text(before, m) for m in before.motions}
    changed = [m for m in after.motions if _text(after, m) not in old_motions]
    assert {_text(after, m) for m in changed} <= set(check_motions)
    if result.moves_compensated:
        assert changed or new_decls

    # same text, same values: the check program reads each target as the output does
    compared = 0
    for motion in after.motions:
        twin = check_motions.get(_text(after, motion))
        if twin is None:
            continue
        for ours, theirs in zip(twin.targets, motion.targets, strict=True):
            assert ours.value == theirs.value
            compared += 1
    assert compared >= len(captured["motions"])
    # what the rewrite read back (in bulk where it could) is what the full model reads
    _same_read(captured["read"], read_back_full(captured["units"], name, captured["expected"]))


def test_a_cam_program_is_read_back_in_bulk_with_the_values_the_model_reads(
        monkeypatch, comp):
    text = cam_program(300)

    def full_route(*args):
        raise AssertionError("the CAM program's parts went the full route")

    monkeypatch.setattr(verify_module, "read_back_full", full_route)
    result, captured = _rewrite_capturing_units(monkeypatch, text.encode(), "cam.mod", comp,
                                                RewriteOptions())
    monkeypatch.undo()
    assert result.moves_compensated == 300
    check_text, order = captured["units"].text()
    bulk = read_bulk(check_text)
    assert bulk is not None and len(bulk.calls) == len(order) == 300
    full = read_back_full(captured["units"], "cam.mod", captured["expected"])
    assert full.joint.all()
    _same_read(captured["read"], full)
    # and the joints are those the motions of the full parse name
    for ident, motion in enumerate(captured["motions"][:20]):
        row = np.flatnonzero(captured["expected"].motion == ident)[0]
        assert motion.targets[0].value[0] == tuple(full.robax[row])


@pytest.mark.parametrize("text", [
    "MODULE m\nPROC p()\n  IF a MoveL p1, v100, z1, tool0;\nENDPROC\nENDMODULE\n",
    "MODULE m\nVAR num a{2};\nENDMODULE\n",
    "MODULE m\nPROC p()\n  MoveL Offs(p1, 1, 0, 0), v100, z1, tool0;\nENDPROC\nENDMODULE\n",
    "MODULE m\nPROC p()\n  MoveL p1, v100, z1, tool0\nENDPROC\nENDMODULE\n",
    "MODULE m\nPROC p(num x)\n  MoveL p1, v100, z1, tool0;\nENDPROC\nENDMODULE\n",
])
def test_the_bulk_reader_declines_what_is_not_simple_or_does_not_parse(text):
    assert read_bulk(text) is None


def test_the_bulk_reader_reads_scopes_and_arguments():
    text = ("MODULE m\nCONST jointtarget j:=[[1,2,3,4,5,6],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
            "CONST jointtarget J:=[[0,0,0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
            "PROC p()\n  LOCAL CONST jointtarget j:=[[6,5,4,3,2,1],[0,0,0,0,0,0]];\n"
            "  MoveAbsJ j\\NoEOffs, v100, fine, tool0 \\WObj:=w;\n"
            "  MoveC\\Conc, c1, [[1,2,3],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,0]], v5, z1, t;\n"
            "ENDPROC\nPROC q()\n  MoveAbsJ j, v100, z1, tool0;\nENDPROC\nENDMODULE\n")
    bulk = read_bulk(text)
    assert bulk is not None and [c[0] for c in bulk.calls] == ["MoveAbsJ", "MoveC", "MoveAbsJ"]
    assert bulk.arguments(0) == (("j", "v100", "fine", "tool0"), {"noeoffs": None, "wobj": "w"})
    assert bulk.arguments(1)[0][:2] == ("c1", "[[1,2,3],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,0]]")
    assert bulk.arguments(1)[1] == {"conc": None}
    assert [bulk.scope(i) for i in range(3)] == [("m", "p"), ("m", "p"), ("m", "q")]
    assert bulk.lookup("m", "p", "J")[1] == "[[6,5,4,3,2,1],[0,0,0,0,0,0]]"
    assert bulk.lookup("m", "q", "j")[1].startswith("[[1,2,3")


_ARGUMENTS = ["p1", "p2", "[[1,2,3],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,0]]", "v100", "z1",
              "tool0", "\\WObj:=w", "\\Conc", "\\V:=120", "-1", "fine", "\\ID:=17"]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from(["MoveC", "MoveL", "Foo"]),
                          st.lists(st.sampled_from(_ARGUMENTS), min_size=1, max_size=6),
                          st.sampled_from([",", ", ", " ,\n  ", ",! c\n"])),
                min_size=1, max_size=12))
def test_the_bulk_reader_splits_every_call_as_read_whole(calls):
    """Call arguments read through the shared texts after the first and the second value
    are those of the text after the first value read whole."""
    from rapidfix.rapid.readback import _tail_arguments

    lines = [f"  {name} {sep.join(args)};" for name, args, sep in calls]
    bulk = read_bulk("MODULE m\nPROC p()\n" + "\n".join(lines) + "\nENDPROC\nENDMODULE\n")
    if bulk is None:  # a call the grammar refuses (a switch after a value, ...)
        return
    for _ in range(2):  # read again: now from what was kept
        for i, (_name, first, rest) in enumerate(bulk.calls):
            required, optional = _tail_arguments(rest)
            assert bulk.arguments(i) == (((first, *required) if first else required), optional)


def test_a_rewritten_part_that_does_not_parse_stops_the_rewrite(monkeypatch, comp, tmp_path):
    source = SAMPLES / "ballbar.mod"
    real = emission_module.jointtarget_literals

    def broken(q_deg, extax):
        return [text[:-1] for text in real(q_deg, extax)]  # drops the closing bracket

    monkeypatch.setattr(emission_module, "jointtarget_literals", broken)
    out = tmp_path / "out.mod"
    with pytest.raises(RapidSemanticError, match="does not parse"):
        rewrite_file(source, out, comp, RewriteOptions())
    assert not out.exists() and not list(tmp_path.iterdir())


def _filtered_cases() -> str:
    """A program whose filtered robtargets take every way: declarations that take the
    filtered robtarget (used by one move, or by two with the same literal), names used
    elsewhere too or by two moves with different literals (a new robtarget after the
    declaration, LOCAL after a LOCAL one, one whose name is taken), Offs and RelTool of
    a name (one declaration for the same literal, a numbered one for another), inline
    targets, a MoveC with one target inline or both new, a routine's own declaration."""
    lines = cam_program(8).splitlines()
    decls = [line for line in lines if "CONST robtarget" in line]
    literal = decls[6].split(":=", 1)[1].rstrip(";")
    inline = literal.replace("-147.000", "-146.250", 1)
    move = ", v100, z1, tMill\\WObj:=wPlate;"
    body = [
        lines[1].replace("tMill:=[TRUE,[[0,0,100]", "tMill2:=[TRUE,[[0,0,102]"),
        f"  LOCAL CONST robtarget q1:={literal};",
        f"  CONST robtarget ft_p3:={literal};",
        "  VAR robtarget pTmp;",
        "  PROC main()",
        "    MoveJ p0, v500, fine, tMill\\WObj:=wPlate;",
        f"    MoveL p1{move}", f"    MoveL p1{move}",
        f"    MoveL p2{move}", "    pTmp := p2;",
        f"    MoveL Offs(p3, 0, 0, 1){move}", f"    MoveL Offs(p3, 0, 0, 1){move}",
        f"    MoveL Offs(p3, 0, 0, 2){move}", f"    MoveL p3{move}",
        f"    MoveL {inline}{move}",
        f"    MoveL RelTool(p4, 0, 0, 5){move}", f"    MoveL p4{move}",
        f"    MoveC {inline}, p5{move}", f"    MoveL p5{move}",
        f"    MoveC Offs(p6, 0, 2, 0), {inline}{move}",
        f"    MoveL q1{move}", f"    MoveL Offs(q1, 1, 0, 0){move}",
        "  ENDPROC",
        "  PROC other()",
        f"    CONST robtarget r1:={inline};",
        f"    MoveL r1{move}", f"    MoveL r1{move}", "    pTmp := r1;", f"    MoveL p2{move}",
        f"    MoveL p7{move}", f"    MoveL p7{move.replace('tMill', 'tMill2')}",
        "  ENDPROC",
        "ENDMODULE",
    ]
    return "\n".join([*lines[:3], *decls, *body]) + "\n"


_STACKED = odd_program("stacked", 300)


def _arcs() -> str:
    """Arcs with intermediate points whose statements share their text after the target
    or differ in it: switches before the targets, \\Z, \\Inpos and \\T (which an
    intermediate point drops), other zones, a comment in the tail."""
    variants = [
        lambda line: line,
        lambda line: line.replace("MoveC ", "MoveC \\Conc, "),
        lambda line: line.replace(", fine,", ", z10 \\Z:=5,"),
        lambda line: line.replace(", fine,", ", fine \\Inpos:=inpos20,"),
        lambda line: line.replace(", vFeed,", ", vFeed \\T:=2,"),
        lambda line: line.replace(", fine,", ", ! zone next\n      fine,"),
        lambda line: line.replace(", fine,", ",fine ,"),
        # arguments an intermediate point drops before the target: the same statement
        # parts for every move of one text, shared
        lambda line: line.replace("MoveC ", "MoveC \\Conc \\ID:=7, "),
        lambda line: line.replace("MoveC ", "MoveC \\T:=2 \\Conc, "),
    ]
    lines, k = [], 0
    for line in shape_program("movec", 400).splitlines():
        if line.lstrip().startswith("MoveC "):
            line = variants[(k // 2) % len(variants)](line)
            k += 1
        lines.append(line)
    return "\n".join(lines) + "\n"


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(0, 4), min_size=1, max_size=30), st.booleans())
def test_moves_and_their_inserted_points_are_placed_as_one_list(counts, before):
    """`_interleave` (how the emission orders each move's name or statement with those of
    the points inserted before it) against the list built one move at a time."""
    items = [f"m{j}" for j in range(len(counts))]
    extras = [f"m{j}x{t}" for j, c in enumerate(counts) for t in range(c)]
    expected, owners, at = [], [], 0
    for j, c in enumerate(counts):
        own = extras[at:at + c]
        at += c
        expected += [*own, items[j]] if before else [items[j], *own]
        owners += [j] * (c + 1)
    places, extra_places, order, owner = emission_module._interleave(
        np.array(counts, dtype=np.int64), before)
    assert [(items + extras)[n] for n in order] == expected
    assert [expected[n] for n in places] == items
    assert [expected[n] for n in extra_places] == extras
    assert owner == owners


@pytest.mark.parametrize("emit", ["jointtargets", "robtargets"])
@pytest.mark.parametrize("name", [*PROGRAMS, "cam", "filtered_cases", "stacked", "arcs",
                                  "concurrent"])
def test_moves_emitted_in_columns_give_what_the_move_by_move_route_gives(monkeypatch, comp, name,
                                                                        emit):
    data = (cam_program(200) if name == "cam" else _filtered_cases()
            if name == "filtered_cases" else _STACKED if name == "stacked"
            else _arcs() if name == "arcs" else odd_program("concurrent", 300)
            if name == "concurrent" else (SAMPLES / name).read_bytes())
    data = data.encode() if isinstance(data, str) else data
    options = RewriteOptions(emit=emit, force=True)
    columns = rewrite_source(data, name, comp, options)
    monkeypatch.setattr(emission_module._Emitter, "_columns", False)
    one_by_one = rewrite_source(data, name, comp, options)
    assert columns.data == one_by_one.data
    assert one_by_one.moves_compensated == columns.moves_compensated
    if name == "arcs" and emit == "jointtargets":  # every variant got intermediate points
        # but the synchronized one (`\\ID`), which kept its MoveC
        out = columns.data.decode()
        assert columns.points_added > 50
        for shown in ["MoveAbsJ \\Conc, jt_", "_1, vFeed, z0, tMill", "_1, vFeed, z0 , tMill",
                      "_1, vFeed , z0, tMill", "_1, vFeed, ! zone next\n      z0,",
                      "_1, vFeed,z0 , tMill", "MoveC \\Conc \\ID:=7, ft_",
                      "MoveAbsJ \\T:=2 \\Conc, jt_"]:
            assert shown in out, shown
    assert one_by_one.worst_predicted_mm == columns.worst_predicted_mm
    if name == "filtered_cases" and emit == "robtargets":
        # every way a filtered robtarget is written was taken
        out = columns.data.decode()
        for declared in ["LOCAL CONST robtarget ft_q1:=", "CONST robtarget ft_p2:=",
                         "CONST robtarget ft_p3_2:=", "CONST robtarget ft_p3_offs:=",
                         "CONST robtarget ft_p3_offs_2:=", "CONST robtarget ft_p4_reltool:=",
                         "CONST robtarget ft_q1_offs:=", "    CONST robtarget ft_r1:=",
                         "CONST robtarget ft_p6_offs:=", "CONST robtarget ft_p7:=",
                         "CONST robtarget ft_p7_2:="]:
            assert out.count(declared) == 1, declared
        assert out.count("MoveL ft_p3_offs,") == 2 and "MoveL p1," in out
        assert "MoveC [[" in out and "MoveC ft_p6_offs, [[" in out and "MoveL [[" in out
        assert columns.moves_compensated == 21


def test_jointtarget_literals_are_read_back_in_one_pass_or_left_to_the_full_route():
    from rapidfix.rapid.readback import NotBulk, joint_values

    good = ["[[1,-2.5,3E+02,.5,1.,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]",
            "[[-0.000001,10,20,30,40,50],[0,0,0,0,0,1.25]]"] * 300
    got = joint_values(good)
    want = [[float(v) for v in t[2:t.index("]")].split(",")] for t in good]
    assert np.array_equal(got, np.array(want))
    for bad in ["[[1.2.3,0,0,0,0,0],[0,0,0,0,0,0]]", "[[1e,0,0,0,0,0],[0,0,0,0,0,0]]",
                "[[--1,0,0,0,0,0],[0,0,0,0,0,0]]", "[[0,0,0,0,0],[0,0,0,0,0,0]]",
                "[[0,0,0,0,0,0,0],[0,0,0,0,0,0]]", "[[0,0,0,0,0,0],[0,0,0,0,0]]",
                "[[0,0,0,0,0,0],[0,0,0,0,0,0],[0]]", "[[0,0,0,0,0,0]]", "[[1e999,0,0,0,0,0],"
                "[0,0,0,0,0,0]]"]:
        with pytest.raises(NotBulk):
            joint_values([*good[:5], bad, *good[:300]])


def test_robtarget_literals_are_read_back_in_one_pass_as_one_by_one():
    """robtarget_values gives what _robtarget_value (the exact reader) gives each literal,
    in one pass for the rewrite's compact form and one by one for any other, and refuses
    (NotBulk) what it refuses."""
    from rapidfix.rapid.readback import NotBulk, _robtarget_value, robtarget_values

    compact = ["[[1,-2.5,3E+02],[1,0,0,0],[0,-1,2,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]",
               "[[.5,1.,-0],[0.5,0.5,0.5,0.5],[1,1,1,1],[0,0,0,0,0,1e999]]"] * 200
    spaced = "[[1, 2, 3], [1,0,0,0], [0,0,0,0], [0,0,0,0,0,0]]"
    for texts in (compact, [*compact[:3], spaced, *compact[:3]]):
        got = robtarget_values(texts)
        want = [np.array(part, dtype=float) for part in zip(*map(_robtarget_value, texts))]
        for g, w in zip(got, want):
            assert np.array_equal(g, w)
    for bad in ["[[1.2.3,0,0],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,0]]",
                "[[1e,0,0],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,0]]",
                "[[0,0,0],[1,0,0,0],[0,1e999,0,0],[0,0,0,0,0,0]]",
                "[[0,0,0],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,1e]]",
                "[[0,0,0],[1,0,0,0],[0,0,0,0],[0,0,0,0,0]]", "[[0,0,0],[1,0,0,0],[0,0,0,0]]",
                "[[0,0],[1,0,0,0],[0,0,0,0],[0,0,0,0,0,0]]"]:
        with pytest.raises(NotBulk):
            _robtarget_value(bad)
        with pytest.raises(NotBulk):
            robtarget_values([*compact[:5], bad, *compact[:5]])


# ------------------------------------------------------------- the read-back in columns
def _units(declarations, statements):
    """Check units with jointtarget declarations (module level of M) and MoveAbsJ
    statements given as (text before the name, name, text after) in routine p."""
    from rapidfix.postprocess.reparse_changes import CheckUnits

    units = CheckUnits()
    units.add_jointtarget_declarations("M", None, declarations)
    units.add_statements(["M"] * len(statements), ["p"] * len(statements),
                         ["".join(slot) for slot in statements], statements)
    return units


def _expected(count, joints_deg=None):
    from rapidfix.postprocess.placement import Placement
    from rapidfix.postprocess.verify import Expected

    eye = np.repeat(np.eye(4)[None], count, 0)
    joints = None if joints_deg is None else np.radians(np.asarray(joints_deg, float))
    # the read-back needs no frames nor conditions
    return Expected(np.arange(count), np.zeros(count, int), np.zeros((count, 3)),
                    Placement(eye, eye, eye), None, joints)


_DECLS = ["CONST jointtarget jt_a:=[[1,2,3,4,5,6],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
          "CONST jointtarget jt_b:=[[-1.5,0,.25,10,20,30],[0,0,0,0,0,0]];"]
_MOVES = [("MoveAbsJ ", "jt_b", ", v100, z1, tool0;"),
          ("MoveAbsJ\\Conc, ", "JT_A", ", v100, fine, tool0 \\WObj:=w;"),
          ("MoveAbsJ ", "jt_a", ", v100, z1, tool0;")]


def test_moves_made_as_columns_are_read_as_the_full_route_reads_them():
    from rapidfix.postprocess.verify import _read_columns, read_back, read_back_full

    units, expected = _units(_DECLS, _MOVES), _expected(3)
    columns = _read_columns(units, expected, "x.mod")
    assert columns is not None
    _same_read(columns, read_back_full(units, "x.mod", expected))
    assert columns.robax.tolist()[:2] == [[-1.5, 0, 0.25, 10, 20, 30], [1, 2, 3, 4, 5, 6]]
    _same_read(read_back(units, "x.mod", expected), columns)


@pytest.mark.parametrize("declarations, moves, message", [
    ([_DECLS[0].replace("4,5,6]", "4,5]")], _MOVES[2:], "cannot be read back"),
    ([_DECLS[0].replace("4,5", "4.5.5")], _MOVES[2:], "does not parse"),
    (_DECLS, [("MoveAbsJ ", "jt_a", ", v100, z1, tool0")], "does not parse"),
    (_DECLS, [("MoveAbsJ ", "jt_a", " v100, z1, tool0;")], "does not parse"),
    (_DECLS, [("MoveAbsJ ", "jt_a", ", v100, z1, tool0; MoveAbsJ jt_b, v1, z1, tool0;")],
     "motion instructions"),
    (_DECLS, [("MoveAbsJ ", "jt_c", ", v100, z1, tool0;")], "cannot be read back"),
    ([*_DECLS, _DECLS[0].replace("1,2,3", "3,2,1")], _MOVES, "declares jt_a twice"),
])
def test_the_read_back_in_columns_stops_a_broken_statement_declaration_or_name(
        declarations, moves, message):
    from rapidfix.postprocess.verify import read_back

    with pytest.raises((RapidSemanticError, ValueError), match=message):
        read_back(_units(declarations, moves), "x.mod", _expected(len(moves)))


def test_a_jointtarget_that_does_not_hold_the_joints_planned_stops_the_read_back():
    from rapidfix.postprocess.verify import read_back

    planned = [[-1.5, 0, 0.25, 10, 20, 30], [1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 6]]
    read_back(_units(_DECLS, _MOVES), "x.mod", _expected(3, planned))  # as planned
    planned[2][5] = 6.000002
    with pytest.raises(RapidSemanticError, match="other joints than planned"):
        read_back(_units(_DECLS, _MOVES), "x.mod", _expected(3, planned))


def test_a_rewrite_that_writes_a_wrong_digit_or_one_name_twice_writes_nothing(
        monkeypatch, comp, tmp_path):
    from rapidfix.postprocess.naming import NameAllocator

    source = tmp_path / "cam.mod"
    source.write_text(cam_program(40))
    real = emission_module.jointtarget_literals

    def one_digit_off(q_deg, extax):
        texts = real(q_deg, extax)
        return [texts[0].replace("[[", "[[1", 1), *texts[1:]]

    monkeypatch.setattr(emission_module, "jointtarget_literals", one_digit_off)
    out = tmp_path / "out.mod"
    with pytest.raises(RapidSemanticError, match="other joints than planned"):
        rewrite_file(source, out, comp, RewriteOptions())
    assert not out.exists()
    monkeypatch.undo()
    allocate_many = NameAllocator.allocate_many
    monkeypatch.setattr(NameAllocator, "allocate_many",
                        lambda self, stems, prefix="jt_": [allocate_many(self, stems, prefix)[0]]
                        * len(stems))
    with pytest.raises(RapidSemanticError, match="twice"):
        rewrite_file(source, out, comp, RewriteOptions())
    assert not out.exists()


def test_statement_templates_that_differ_in_their_digits_are_read_once():
    from rapidfix.rapid import one_per_shape

    templates = [("    MoveAbsJ \\ID:=11, ", ", v100, z1, tool0;"),
                 ("    MoveAbsJ \\ID:=12, ", ", v100, z1, tool0;"),
                 ("    MoveAbsJ \\ID:=13, ", ", v200, z1, tool0;"),  # the same shape
                 ("    MoveAbsJ \\ID:=140, ", ", v100, z1, tool0;"),
                 ("    MoveL1 \\ID:=11, ", ", v100, z1, tool0;"),  # another call's name
                 ("    MoveL2 \\ID:=11, ", ", v100, z1, tool0;"),
                 ("    MoveAbsJ \\ID:=11, ", ", v100, z1, tool0; ! 1"),  # a comment
                 ("    MoveAbsJ \\ID:=11, ", ", v100, z1, tool0; ! 2"),
                 ('    Foo "1", ', ";"), ('    Foo "2", ', ";"),  # strings
                 ("    Foo 0x1, ", ";"), ("    Foo 0x2, ", ";")]  # radix prefixes
    assert list(one_per_shape(templates)) == [templates[n] for n in (0, 3, 4, 5, 6, 7, 8, 9,
                                                                       10, 11)]


def test_a_multimove_program_is_read_back_in_columns_once_per_statement_shape(
        monkeypatch, comp):
    # every move numbered (`\\ID:=10`, `\\ID:=20`, ...): its statements are read back
    # through a few templates, not one each
    parsed = _bulk_texts(monkeypatch)
    text = odd_program("multimove", 900)
    result = rewrite_source(text.encode(), "coordinated.mod", comp, RewriteOptions())
    assert result.moves_compensated == result.moves_total > 200
    assert parsed and sum(text.count("MoveAbsJ") for text in parsed) < 30
    assert result.worst_predicted_mm is not None and result.worst_predicted_mm < 1e-3


def _bulk_texts(monkeypatch) -> list[str]:
    """The texts the read-back gives its bulk reader, as it gives them."""
    parsed: list[str] = []
    real = verify_module.read_targets_in_bulk

    def spy(text, *args):
        parsed.append(text)
        return real(text, *args)

    monkeypatch.setattr(verify_module, "read_targets_in_bulk", spy)
    return parsed


def test_a_cam_program_is_read_back_in_columns_without_parsing_its_jointtargets(
        monkeypatch, comp):
    parsed = _bulk_texts(monkeypatch)
    result = rewrite_source(cam_program(300).encode(), "cam.mod", comp, RewriteOptions())
    assert result.moves_compensated == 300
    assert parsed and not any("CONST jointtarget jt_" in text for text in parsed)
    assert sum(text.count("MoveAbsJ") for text in parsed) < 30  # the distinct texts only


def test_statements_added_one_by_one_or_in_runs_give_the_same_check_program():
    """The check units keep statements as runs of consecutive ids: added one by one, in
    runs, interleaved across scopes, the check program and each scope's ids are those
    of the plain list of (scope, id, text) written out scope by scope."""
    import itertools

    from rapidfix.postprocess.reparse_changes import CheckUnits

    plan = [("A", "p", "MoveAbsJ a0, v1, z1, tool0;"), ("A", "p", "MoveAbsJ a1, v1, z1, tool0;"),
            ("A", "q", "MoveAbsJ b0, v1, z1, tool0;"), ("A", "p", "MoveAbsJ a2, v1, z1, tool0;"),
            ("B", "r", "MoveAbsJ c0, v1, z1, tool0;"), ("A", "p", "MoveAbsJ a3, v1, z1, tool0;"),
            ("A", "p", "MoveAbsJ a4, v1, z1, tool0;"), ("A", "q", "MoveAbsJ b1, v1, z1, tool0;")]
    # the independent truth: every statement under its scope, scopes in first-use order
    scopes: dict[tuple[str, str], list[int]] = {}
    for ident, (module, routine, _) in enumerate(plan):
        scopes.setdefault((module, routine), []).append(ident)
    lines, order = [], []
    for module in dict.fromkeys(m for m, _, _ in plan):
        lines.append(f"MODULE {module}")
        for (m, routine), idents in scopes.items():
            if m == module:
                lines += [f"PROC {routine}()", *(plan[i][2] for i in idents), "ENDPROC"]
                order += idents
        lines.append("ENDMODULE")
    want = ("\n".join(lines) + "\n", order)

    for cuts in ([], [1, 2, 3, 4, 5, 6, 7], [3, 5], [2, 6], [4]):  # where runs start
        units = CheckUnits()
        bounds = [0, *cuts, len(plan)]
        for a, b in itertools.pairwise(bounds):
            if b - a == 1 and a % 2:
                assert units.add_statement(*plan[a]) == a
            else:
                part = plan[a:b]
                assert units.add_statements([m for m, _, _ in part], [r for _, r, _ in part],
                                            [t for _, _, t in part]) == range(a, b)
        assert units.text() == want
        assert units.statement_scopes() == list(scopes.items())
        _, motions = units.parse("x.mod")
        assert [m.target.name for m in motions] == [t.split()[1][:-1] for _, _, t in plan]


# ------------------------------------------------- kept instructions, robtargets as columns
_LIT = ("[[100,200,300],[1,0,0,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]",
        "[[-1.5,2.25,.5],[0.5,0.5,0.5,0.5],[-1,0,-1,4],[0,0,0,0,0,0]]",
        "[[7,8,9],[0,1,0,0],[1,1,1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
_ROB_DECLS = {("M", None): [f"CONST robtarget p1:={_LIT[0]};",
                            f"LOCAL PERS RobTarget  P2 := {_LIT[1]} ;"],
              ("M", "p"): [f"VAR robtarget p1:={_LIT[2]};"]}  # p1 of routine p
_KEPT = [("ArcL ", "p1", ",v100,seam1,weld1\\Weave:=weave1,z1,tWeld;"),  # routine p: p's p1
         ("MoveL ", _LIT[1], ", v100, fine, tool0 \\WObj:=w;"),          # inline
         ("MoveC ", "p2", ",", "P1", ",v100,z1,tool0;"),                # CirPoint, ToPoint
         ("SearchL\\Stop, sensor, pFound, ", "p2", ", v100, tool0;")]  # target not first


def _kept_units(declarations, statements, routine="p"):
    from rapidfix.postprocess.reparse_changes import CheckUnits

    units = CheckUnits()
    for (module, scope), texts in declarations.items():
        units.add_robtarget_declarations(module, scope, texts)
    units.add_statements(["M"] * len(statements), [routine] * len(statements),
                         ["".join(slot) for slot in statements], target_slots=statements)
    return units


def _kept_expected(statements):
    from rapidfix.postprocess.placement import Placement
    from rapidfix.postprocess.verify import Expected

    motion = [n for n, slot in enumerate(statements) for _ in slot[1::2]]
    slot = [j for texts in statements for j in range(len(texts[1::2]))]
    eye = np.repeat(np.eye(4)[None], len(motion), 0)
    return Expected(np.array(motion), np.array(slot), np.zeros((len(motion), 3)),
                    Placement(eye, eye, eye), None, None)


def test_kept_instructions_are_read_as_columns_as_the_full_route_reads_them():
    from rapidfix.postprocess.verify import _read_columns, read_back

    units, expected = _kept_units(_ROB_DECLS, _KEPT), _kept_expected(_KEPT)
    columns = _read_columns(units, expected, "x.mod")
    assert columns is not None and not columns.joint.any()
    _same_read(columns, read_back_full(units, "x.mod", expected))  # the independent route
    # p1 in routine p is the routine's own; P1 and p1 are one name; the MoveC reads its
    # circle point and then its destination
    assert columns.trans.tolist() == [[7, 8, 9], [-1.5, 2.25, 0.5], [-1.5, 2.25, 0.5],
                                      [7, 8, 9], [-1.5, 2.25, 0.5]]
    assert columns.conf.tolist()[1] == [-1, 0, -1, 4]
    _same_read(read_back(units, "x.mod", expected), columns)


@pytest.mark.parametrize("declarations, statements", [
    # written otherwise: the parser decides, and reads the same
    ({("M", None): [f"CONST robtarget p1:={_LIT[0]}; ! taught"]}, _KEPT[:1]),
    ({("M", None): [f"CONST robtarget p1:={_LIT[0].replace(',', ', ')};"]}, _KEPT[:1]),
    ({("M", None): [f"CONST robtarget p1:=\n  {_LIT[0]};"]}, _KEPT[:1]),
    ({("M", None): [f"CONST robtarget p1:={_LIT[0]};"]},
     [("MoveL ", _LIT[1].replace(",", ", "), ", v100, z1, tool0;")]),
    # a keyword as a name: the grammar decides
    ({("M", None): [f"CONST robtarget if:={_LIT[0]};"]},
     [("ArcL ", "if", ",v100,seam1,weld1,z1,tWeld;")]),
])
def test_robtargets_written_otherwise_are_read_as_the_full_route_reads_them(
        declarations, statements):
    from rapidfix.postprocess.verify import read_back

    units, expected = _kept_units(declarations, statements), _kept_expected(statements)
    _same_read(read_back(units, "x.mod", expected),
               read_back_full(units, "x.mod", expected))


def test_a_name_declared_otherwise_in_the_routine_is_not_read_from_the_module():
    from rapidfix.postprocess.verify import _read_columns, read_back

    units = _kept_units({("M", None): [f"CONST robtarget p1:={_LIT[0]};"]}, _KEPT[:1])
    units.add_declaration("M", "p", f"PERS robtarget p1:={_LIT[2]}; ! the routine's own")
    expected = _kept_expected(_KEPT[:1])
    assert _read_columns(units, expected, "x.mod") is None
    assert read_back(units, "x.mod", expected).trans.tolist() == [[7, 8, 9]]


@pytest.mark.parametrize("declarations, statements, message", [
    ({("M", None): [f"CONST robtarget p1:={_LIT[0]};"]},
     [("ArcL ", "p9", ",v100,seam1,weld1,z1,tWeld;")], "cannot be read back"),
    ({("M", None): [f"CONST robtarget p1:={_LIT[0][:-1]};"]}, _KEPT[:1], "does not parse"),
    ({("M", None): [f"CONST robtarget p1:={_LIT[0].replace('100', '1.0.0')};"]}, _KEPT[:1],
     "does not parse"),
    ({("M", None): [f"CONST robtarget p1:={_LIT[0]};"]},
     [("ArcL ", "p1", ",v100,seam1,weld1,z1,tWeld")], "does not parse"),
    ({("M", None): [f"CONST robtarget p1:={_LIT[0]};"]},
     [("ArcL ", "p1", ",v100,seam1,weld1,z1,tWeld; MoveL p1,v1,z1,tool0;")],
     "motion instructions"),
    ({}, [("MoveL ", _LIT[0].replace("[[", "[[[", 1), ",v1,z1,tool0;")], "does not parse"),
])
def test_the_read_back_of_kept_instructions_stops_a_broken_statement_declaration_or_name(
        declarations, statements, message):
    from rapidfix.postprocess.verify import read_back

    with pytest.raises((RapidSemanticError, ValueError), match=message):
        read_back(_kept_units(declarations, statements), "x.mod", _kept_expected(statements))


@pytest.mark.parametrize("shape, emit", [("arc_weld", "jointtargets"), ("feeds", "robtargets"),
                                         ("named", "robtargets"), ("movec", "robtargets"),
                                         ("scoped", "robtargets")])
def test_kept_instructions_of_a_program_are_read_back_as_columns(monkeypatch, comp, shape,
                                                                 emit):
    """The arc-welding cell (its weld moves keep their instructions), and programs
    rewritten with filtered robtargets: their targets are read as columns (no statement
    nor declaration parsed but one per distinct text around the targets), the values
    those of the full route."""
    from odd_shapes import ODD_SHAPES, odd_moves
    from program_shapes import shape_moves

    parsed: list[tuple[str, int]] = []  # (text, how many statements) of each parse
    real = verify_module.read_targets_in_bulk

    def spy(text, order, *args):
        parsed.append((text, len(order)))
        return real(text, order, *args)

    monkeypatch.setattr(verify_module, "read_targets_in_bulk", spy)
    monkeypatch.setattr(verify_module, "read_back_full", None)  # never the full route
    data = (odd_moves if shape in ODD_SHAPES else shape_moves)(shape, 120).encode()
    result, captured = _rewrite_capturing_units(monkeypatch, data, "t.mod", comp,
                                                RewriteOptions(emit=emit))
    assert result.moves_compensated >= 60  # (movec: 120 moves are 80 instructions)
    units = captured["units"]
    slots = [slot for slot in units.target_slots() if slot is not None]
    assert len(slots) >= 60
    declared = [t for texts in units.robtarget_declarations().values() for t in texts]
    assert declared or shape == "feeds"  # feeds: its targets are inline
    assert not any(decl in text for text, _ in parsed for decl in declared)
    templates = len({slot[0::2] for slot in slots})
    moves = {(slot[0], slot[2]) for slot in units.joint_slots() if slot is not None}
    assert sum(count for _, count in parsed) <= templates + len(moves)  # distinct texts only
    assert templates < len(slots) or shape == "feeds"  # feeds: a speed of its own a move
    _same_read(captured["read"], read_back_full(units, "t.mod", captured["expected"]))


_NUMBER = st.one_of(st.integers(-2000, 2000).map(str),
                    st.floats(-2000, 2000, allow_nan=False).map(lambda v: f"{v:.4f}"),
                    st.sampled_from(["0", "-0", ".5", "1.", "1E+3", "9E+09", "1e-2", "+2"]))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(
    st.sampled_from(["CONST", "PERS", "VAR", "LOCAL CONST", "TASK PERS", "local task pers"]),
    st.sampled_from(["robtarget", "RobTarget"]),
    st.sampled_from([":=", " := ", ":=  "]),
    st.lists(_NUMBER, min_size=17, max_size=17),
    st.sampled_from(["", ", ", "!"]),    # how the literal is written: compact, spaced, noted
    st.booleans()),                        # the statement names it, or holds it inline
    min_size=1, max_size=6))
def test_kept_instructions_read_back_as_the_full_route_reads_them(rows):
    """Declarations and statements of kept instructions in the forms a rewrite may leave
    (the words before a replaced value as a program wrote them), with numbers as RAPID
    writes them: the read-back (in columns where it takes them) reads what the full
    parse of the same text reads, or both refuse it."""
    from rapidfix.postprocess.verify import read_back

    declarations, statements = [], []
    for n, (storage, type_name, assign, numbers, style, inline) in enumerate(rows):
        groups = (numbers[:3], numbers[3:7], numbers[7:11], numbers[11:])
        literal = "[" + ",".join("[" + ",".join(g) + "]" for g in groups) + "]"
        if style == ", ":
            literal = literal.replace(",", ", ")
        note = " ! taught" if style == "!" else ""
        if inline:
            statements.append(("MoveL ", literal, ",v100,z1,tool0;"))
        else:
            declarations.append(f"{storage} {type_name} p{n}{assign}{literal};{note}")
            statements.append(("MoveL ", f"p{n}", ",v100,z1,tool0;"))
    units = _kept_units({("M", None): declarations}, statements)
    expected = _kept_expected(statements)
    try:
        full = read_back_full(units, "x.mod", expected)
    except (RapidSemanticError, ValueError) as err:
        with pytest.raises(type(err)):
            read_back(units, "x.mod", expected)
        return
    _same_read(read_back(units, "x.mod", expected), full)


def test_robtargets_not_read_as_columns_leave_the_jointtargets_to_the_columns():
    """A replaced declaration written over two lines is parsed with everything the columns
    do not take; the MoveAbsJ statements beside it are still read as columns."""
    from rapidfix.postprocess.verify import _read_columns

    units = _units(_DECLS, _MOVES)
    units.add_robtarget_declarations("M", None, [f"CONST robtarget p1:=\n  {_LIT[0]};"])
    units.add_statements(["M"], ["p"], ["".join(_KEPT[0])], target_slots=[_KEPT[0]])
    expected = _expected(4)
    columns = _read_columns(units, expected, "x.mod")
    assert columns is not None
    _same_read(columns, read_back_full(units, "x.mod", expected))
    assert columns.joint.tolist() == [True, True, True, False]
    assert columns.trans[3].tolist() == [100, 200, 300]
