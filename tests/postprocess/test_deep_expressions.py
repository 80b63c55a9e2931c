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
