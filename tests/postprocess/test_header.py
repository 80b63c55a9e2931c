"""The header comment of a compensated program (postprocess/header.py)."""

from __future__ import annotations

from rapidfix.postprocess.header import Header, is_compensated, read_header


def test_header_round_trip():
    header = Header(
        "1.2.3",
        "models/cell model.json",
        "a" * 64,
        "b" * 64,
        {"emit": "jointtargets", "path_tolerance_mm": "0.1"},
        "3 moves",
    )
    text = "MODULE M" + header.render("  ", "\r\n") + "\r\nENDMODULE\r\n"
    back = read_header(text)
    assert back.model_sha256 == "a" * 64 and back.input_sha256 == "b" * 64
    assert back.options == {"emit": "jointtargets", "path_tolerance_mm": "0.1"}
    assert back.version == "1.2.3" and back.model_path == "models/cell model.json"
    assert is_compensated(text) and not is_compensated("MODULE M\n! rapidfix rocks\nENDMODULE\n")
