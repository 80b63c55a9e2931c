"""A move to an expression nested thousands deep: left as written, with a reason and a
label cut short, never a RecursionError."""

from __future__ import annotations

import pytest

from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source


@pytest.mark.parametrize("value", ["-" * 3000 + "1", "(" * 3000 + "0" + ")" * 3000,
                                   "+".join(["0"] * 20000)])
def test_a_move_to_an_expression_nested_thousands_deep_is_left_with_a_reason(value, comp):
    text = ("MODULE M\n  PERS tooldata t:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],"
            "0,0,0]];\n  CONST robtarget p1:=[[600,0,600],[0,0,1,0],[0,0,0,0],"
            "[9E9,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n"
            "    MoveJ p1,v100,fine,t;\n"
            f"    MoveL Offs(p1,{value},0,0),v100,fine,t;\n  ENDPROC\nENDMODULE\n")
    result = rewrite_source(text.encode(), "m.mod", comp, RewriteOptions())
    assert result.moves_compensated == 1 and len(result.skipped) == 1
    skipped = result.skipped[0]
    assert skipped.where == "m.mod:6" and "nested too deeply" in skipped.reason
    assert len(skipped.label) < 220 and skipped.label.endswith(" ...")


def test_a_target_written_over_lines_with_comments_is_quoted_on_one_line(comp):
    """A message quotes a destination (and a circle point) written over several lines with
    comments in it on one line, without the comments."""
    text = ("MODULE M\n  PERS tooldata t:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],"
            "0,0,0]];\n  CONST robtarget p1:=[[9000,0,600],[0,0,1,0],[0,0,0,0],"
            "[9E9,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n"
            "    MoveL Offs(p1, ! far \"away\"\r\n      0,\t0,\n      1),v100,fine,t;\n"
            "    MoveC Offs(p1, ! circle\n 0,1,0), p1,v100,fine,t;\n"
            "  ENDPROC\nENDMODULE\n")
    result = rewrite_source(text.encode(), "m.mod", comp, RewriteOptions())
    labels = [s.label for s in result.skipped]
    assert labels == ["MoveL Offs(p1, 0, 0, 1)", "MoveC p1"]
    assert "CirPoint Offs(p1, 0,1,0): " in result.skipped[1].reason
    assert all("\n" not in str(s) and "!" not in str(s) for s in result.skipped)
