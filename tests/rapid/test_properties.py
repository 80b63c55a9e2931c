"""Property tests: random valid programs parse, evaluate and round-trip; random
corruptions of them raise RapidSyntaxError and nothing else."""

from __future__ import annotations

import codecs

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse_program
from rapidfix.rapid.edit import Editor

SETTINGS = settings(max_examples=120, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

names = st.from_regex(r"[a-z][a-z0-9_]{0,8}", fullmatch=True).map(lambda n: "d_" + n)
STRINGS = ['"a"', '"b""c"', '""', '"x\\41"']
gaps = st.sampled_from([" ", "  ", "\t", "\n  ", " ! note\n  ", "\r\n", "\n\n"])


def cased(word: str) -> st.SearchStrategy[str]:
    return st.sampled_from([word.upper(), word.lower(), word.capitalize()])


@st.composite
def number(draw: st.DrawFn) -> tuple[str, float]:
    """A num literal in one of RAPID's spellings, with its value."""
    kind = draw(st.sampled_from(["int", "dec", "exp", "dot", "hex"]))
    if kind == "hex":
        n = draw(st.integers(0, 4095))
        return f"0x{n:X}", float(n)
    if kind == "int":
        n = draw(st.integers(0, 100000))
        return str(n), float(n)
    if kind == "dot":
        digits = draw(st.integers(1, 999))
        return f".{digits}", float(f".{digits}")
    mantissa = draw(st.decimals(min_value=0, max_value=1000, places=3, allow_nan=False))
    if kind == "dec":
        return str(mantissa), float(mantissa)
    exponent = draw(st.integers(-3, 9))
    text = f"{mantissa}E{exponent:+03d}"
    return text, float(text)


@st.composite
def expression(draw: st.DrawFn, depth: int = 0) -> tuple[str, float]:
    """A constant num expression (text, value) with + - * unary minus and parentheses."""
    if depth > 2 or draw(st.booleans()):
        return draw(number())
    left, lv = draw(expression(depth + 1))
    right, rv = draw(expression(depth + 1))
    op = draw(st.sampled_from(["+", "-", "*", "neg"]))
    if op == "neg":
        return f"-({left})", -lv
    value = {"+": lv + rv, "-": lv - rv, "*": lv * rv}[op]
    # the left operand keeps RAPID's left associativity without parentheses
    # when it is a sum and the operator is + or -; everything else is wrapped
    if op in "+-" and depth % 2 == 0:
        return f"{left} {op} ({right})", value
    return f"({left}) {op} ({right})", value


@st.composite
def robtarget_literal(draw: st.DrawFn) -> tuple[str, tuple[float, float, float]]:
    trans = [draw(number()) for _ in range(3)]
    text = ("[[" + ",".join(t for t, _ in trans) + "],[1,0,0,0],[0,-1,2,0],"
            "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
    return text, tuple(v for _, v in trans)


@st.composite
def statement(draw: st.DrawFn, targets: list[str], depth: int = 0) -> str:
    g = draw(gaps)
    choice = draw(st.integers(0, 6 if depth < 2 else 2))
    if choice == 0:
        target = draw(st.sampled_from(targets))
        move = draw(st.sampled_from(["MoveL", "MoveJ", "movel"]))
        extra = draw(st.sampled_from(["", " \\WObj:=wobj0", "\\V:=100", " \\T:=2 \\WObj:=wobj0"]))
        return f"{move}{g}{target},{g}v100, z10,{g}tool0{extra};"
    if choice == 1:
        return f"reg1 :={g}{draw(expression())[0]};"
    if choice == 2:
        return "TPWrite " + draw(st.sampled_from(STRINGS)) + ";"
    body = g.join(draw(st.lists(statement(targets, depth + 1), min_size=0, max_size=3)))
    if choice == 3:
        return (f"{draw(cased('IF'))} reg1 > 1 {draw(cased('THEN'))}{g}{body}{g}"
                f"{draw(cased('ELSE'))}{g}{draw(cased('ENDIF'))}")
    if choice == 4:
        return f"FOR i FROM 1 TO 3 DO{g}{body}{g}ENDFOR"
    if choice == 5:
        return f"WHILE reg1 < 2 DO{g}{body} reg1 := reg1 + 1;{g}ENDWHILE"
    return f"TEST reg1{g}CASE 1, 2:{g}{body}{g}DEFAULT:{g}Stop;{g}ENDTEST"


@st.composite
def program_text(draw: st.DrawFn) -> tuple[str, dict[str, float], dict[str, tuple], int]:
    """A random valid module, the values of its CONST nums and robtargets, and its
    number of motion instructions."""
    nums = draw(st.dictionaries(names, expression(), min_size=1, max_size=4))
    targets = draw(st.dictionaries(names.map(lambda n: "p" + n), robtarget_literal(),
                                   min_size=1, max_size=4))
    g = draw(gaps)
    lines = [f"{draw(cased('MODULE'))} Rand"]
    lines += [f"  {draw(cased('CONST'))} num {n} :={g}{text};" for n, (text, _) in nums.items()]
    lines += [f"  CONST robtarget {n}:={text};" for n, (text, _) in targets.items()]
    lines.append("  VAR num reg1 := 0;")
    body = draw(st.lists(statement(list(targets)), min_size=1, max_size=6))
    lines.append(f"  PROC main(){g}" + f"{g}".join(body) + f"{g}{draw(cased('ENDPROC'))}")
    lines.append(draw(cased("ENDMODULE")))
    text = "\n".join(lines) + draw(st.sampled_from(["", "\n", "\n! end\n"]))
    moves = sum(s.lower().count("movel") + s.count("MoveJ") for s in body)
    return text, {n: v for n, (_, v) in nums.items()}, \
        {n: v for n, (_, v) in targets.items()}, moves


def encode(text: str, newline: str, bom: bool) -> bytes:
    data = text.replace("\r\n", "\n").replace("\n", newline).encode("utf-8")
    return (codecs.BOM_UTF8 if bom else b"") + data


@SETTINGS
@given(program_text(), st.sampled_from(["\n", "\r\n"]), st.booleans())
def test_random_programs_parse_evaluate_and_round_trip(generated, newline, bom):
    text, nums, targets, moves = generated
    data = encode(text, newline, bom)
    program = parse_program(data, "random.mod")
    assert Editor(program).render() == data
    assert program.source.encode() == data
    for name, value in nums.items():
        decl = program.declaration(name)
        assert decl.static
        assert abs(decl.value - value) <= 1e-9 * max(1.0, abs(value))
    for name, trans in targets.items():
        assert program.declaration(name).data.trans == trans
    assert len(program.motions) == moves
    for motion in program.motions:
        assert motion.target.static and motion.target.data.trans == targets[motion.target.name]
        assert motion.span.text.endswith(";")


JUNK = ["", ";", ",", ":=", "(", ")", "[", "]", "{", "}", "\\", "%", "<SMT>", "<EXP>", "!",
        "\"", "ENDIF", "ENDMODULE", "MODULE", "IF", "x", "1", ".", "?", "\x00", "\xff", "é", "\n"]


@st.composite
def corruption(draw: st.DrawFn) -> bytes:
    text, _nums, _targets, _moves = draw(program_text())
    chars = list(text)
    for _ in range(draw(st.integers(1, 3))):
        position = draw(st.integers(0, len(chars)))
        action = draw(st.sampled_from(["insert", "delete", "replace"]))
        junk = list(draw(st.sampled_from(JUNK)))
        if action == "insert":
            chars[position:position] = junk
        else:
            length = draw(st.integers(1, 12))
            chars[position:position + length] = junk if action == "replace" else []
    encoding = draw(st.sampled_from(["utf-8", "latin-1"]))
    return "".join(chars).encode(encoding, errors="replace")


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(corruption())
def test_corruptions_raise_only_rapid_syntax_error(data):
    try:
        program = parse_program(data, "broken.mod")
    except RapidSyntaxError as err:
        assert err.file == "broken.mod"
        assert "\n" not in err.message
        if err.line is not None:
            assert 1 <= err.line <= data.count(b"\n") + 1
        if isinstance(err.column, int):
            assert err.column >= 1
    else:  # some corruptions are still valid RAPID: then they must round-trip
        assert Editor(program).render() == data
