"""What the rewrite keeps: optional arguments, line endings, encodings, other text."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rapidfix.demo.ballbar_program import ballbar_program
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import parse_program

OPTIONAL = [
    (
        "MoveL pBB01, v50\\T:=2, z5\\Z:=3, tBallbar\\WObj:=wobjBallbar;",
        "MoveAbsJ jt_pBB01, v50\\T:=2, z5\\Z:=3, tBallbar\\WObj:=wobjBallbar;",
    ),
    (
        "MoveL \\Conc, pBB01, v50\\V:=60, fine\\Inpos:=inpos20, tBallbar\\WObj:=wobjBallbar;",
        "MoveAbsJ \\Conc, jt_pBB01, v50\\V:=60, fine\\Inpos:=inpos20, tBallbar\\WObj:=wobjBallbar;",
    ),
]


@pytest.mark.parametrize(("line", "expected"), OPTIONAL)
def test_optional_arguments_are_kept(comp, line, expected):
    text = ballbar_program().replace(
        "MoveL pBB01, v50, fine, tBallbar\\WObj:=wobjBallbar;", line, 1
    )
    result = rewrite_source(text.encode(), "opt.mod", comp, RewriteOptions(path_tolerance_mm=0.05))
    out = result.data.decode()
    assert expected in out
    assert not result.skipped
    # intermediate points of this move drop \T, \Z, \Inpos and \Conc (its comma too) and
    # fly by in z0
    points = [statement.strip() for statement in out.splitlines()
              if "jt_pBB01_" in statement and "MoveAbsJ" in statement]
    assert points
    for statement in points:
        assert statement.startswith("MoveAbsJ jt_pBB01_")
        assert "\\T:=" not in statement and "\\Z:=" not in statement
        assert "\\Inpos" not in statement and "\\Conc" not in statement
        assert ", z0, tBallbar" in statement


def test_a_synchronized_move_keeps_its_number_and_takes_no_intermediate_points(comp):
    """`\\ID` numbers a move of a MultiMove program's synchronized mode, whose other tasks
    run moves of the same numbers: a MoveAbsJ keeps the number where the joint path stays
    within the tolerance without points; where it would need some, the move stays a MoveL
    (its robtarget filtered) and says why."""
    from rapidfix.postprocess.refinement import SYNCHRONIZED

    line = "MoveL pBB01\\ID:=idMove, v50, z1, tBallbar\\WObj:=wobjBallbar\\TLoad:=load0;"
    text = ballbar_program().replace(
        "MoveL pBB01, v50, fine, tBallbar\\WObj:=wobjBallbar;", line, 1
    ).replace("    PROC main()", "    VAR identno idMove := 10;\n    PROC main()", 1)
    loose = rewrite_source(text.encode(), "opt.mod", comp, RewriteOptions(path_tolerance_mm=0.5))
    assert ("MoveAbsJ jt_pBB01\\ID:=idMove, v50, z1, tBallbar\\WObj:=wobjBallbar"
            "\\TLoad:=load0;") in loose.data.decode()
    assert "jt_pBB01_" not in loose.data.decode() and not loose.filtered_reasons
    tight = rewrite_source(text.encode(), "opt.mod", comp, RewriteOptions(path_tolerance_mm=0.05))
    out = tight.data.decode()
    assert line in out and "jt_pBB01" not in out and not tight.skipped
    assert tight.filtered_reasons == {SYNCHRONIZED: 1}
    assert tight.moves_total == loose.moves_total
    # the same move unnumbered takes the points
    plain = rewrite_source(text.replace("\\ID:=idMove", "").encode(), "opt.mod", comp,
                           RewriteOptions(path_tolerance_mm=0.05))
    assert "MoveAbsJ jt_pBB01_1," in plain.data.decode() and not plain.filtered_reasons


def test_corr_has_no_joint_form_and_keeps_its_move_with_a_filtered_robtarget(comp):
    """MoveAbsJ takes no \\Corr: the move stays a MoveL with \\Corr, to a filtered robtarget
    (where it lands is tested on the virtual robot in test_end_to_end)."""
    text = ballbar_program().replace(
        "MoveL pBB01, v50, fine, tBallbar\\WObj:=wobjBallbar;",
        "MoveL pBB01, v50, fine, tBallbar\\WObj:=wobjBallbar\\Corr;",
        1,
    )
    result = rewrite_source(text.encode(), "corr.mod", comp, RewriteOptions())
    assert result.skipped == [] and result.moves_compensated == result.moves_total
    assert result.filtered_reasons == {"optional argument \\Corr has no MoveAbsJ form": 1}
    out = result.data.decode()
    assert "MoveL pBB01, v50, fine, tBallbar\\WObj:=wobjBallbar\\Corr;" in out
    declared = re.compile(r"CONST robtarget pBB01:=[^;]*;")
    assert declared.search(out).group() != declared.search(text).group()  # filtered in place
    assert ("  1 move kept its instruction with a filtered robtarget (optional argument \\Corr "
            "has no MoveAbsJ form)") in result.report_lines()


def test_crlf_and_cp1252_are_kept(comp):
    text = ballbar_program().replace("! Ballbar test", "! Kugelstab-Prüfung: Ballbar test", 1)
    data = text.replace("\n", "\r\n").encode("cp1252")
    result = rewrite_source(data, "legacy.mod", comp, RewriteOptions())
    assert result.moves_compensated == 21
    out = result.data
    assert b"Kugelstab-Pr\xfcfung" in out  # still cp1252, not UTF-8
    assert out.count(b"\r\n") == out.count(b"\n")  # every line ends CRLF
    parse_program(out, "legacy_out.mod")


def test_lone_cr_lines_are_kept(comp):
    """A program whose lines end in a lone CR is rewritten as the same program with LF
    is, line for line, and its new lines end in CR too."""
    text = ballbar_program()
    with_lf = rewrite_source(text.encode(), "legacy.mod", comp, RewriteOptions())
    with_cr = rewrite_source(text.replace("\n", "\r").encode(), "legacy.mod", comp,
                             RewriteOptions())
    assert with_cr.moves_compensated == with_lf.moves_compensated == 21
    assert b"\n" not in with_cr.data
    digest = re.compile(rb"input_sha256: [0-9a-f]+")  # of different bytes
    assert (digest.sub(b"", with_cr.data.replace(b"\r", b"\n"))
            == digest.sub(b"", with_lf.data))
    assert [s.where for s in with_cr.skipped] == [s.where for s in with_lf.skipped]


def test_rewrite_is_deterministic_and_inputs_are_bytes_in_bytes_out(comp):
    data = ballbar_program().encode()
    a = rewrite_source(data, "a.mod", comp, RewriteOptions())
    b = rewrite_source(data, "a.mod", comp, RewriteOptions())
    assert a.data == b.data
    # a program with no motion at all gets only the header
    empty = b'MODULE Empty\n  PROC main()\n    TPWrite "hi";\n  ENDPROC\nENDMODULE\n'
    result = rewrite_source(empty, "e.mod", comp, RewriteOptions())
    lines = result.data.decode().splitlines(keepends=True)
    kept = [line for line in lines if "rapidfix-compensated" not in line]
    assert "".join(kept).encode() == empty and result.worst_predicted_mm is None
    assert np.isclose(result.moves_total, 0)


@pytest.mark.parametrize(("before", "after_search_known"), [
    ("TriggL pBB04, v50, gun, fine, tBallbar\\WObj:=wobjBallbar;", True),
    ("SearchL \\Stop, di1, pHit, pBB04, v50, tBallbar\\WObj:=wobjBallbar;", False),
])
def test_a_move_after_a_search_starts_where_the_search_stopped(comp, before, after_search_known):
    """A kept instruction ends on its compensated target, so the MoveL after it becomes
    MoveAbsJ from there; a search may stop short (its signal), so the MoveL after it
    does not know its start and keeps its instruction with a filtered robtarget."""
    text = ballbar_program().replace(
        "MoveL pBB04, v50, fine, tBallbar\\WObj:=wobjBallbar;", before, 1)
    result = rewrite_source(text.encode(), "search.mod", comp, RewriteOptions())
    out = result.data.decode()
    assert result.skipped == []
    assert ("MoveAbsJ jt_pBB05," in out) is after_search_known
    assert ("MoveL pBB05, v50, fine, tBallbar\\WObj:=wobjBallbar;" in out) is not after_search_known
    assert result.filtered_reasons.get("start not known before run time", 0) == (
        0 if after_search_known else 1)


def plain_unknown(comp) -> int:
    """Moves of the ballbar program whose start is not known before run time."""
    from rapidfix.postprocess.refinement import START_UNKNOWN

    plain = rewrite_source(ballbar_program().encode(), "plain.mod", comp, RewriteOptions())
    return plain.filtered_reasons.get(START_UNKNOWN, 0)


def test_moves_under_a_program_displacement_keep_their_instruction(comp):
    """A MoveAbsJ is not displaced by PDispOn/PDispSet: the moves that may run displaced
    keep their instruction with compensated robtargets (the controller displaces them),
    with a warning; the move after one starts where the displacement left the robot, so
    its start is not known; the moves outside stay MoveAbsJ. PDispOn's points are no
    moves."""
    from rapidfix.postprocess.planning import DISPLACED
    from rapidfix.postprocess.refinement import START_UNKNOWN

    moves = re.findall(r"\n(\s*)(MoveL [^;]*;)", ballbar_program())
    first, second, third = (line for _, line in moves[2:5])
    text = ballbar_program().replace(
        first, "PDispOn \\ExeP:=pBB01, pBB01, tBallbar\\WObj:=wobjBallbar;\n" + first, 1)
    text = text.replace(second, second + "\nPDispOff;", 1)
    result = rewrite_source(text.encode(), "disp.mod", comp, RewriteOptions())
    out = result.data.decode()
    assert first in out and second in out  # kept, their robtargets compensated in place
    assert result.filtered_reasons[DISPLACED] == 2
    # the move after them: kept, where the plain program has none but its first
    assert third in out
    assert result.filtered_reasons[START_UNKNOWN] == plain_unknown(comp) + 1
    assert any("2 move(s) may run with a program displacement" in w for w in result.warnings)
    assert not any("PDispOn is not a motion instruction" in w for w in result.warnings)
    assert "MoveAbsJ" in out
    plain = rewrite_source(ballbar_program().encode(), "plain.mod", comp, RewriteOptions())
    assert DISPLACED not in plain.filtered_reasons
    assert all(line not in plain.data.decode() for line in (first, second, third))
