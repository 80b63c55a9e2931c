"""Constructs met in RAPID programs written by others, each in a minimal text of our own.

A corpus of a few hundred public RAPID files (RobotStudio backups, CAM output,
student labs, system modules) was run through `rapidfix check` and `rapidfix
rewrite`; every construct it refused that the RAPID kernel manual allows has a
test here.
"""

from __future__ import annotations

import pytest

from rapidfix.cli import main
from rapidfix.exceptions import RapidSyntaxError
from rapidfix.rapid import parse_program

TARGET = "[[400,-50.5,300],[0,0,1,0],[0,0,-1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"


# ---------------------------------------------------------------- ISO 8859-1 names
# RAPID's character set is ISO 8859-1: its accented letters are letters, so they
# may stand in identifiers (a Spanish cell names a routine after the letter Ñ).
LATIN1_MODULE = "\n".join([
    "MODULE Letras",
    f"  CONST robtarget pÑ:={TARGET};",
    "  PERS tooldata herramientaÉ:=[TRUE,[[0,0,120],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
    "  PROC Ñ()",
    "    MoveL pÑ, v100, fine, herramientaÉ;",
    "    MoveL Offs(PÑ, 0, 0, 25), v100, fine, HERRAMIENTAÉ;",
    "  ENDPROC",
    "  PROC Año_2024()",
    "    Ñ;",
    "  ENDPROC",
    "ENDMODULE",
    "",
])


def test_latin1_letters_in_names_parse_and_resolve_case_insensitively():
    program = parse_program(LATIN1_MODULE, "letras.mod")
    first, offset = program.motions
    assert first.target.name == "pÑ" and first.target.static
    assert first.target.data.trans == (400.0, -50.5, 300.0)
    assert first.tool.name == "herramientaÉ"
    # RAPID compares names without case: PÑ is pÑ, HERRAMIENTAÉ is herramientaÉ
    assert program.declaration("pñ") is program.declaration("PÑ") is not None
    assert offset.target.static and offset.target.data.trans == (400.0, -50.5, 325.0)
    assert offset.tool.declaration is program.declaration("herramientaé")


def test_latin1_names_in_a_cp1252_file_are_checked_ok(tmp_path, capsys):
    path = tmp_path / "letras.mod"
    path.write_bytes(LATIN1_MODULE.replace("\n", "\r\n").encode("cp1252"))
    assert main(["check", str(path)]) == 0
    assert "2 motion instructions" in capsys.readouterr().out


@pytest.mark.parametrize("sign", ["×", "÷"])
def test_signs_of_iso_8859_1_are_not_letters(sign):
    # × and ÷ are in the same block as the accented letters but are not letters
    with pytest.raises(RapidSyntaxError) as caught:
        parse_program(f"MODULE M\n  VAR num a{sign}b;\nENDMODULE\n", "signs.mod")
    assert (caught.value.line, caught.value.column) == (2, 12)
