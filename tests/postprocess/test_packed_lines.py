"""A program with its statements packed onto fewer lines rewrites to the same program.

RAPID does not care where a line ends, and neither may the rewrite: new declarations
go after their anchor, not after whatever else shares its line (a routine's statements,
the ENDMODULE), and the header's line comments never swallow code that followed the
MODULE line. The same program, one statement a line and packed, must give outputs
with the same statements (whitespace aside) that parse to the same moves and data.
"""

from __future__ import annotations

import re

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import parse_program

EXTAX = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"


def _target(x: float, y: float, z: float) -> str:
    return f"[[{x:g},{y:g},{z:g}],[0,0.258819045,0.965925826,0],[0,0,-1,1],{EXTAX}]"


LINES = [
    "MODULE Packed",
    "  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];",
    "  PERS wobjdata wPlate:=[FALSE,TRUE,\"\",[[850,80,450],"
    "[0.923879533,0,-0.382683432,0]],[[0,0,0],[1,0,0,0]]];",
    f"  CONST robtarget p1:={_target(100, 50, 0)};",
    "  ! the part's corners",
    f"  CONST robtarget p2:={_target(160, 50, 0)};",
    f"  CONST robtarget p3:={_target(160, 110, 0)};",
    "  PROC main()",
    f"    CONST robtarget pLoc:={_target(120, 80, 10)};",
    "    MoveJ p1, v500, fine, tBar\\WObj:=wPlate;",
    "    MoveL p2, v100, z1, tBar\\WObj:=wPlate; ! along the edge",
    "    MoveC Offs(p2,5,30,0), p3, v100, z1, tBar\\WObj:=wPlate;",
    "    MoveL pLoc, v100, fine, tBar\\WObj:=wPlate;",
    "    side;",
    "  ENDPROC",
    "  PROC side()",
    f"    MoveL {_target(130, 60, 30)}, v100, z1, tBar\\WObj:=wPlate;",
    "    MoveJ Offs(p1,0,0,20), v500, fine, tBar\\WObj:=wPlate;",
    "  ENDPROC",
    "ENDMODULE",
]
#: a line may be joined to the next one where it holds no comment
JOINABLE = [k for k, line in enumerate(LINES[:-1]) if "!" not in line]
_COMMENT = re.compile(r"![^\r\n]*")  # (no string of the program holds a '!')
OPTIONS = {
    "jointtargets": RewriteOptions(path_tolerance_mm=0.01),
    "robtargets": RewriteOptions(emit="robtargets"),
    "approach": RewriteOptions(approach=True),
}


def _packed(joins: set[int]) -> str:
    return "".join(line + (" " if k in joins else "\n") for k, line in enumerate(LINES))


def _statements(data: bytes) -> str:
    """The output without its comments (the header's among them; a comment joined to
    the line before keeps new lines after it), every run of blanks one space."""
    return " ".join(_COMMENT.sub("", data.decode()).split())


def _shape(data: bytes) -> tuple:
    """What the whole output parses to: its moves and declarations as written."""
    program = parse_program(data, "out.mod")

    def written(span) -> str:
        return " ".join(program.text[span.start:span.end].split())

    return ([written(m.span) for m in program.motions],
            sorted((d.name, written(d.span)) for d in program.declarations))


def _reference(comp, mode):
    return rewrite_source(_packed(set()).encode(), "packed.mod", comp, OPTIONS[mode])


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(joins=st.sets(st.sampled_from(JOINABLE)), mode=st.sampled_from(sorted(OPTIONS)))
def test_packed_lines_rewrite_to_the_same_program(comp, joins, mode):
    plain = _reference(comp, mode)
    assert plain.moves_compensated == 6 and not plain.skipped
    packed = rewrite_source(_packed(joins).encode(), "packed.mod", comp, OPTIONS[mode])
    assert packed.moves_compensated == plain.moves_compensated
    assert packed.skipped == [] and packed.warnings == plain.warnings
    assert _statements(packed.data) == _statements(plain.data)
    # the whole output parses, and no code went into a comment or after ENDMODULE
    assert _shape(packed.data) == _shape(plain.data)


def test_everything_on_one_line(comp):
    """The extreme: MODULE to ENDMODULE on one line (comments left out)."""
    text = " ".join(line.split("!")[0].strip() for line in LINES if line.strip()[0] != "!")
    plain = rewrite_source("\n".join(LINES).encode(), "packed.mod", comp, OPTIONS["jointtargets"])
    packed = rewrite_source(text.encode(), "packed.mod", comp, OPTIONS["jointtargets"])
    out = packed.data.decode()
    assert out.rstrip().endswith("ENDMODULE")
    assert all(not line.lstrip().startswith("!") or ("rapidfix-compensated" in line
               and "MoveL" not in line and "CONST" not in line) for line in out.splitlines())
    assert _shape(packed.data)[1] == _shape(plain.data)[1]
    assert len(parse_program(packed.data, "out.mod").motions) == len(
        parse_program(plain.data, "out.mod").motions)


_FAR = "[[600,100,500],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
SMALL = {
    # the first item on the MODULE line: new declarations are not indented by "MODULE M "
    "no declarations, one line, no final newline":
        f"MODULE M PROC main() MoveJ {_FAR}, v100, fine, tool0; ENDPROC ENDMODULE",
    "a comment on the MODULE line":
        f"MODULE M(SYSMODULE) ! cell data\n  CONST robtarget p1:={_FAR};\n  PROC main()\n"
        "    MoveJ p1, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
    "the routine on the line of the last declaration":
        f"MODULE M\n  CONST robtarget p1:={_FAR}; PROC main()\n"
        "    MoveJ p1, v100, fine, tool0; MoveL Offs(p1,0,0,30), v100, fine, tool0;\n"
        "  ENDPROC ENDMODULE\n",
}


def test_small_layouts_keep_their_code_and_comments(comp):
    from rapidfix.postprocess.header import read_header

    for name, text in SMALL.items():
        source = parse_program(text.encode(), "m.mod")
        for mode, options in OPTIONS.items():
            result = rewrite_source(text.encode(), "m.mod", comp, options)
            assert result.moves_compensated == len(source.motions), (name, mode)
            out = parse_program(result.data, "out.mod")  # the whole output parses
            # new lines after a mid-line anchor stand together: no empty line among them
            assert out.text.count("\n\n") == text.count("\n\n"), (name, mode)
            # and the header comes first, right after the MODULE line
            assert "rapidfix-compensated" in out.text.splitlines()[1], (name, mode)
            assert len(out.motions) >= len(source.motions), (name, mode)
            header = read_header(out.text)
            assert header is not None and header.summary.endswith("left as they were")
            if "!" in text:
                assert any(line.strip() == "! cell data" for line in out.text.splitlines())
