"""A syntax error is explained from its error window (rapidfix.rapid.error_window): the
module items before the one holding it blanked, and the completed statements of the
routine it is in but the last, so the plain grammar need not read a large file again.
The message, line and column must be exactly those the plain grammar gives on the whole
text: checked on the samples and benchmark shapes with errors put in at random places,
with windows made however small (the size threshold set to 0)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from odd_shapes import odd_moves
from program_shapes import shape_moves

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import error_window, fastpath, parse_program, syntax_errors
from rapidfix.rapid.source import decode_source

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
TEXTS = [
    *(decode_source(p.read_bytes(), p.name).text for p in sorted(SAMPLES.iterdir())
      if p.suffix in (".mod", ".prg")),
    shape_moves("prg", 40), shape_moves("control", 30), shape_moves("crlf_tabs", 30),
    odd_moves("modules", 50), odd_moves("many_procs", 20), odd_moves("frames", 20),
    # module data after the routines, LOCAL/TASK items, a module with attributes
    "MODULE A(SYSMODULE, NOSTEPIN)\n  LOCAL PROC r()\n    a:=1;\n  ENDPROC\n"
    "  TASK PERS num n:=1;\n  LOCAL VAR num m{2}:=[1,\n    2];\n  FUNC num f()\n"
    "    RETURN 1;\n  ENDFUNC\n  CONST num k:=2;\n  TRAP t\n    Stop;\n  ENDTRAP\n"
    "  VAR num z:=3;\nENDMODULE\n",
]
INSERTS = ["x", ";", "(", ")", "]", "[", ",", '"', "ENDPROC", "PROC p()", "MoveL", "VAR",
           "CONST num", "MODULE", "ENDMODULE", "%%%", "1_a", "\\", ":=", "IF", "\n", "<DDN>",
           "x := a, b;", "n := n + 1;", "p.trans.x := ", ".", "{", "1-"]


def _outcome(text: str) -> str:
    try:
        program = parse_program(text, "t.mod")
    except RapidSyntaxError as err:
        return str(err)
    return f"ok {len(program.motions)} {len(program.declarations)}"


def _windowed_and_whole(text: str, monkeypatch) -> tuple[list[str], str, str]:
    """(the texts the plain grammar was given, the error message, the message with no
    window) of a program with a syntax error."""
    seen: list[str] = []
    plain = fastpath.rapid_parser()

    class Spy:
        def parse(self, given: str):
            seen.append(given)
            return plain.parse(given)

    with monkeypatch.context() as m:
        m.setattr(fastpath, "rapid_parser", lambda: Spy())
        with pytest.raises(RapidSyntaxError) as windowed:
            parse_program(text, "t.mod")
    with monkeypatch.context() as m:
        m.setattr(fastpath, "window", lambda *_: None)
        m.setattr(syntax_errors, "window", lambda *_: None)
        with pytest.raises(RapidSyntaxError) as whole:
            parse_program(text, "t.mod")
    return seen, str(windowed.value), str(whole.value)


@pytest.fixture
def any_window(monkeypatch):
    monkeypatch.setattr(error_window, "_WORTH", 0)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, len(TEXTS) - 1), where=st.floats(0, 1), cut=st.integers(0, 3),
       insert=st.sampled_from(INSERTS))
def test_the_error_window_says_what_the_whole_text_says(any_window, monkeypatch, which, where,
                                                        cut, insert):
    base = TEXTS[which]
    at = int(where * len(base))
    text = base[:at] + insert + base[at + cut:]
    windowed = _outcome(text)
    with monkeypatch.context() as m:
        m.setattr(fastpath, "window", lambda *_: None)
        m.setattr(syntax_errors, "window", lambda *_: None)
        whole = _outcome(text)
    assert windowed == whole


@pytest.mark.parametrize("local", [False, True])
def test_a_late_error_in_a_large_file_is_explained_from_its_routine(monkeypatch, local):
    """The plain grammar reads only the window: the items before the error's routine
    are blank in what it is given, and the message is the whole text's (the routines'
    heads one fast token each, `LOCAL PROC Path_1()` too)."""
    text = shape_moves("named", 1500)  # three routines
    if local:
        text = text.replace("PROC Path_", "LOCAL PROC Path_")
    at = text.rindex("MoveL")
    text = text[:at] + "MoveL p1 v100, z1, tMill;\n    " + text[at:]
    seen, windowed, whole = _windowed_and_whole(text, monkeypatch)
    assert len(seen) == 1 and len(seen[0]) == len(text)
    kept = seen[0].replace(" ", "").replace("\n", "")
    assert len(kept) < len(text.replace(" ", "").replace("\n", "")) / 4
    assert "CONST robtarget" not in seen[0]  # the data section is blank
    line = text[:text.index("MoveL p1 v100")].count("\n") + 1
    assert f":{line}:" in windowed
    assert windowed == whole


def test_no_window_when_little_would_be_left_out():
    from lark.exceptions import UnexpectedInput

    text = "MODULE M\n  PROC main()\n    Stop;\n    MoveL p1 v100;\n  ENDPROC\nENDMODULE\n"
    with pytest.raises(UnexpectedInput) as err:
        fastpath.rapid_parser().parse(text)
    assert error_window.window(text, err.value) is None


@pytest.mark.parametrize(("value", "message"), [
    ("[1,\n  VAR  2]", "t.mod:7:8: unexpected '2'; expected one of an operator"),
    ("[1,\n  VAR, 2 3]", "t.mod:7:10: unexpected '3'; expected one of an operator"),
    ("[1,\n  VAR];\n  VAR num k:= ;", "t.mod:8:15: unexpected ';'; expected one of "),
])
def test_a_keyword_inside_a_value_is_no_cut(any_window, monkeypatch, value, message):
    """Found by the property test: `VAR` at the start of a line inside a declaration's
    aggregate is read as a name; the line is no module item, and the declaration it is
    in must not be blanked (the plain grammar expects an operator there, not a name)."""
    text = ("MODULE A\n  PROC r()\n    a:=1;\n  ENDPROC\n  TASK PERS num n:=1;\n"
            f"  LOCAL VAR num m{{2}}:={value}\nENDMODULE\n")
    windowed = _outcome(text)
    with monkeypatch.context() as m:
        m.setattr(fastpath, "window", lambda *_: None)
        m.setattr(syntax_errors, "window", lambda *_: None)
        assert windowed == _outcome(text)
    assert windowed.startswith(message)


def test_an_error_after_complete_declarations_is_explained_from_the_last(monkeypatch):
    """A stray statement among a CAM program's declarations: the declarations before
    the last complete one are blank in what the plain grammar is given."""
    text = shape_moves("named", 3000)
    at = text.index("  CONST robtarget p2000")
    text = text[:at] + "  x := 1;\n" + text[at:]
    seen, windowed, whole = _windowed_and_whole(text, monkeypatch)
    assert len(seen) == 1 and seen[0].count("CONST robtarget") == 1001  # p1999 .. p2999
    assert windowed == whole


@pytest.mark.parametrize("inside", [
    "  RECORD partinfo\n    string name;\n   PROC p() bool Stop;\n  ENDRECORD\n",  # a field's type
    "  PROC main()\n    Stop;\n    PROC p(1 x;\n  ENDPROC\n",  # a call's name
    "  PROC main()\n    VAR num n:=1;\n    Stop;\n    VAR num m:= ;\n  ENDPROC\n",
])
def test_a_keyword_the_lexer_read_as_a_name_is_no_cut(any_window, monkeypatch, inside):
    """Found by the property test: where the keyword cannot stand (a record's field
    type, a call's name), the contextual lexer reads `PROC` or `VAR` as a name; the line
    is then no module item and the text before it must not be blanked."""
    head = "MODULE M\n  CONST num k:=1;\n  PROC a()\n    Stop;\n  ENDPROC\n"
    text = head + inside + "ENDMODULE\n"
    windowed = _outcome(text)
    with monkeypatch.context() as m:
        m.setattr(fastpath, "window", lambda *_: None)
        m.setattr(syntax_errors, "window", lambda *_: None)
        assert windowed == _outcome(text)
    assert windowed.startswith("t.mod:")


@pytest.mark.parametrize("damage", ["truncated", "in_if"])
def test_an_error_late_in_a_long_routine_is_explained_from_its_last_statements(
        monkeypatch, damage):
    """A CAM program cut off in its one routine (no ENDPROC, no ENDMODULE), or with an
    error inside an IF late in it: the plain grammar is given the routine with its
    completed statements blank but the last, and says what it says on the whole text."""
    import re

    # one routine of 2,000 moves: the parts of the named shape run together
    text = re.sub(r"\n  ENDPROC\n  PROC Path_\d+\(\)", "", shape_moves("named", 2000))
    text = text[:text.index("  PROC main()")] + "ENDMODULE\n"
    at = text.rindex("MoveL")
    if damage == "truncated":
        text = text[:at]
    else:
        text = (text[:at] + "IF nCount > 2 THEN\n      Stop;\n      MoveL p1 v100;\n    ENDIF\n    "
                + text[at:])
    seen, windowed, whole = _windowed_and_whole(text, monkeypatch)
    assert len(seen) == 1 and len(seen[0]) == len(text)
    # the routine's statements blank but those of the last run the fast parser had taken
    # (at most RUN_LIMIT) and the one before it; everything before the routine blank
    routine = text.index("PROC ")
    assert seen[0][:routine].split() == ["MODULE", "Named"]
    assert text.count("MoveL", routine) > 2 * fastpath.RUN_LIMIT
    assert seen[0].count("MoveL") <= fastpath.RUN_LIMIT + 2
    assert windowed == whole
    assert ("unexpected end of file" in whole) == (damage == "truncated")


def test_the_body_of_a_routine_in_progress_is_read_from_the_parser():
    """body_span: the first and last of the items a parser completed in the routine it
    was reading (declarations and statements, an IF whole); None outside a routine."""
    from lark.exceptions import UnexpectedInput

    text = ("MODULE M\n  VAR num a:=1;\n  PROC main()\n    VAR num k;\n    IF a THEN\n"
            "      b;\n    ENDIF\n    c := 1;\n    FOR i FROM 1 TO 3 DO\n      x;\n")
    for parser in (fastpath.fast_parser(), fastpath.rapid_parser()):
        with pytest.raises(UnexpectedInput) as err:
            parser.parse(text)
        assert error_window.body_span(err.value) == (text.index("VAR num k"),
                                                      text.index("c := 1"))
        with pytest.raises(UnexpectedInput) as err:
            parser.parse("MODULE M\n  VAR num a:=1;\n  VAR num b:= ;\nENDMODULE\n")
        assert error_window.body_span(err.value) is None
