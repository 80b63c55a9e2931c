"""A fresh process reads its first WARM_UP_CHARS characters with the plain grammar
(rapidfix.rapid.parse): a command on one small file does not pay for building the fast
parser. The route must not change what comes out: trees, models and syntax errors are
compared with the fast route's.
"""

from __future__ import annotations

import sys
from collections import namedtuple
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the comparisons of the fast path tests
from test_fastpath import shape
from test_shared_operands import TARGET, TOOL, WOBJ, model

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse
from rapidfix.rapid.fastpath import parse_text
from rapidfix.rapid.grammar import rapid_parser
from rapidfix.rapid.model_builder import build_program

SMALL = "\n".join([
    "MODULE M", f"  PERS tooldata tMill:={TOOL};", f"  PERS wobjdata wPlate:={WOBJ};",
    f"  CONST robtarget p1:={TARGET};", "  PROC main()",
    "    MoveL p1,v100,z1,tMill\\WObj:=wPlate;",
    "    IF n > 1 THEN", "      MoveL Offs(p1,0,0,n),v100,z1,tMill\\WObj:=wPlate;", "    ENDIF",
    "  ENDPROC", "ENDMODULE", ""])

_Info = namedtuple("_Info", "currsize")


class _Built:
    """Stands for fastpath.fast_parser: only whether it has been built is asked."""

    def __init__(self, built: bool) -> None:
        self.built = built

    def cache_info(self) -> _Info:
        return _Info(1 if self.built else 0)


@pytest.fixture
def routes(monkeypatch):
    """A fresh process's state (nothing read yet, the fast parser not built), and the
    texts each route was given."""
    seen: dict[str, list[str]] = {"plain": [], "fast": []}

    class Plain:
        def parse(self, text):
            seen["plain"].append(text)
            return rapid_parser().parse(text)

    def fast(text):
        seen["fast"].append(text)
        return parse_text(text)

    monkeypatch.setattr(parse, "WARM_UP_CHARS", 20_000)
    monkeypatch.setattr(parse, "_read_plain", 0)
    monkeypatch.setattr(parse, "fast_parser", _Built(False))
    monkeypatch.setattr(parse, "rapid_parser", lambda: Plain())
    monkeypatch.setattr(parse, "parse_text", fast)
    return seen


def test_a_small_file_in_a_fresh_process_is_read_by_the_plain_grammar(routes):
    program = parse.parse_program(SMALL, "small.mod")
    assert routes == {"plain": [SMALL], "fast": []}
    assert shape(program.syntax) == shape(parse_text(SMALL))
    assert model(program) == model(build_program(
        program.source, SMALL.encode(), parse_text(SMALL)))
    assert program.to_bytes() == SMALL.encode()


def test_the_fast_parser_takes_over_once_the_warm_up_is_spent(routes, monkeypatch):
    monkeypatch.setattr(parse, "WARM_UP_CHARS", 2 * len(SMALL) + 10)
    for _ in range(3):
        parse.parse_program(SMALL, "small.mod")
    assert len(routes["plain"]) == 2 and len(routes["fast"]) == 1


def test_a_file_larger_than_the_warm_up_goes_to_the_fast_parser_at_once(routes, monkeypatch):
    monkeypatch.setattr(parse, "WARM_UP_CHARS", len(SMALL) - 1)
    parse.parse_program(SMALL, "small.mod")
    assert routes == {"plain": [], "fast": [SMALL]}


def test_once_the_fast_parser_is_built_every_file_takes_it(routes, monkeypatch):
    monkeypatch.setattr(parse, "fast_parser", _Built(True))
    parse.parse_program(SMALL, "small.mod")
    assert routes == {"plain": [], "fast": [SMALL]}


def test_a_syntax_error_reads_the_same_on_both_routes(routes, monkeypatch):
    broken = SMALL.replace("MoveL p1,v100", "MoveL p1,,v100")
    with pytest.raises(RapidSyntaxError) as plain:
        parse.parse_program(broken, "small.mod")
    assert routes["plain"] and not routes["fast"]
    monkeypatch.setattr(parse, "fast_parser", _Built(True))
    with pytest.raises(RapidSyntaxError) as fast:
        parse.parse_program(broken, "small.mod")
    assert routes["fast"]
    assert str(plain.value) == str(fast.value)
    assert str(plain.value).startswith("small.mod:6:")


def test_a_small_file_in_a_fresh_process_does_not_import_the_fast_path():
    """The fast path's module (its patterns) is imported only when a file takes it."""
    import subprocess

    code = ("import sys\nfrom rapidfix.rapid import parse_program\n"
            f"program = parse_program({SMALL!r}, 'small.mod')\n"
            "print(len(program.motions), 'rapidfix.rapid.fastpath' in sys.modules)\n"
            "parse_program('MODULE L\\n  PROC main()\\n' + '    x:=1;\\n' * 5000\n"
            "              + '  ENDPROC\\nENDMODULE\\n')\n"
            "print('rapidfix.rapid.fastpath' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.split() == ["2", "False", "True"]
