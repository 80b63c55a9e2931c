"""The RAPID receiver shipped in the package: parsed by our grammar, in step with Python."""

import re

from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.link import RECEIVER_MODULE
from rapidfix.link.checksum import crc16
from rapidfix.link.protocol import (
    BUSY_EVERY,
    MAX_PAYLOAD,
    PROTOCOL_VERSION,
    DoneStatus,
    FrameKind,
    ReadyStatus,
)
from rapidfix.link.receiver import TEMP_SUFFIX, ReceiverState


def constants(text):
    """CONST num/string declarations of the module, as Python values."""
    found = {}
    for kind, name, value in re.findall(
        r"^\s*CONST\s+(num|string)\s+(\w+)\s*:=\s*([^;]+);", text, flags=re.MULTILINE
    ):
        found[name] = float(value) if kind == "num" else value.strip().strip('"')
    return found


def test_receiver_module_parses_with_the_project_grammar():
    from rapidfix.rapid import parse_program

    text = RECEIVER_MODULE.read_text(encoding="ascii")
    program = parse_program(text, str(RECEIVER_MODULE))
    names = {routine.name for routine in program.routines}
    assert {"RfxRecvMain", "ReadFrame", "CrcByte", "OnHello", "OnData", "OnEnd"} <= names
    assert not program.motions  # a receiver never moves the robot


def test_receiver_module_speaks_the_protocol_of_the_python_side():
    const = constants(RECEIVER_MODULE.read_text(encoding="ascii"))
    assert const["RFX_VERSION"] == PROTOCOL_VERSION
    assert const["RFX_MAXPAY"] == MAX_PAYLOAD
    assert const["RFX_BUSY_EVERY"] == BUSY_EVERY
    assert const["RFX_TEMP"] == TEMP_SUFFIX
    assert const["SOH"] == 1
    for kind in FrameKind:
        assert const[f"K_{kind.name}"] == kind.value
    for status in ReadyStatus:
        assert const[f"READY_{status.name}"] == status.value
    for status in DoneStatus:
        assert const[f"DONE_{status.name}"] == status.value
    for state in ReceiverState:
        assert const[f"S_{state.name}"] == state.value


def test_receiver_module_is_shipped_inside_the_package():
    assert RECEIVER_MODULE.is_file()
    assert RECEIVER_MODULE.parent.parent.name == "link"
    text = RECEIVER_MODULE.read_text(encoding="ascii")
    assert text.lstrip().startswith("MODULE RfxRecv")
    assert max(len(s) for s in re.findall(r'"([^"]*)"', text)) <= 80  # RAPID string limit


def rapid_crc_byte():
    """CrcByte of RfxRecv.mod run statement by statement with RAPID's byte functions."""
    text = RECEIVER_MODULE.read_text(encoding="ascii")
    body = text[
        text.index("PROC CrcByte(num value)") : text.index("ENDPROC", text.index("CrcByte"))
    ]
    statements = re.findall(r"^\s*(\w+)\s*:=\s*([^;]+);", body, flags=re.MULTILINE)
    assert len(statements) >= 4
    functions = {
        "BitXOr": lambda a, b: a ^ b,
        "BitLSh": lambda a, n: (a << n) & 0xFF,  # a byte: bits shifted past bit 7 are lost
        "BitRSh": lambda a, n: a >> n,
        "BitAnd": lambda a, b: a & b,
    }

    def step(state, value):
        env = dict(functions, value=value, **state)
        for target, expr in statements:
            env[target] = eval(expr, {"__builtins__": {}}, env)
            assert 0 <= env[target] <= 255
        return {"crcHi": env["crcHi"], "crcLo": env["crcLo"]}

    return step


@settings(max_examples=40, deadline=None)
@given(st.binary(max_size=120))
def test_the_rapid_crc_procedure_computes_crc16(data):
    step = rapid_crc_byte()
    state = {"crcHi": 255, "crcLo": 255}  # CrcStart
    for byte in data:
        state = step(state, byte)
    assert (state["crcHi"] << 8) | state["crcLo"] == crc16(data)
