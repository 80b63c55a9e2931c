"""`rapidfix rewrite` as a user runs it: exit status, strict, force, in-place, --decls."""

from __future__ import annotations

import hashlib
import shutil

import pytest

from rapidfix.cli import main
from rapidfix.postprocess.header import read_header
from rapidfix.rapid import load_program

EXTAX = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
USES_OUTSIDE_DATA = """MODULE Station
  CONST robtarget pA:=[[100,50,0],[0,0.258819045,0.965925826,0],[0,0,-1,1],EXTAX];
  PROC main()
    MoveJ pA, v100, fine, tBar\\WObj:=wPlate;
  ENDPROC
ENDMODULE
"""
DECLS = """MODULE BaseData(SYSMODULE)
  PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
  PERS wobjdata wPlate:=[FALSE,TRUE,"",[[850,80,450],[0.923879533,0,-0.382683432,0]],
                         [[0,0,0],[1,0,0,0]]];
ENDMODULE
"""


@pytest.fixture
def program(samples, tmp_path):
    path = tmp_path / "ballbar.mod"
    shutil.copy(samples / "ballbar.mod", path)
    return path


def test_rewrite_writes_header_and_exit_zero(cell, program, tmp_path, capsys):
    out = tmp_path / "out.mod"
    assert main(["rewrite", str(program), "--model", str(cell["model_path"]), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "predicted worst-case TCP deviation" in text
    header = read_header(out.read_text())
    model_sha = hashlib.sha256(cell["model_path"].read_bytes()).hexdigest()
    assert header.model_sha256 == model_sha
    assert header.input_sha256 == hashlib.sha256(program.read_bytes()).hexdigest()
    assert header.options["emit"] == "jointtargets" and header.options["path_tolerance_mm"] == "0.1"
    assert not list(tmp_path.glob(".*.tmp"))


def test_refuses_compensated_program_unless_forced(cell, program, tmp_path, capsys):
    out = tmp_path / "out.mod"
    model = str(cell["model_path"])
    assert main(["rewrite", str(program), "--model", model, "-o", str(out)]) == 0
    again = tmp_path / "again.mod"
    assert main(["rewrite", str(out), "--model", model, "-o", str(again)]) == 1
    assert "already compensated" in capsys.readouterr().err
    assert not again.exists()
    assert main(["rewrite", str(out), "--model", model, "-o", str(again), "--force"]) == 0
    text = again.read_text()
    assert text.count("rapidfix-compensated version") == 1  # the old header was replaced
    load_program(again)


def test_never_overwrites_the_input_unless_in_place(cell, program, capsys):
    model = str(cell["model_path"])
    original = program.read_bytes()
    assert main(["rewrite", str(program), "--model", model, "-o", str(program)]) == 1
    assert "overwrite the input" in capsys.readouterr().err
    assert program.read_bytes() == original
    assert main(["rewrite", str(program), "--model", model, "--in-place"]) == 0
    backup = program.with_name(program.name + ".bak")
    assert backup.read_bytes() == original
    assert b"MoveAbsJ" in program.read_bytes()


def test_warnings_exit_three_and_strict_writes_nothing(cell, tmp_path, capsys):
    prog = tmp_path / "station.mod"
    prog.write_text(USES_OUTSIDE_DATA.replace("EXTAX", EXTAX))
    out = tmp_path / "out.mod"
    model = str(cell["model_path"])
    assert main(["rewrite", str(prog), "--model", model, "-o", str(out)]) == 3
    err = capsys.readouterr().err
    assert f"{prog}:4: MoveJ pA: tool tBar" in err and "--decls" in err
    assert out.exists() and b"MoveAbsJ" not in out.read_bytes()
    strict = tmp_path / "strict.mod"
    assert main(["rewrite", str(prog), "--model", model, "-o", str(strict), "--strict"]) == 1
    assert not strict.exists()
    decls = tmp_path / "base.sys"
    decls.write_text(DECLS)
    assert (
        main(["rewrite", str(prog), "--model", model, "-o", str(out), "--decls", str(decls)]) == 0
    )
    assert "MoveAbsJ jt_pA, v100, fine, tBar\\WObj:=wPlate;" in out.read_text()


@pytest.mark.parametrize(("files", "reason"), [
    ({"a.sys": DECLS.replace("PERS tooldata", "LOCAL PERS tooldata")},
     "tBar in module BaseData of {a} is LOCAL to that module"),
    ({"a.sys": DECLS, "b.sys": DECLS.replace("BaseData", "Other").replace("1.2,", "3.5,")},
     "tBar is declared in module BaseData of {a} and in module Other of {b}"),
    ({"a.sys": DECLS.replace("PERS tooldata tBar", "PERS num tBar:=1;\n  PERS tooldata tX")},
     "tBar in {a} is a num, not a tooldata"),
    ({"a.sys": DECLS.replace("PERS tooldata tBar:=", "VAR tooldata tBar;\n  PERS tooldata tY:=")
      + "MODULE Setter\n  PROC s()\n    tBar := tool0;\n  ENDPROC\nENDMODULE\n"},
     "tBar in {a}: "),
])
def test_declaration_files_are_seen_as_the_controller_sees_other_modules(
        cell, tmp_path, capsys, files, reason):
    """Data of another module is visible when it is declared at module level and not
    LOCAL; a name two modules declare is ambiguous (the controller refuses to load such
    a task) and is taken from neither; each is named with the file it comes from."""
    prog = tmp_path / "station.mod"
    prog.write_text(USES_OUTSIDE_DATA.replace("EXTAX", EXTAX))
    args = ["rewrite", str(prog), "--model", str(cell["model_path"]),
            "-o", str(tmp_path / "out.mod")]
    paths = {}
    for name, text in files.items():
        paths[name] = tmp_path / name
        paths[name].write_text(text)
        args += ["--decls", str(paths[name])]
    assert main(args) == 3
    err = capsys.readouterr().err
    expected = reason.format(**{k.split(".")[0]: str(v) for k, v in paths.items()})
    assert f"{prog}:4: MoveJ pA: tool tBar: {expected}" in err, err
    assert "pass the file" not in err


def test_a_compensated_declaration_file_is_refused(cell, program, tmp_path, capsys):
    """A compensated output passed as a declaration file could lend targets compensated
    once already: refused with the file named and the flag to use, nothing written."""
    model = str(cell["model_path"])
    compensated = tmp_path / "compensated.mod"
    assert main(["rewrite", str(program), "--model", model, "-o", str(compensated)]) == 0
    capsys.readouterr()
    out = tmp_path / "out.mod"
    assert main(["rewrite", str(program), "--model", model, "-o", str(out),
                 "--decls", str(compensated)]) == 1
    err = capsys.readouterr().err
    assert f"{compensated}: is a compensated program" in err
    assert "pass the original file with --decls" in err and "Traceback" not in err
    assert not out.exists()


def test_bad_options_are_user_errors(cell, program, tmp_path, capsys):
    model = str(cell["model_path"])
    out = str(tmp_path / "o.mod")
    assert (
        main(["rewrite", str(program), "--model", model, "-o", out, "--path-tolerance", "0"]) == 1
    )
    assert "path-tolerance" in capsys.readouterr().err
    assert (
        main(["rewrite", str(program), "--model", model, "-o", out, "--robot", "IRB120-3/0.58"])
        == 1
    )
    assert "made for robot" in capsys.readouterr().err
    assert main(["rewrite", str(program), "--model", model]) == 2  # no -o: wrong usage


def test_options_are_refused_in_the_library_words_and_in_the_command_words(
        cell, program, tmp_path, capsys):
    """The library names the field it refuses, the command line the flag."""
    from rapidfix.exceptions import InvalidOption
    from rapidfix.postprocess.rewrite import RewriteOptions

    with pytest.raises(InvalidOption) as err:
        RewriteOptions(temperature_c=400.0)
    assert err.value.option == "temperature_c"
    assert str(err.value).startswith("temperature_c 400 °C is not a cell temperature")
    out = str(tmp_path / "o.mod")
    status = main(["rewrite", str(program), "--model", str(cell["model_path"]), "-o", out,
                   "--temperature", "400"])
    message = capsys.readouterr().err
    assert status == 1 and "--temperature 400 °C is not a cell temperature" in message
    assert "temperature_c" not in message


def test_library_notes_hints_and_reasons_name_options_the_cli_names_flags(
        cell, program, tmp_path, capsys):
    """What the library says names its own options (a caller writes RewriteOptions(force=True));
    what the command prints of it names the flag (`--force`), word for word otherwise."""
    from rapidfix.exceptions import RapidSemanticError
    from rapidfix.postprocess import Compensator, RewriteOptions, rewrite_file, rewrite_source

    comp = Compensator.load(cell["model_path"])
    model = str(cell["model_path"])
    warm = tmp_path / "warm.mod"
    result = rewrite_file(program, warm, comp, RewriteOptions(temperature_c=25.0))
    note = ("RewriteOptions.temperature_c 25 °C: no effect of the model depends on the cell "
            "temperature, so it changes nothing (recorded only)")
    assert note in result.notes
    assert main(["rewrite", str(program), "--model", model, "-o", str(tmp_path / "w2.mod"),
                 "--temperature", "25"]) == 0
    printed = capsys.readouterr().out
    assert "  --temperature 25 °C: no effect of the model depends" in printed
    assert "RewriteOptions" not in printed

    with pytest.raises(RapidSemanticError) as err:
        rewrite_source(warm.read_bytes(), "warm.mod", comp, RewriteOptions())
    assert err.value.hint == "use RewriteOptions(force=True) to compensate it again"
    assert main(["rewrite", str(warm), "--model", model, "-o", str(tmp_path / "x.mod")]) == 1
    assert capsys.readouterr().err.endswith(
        f"{warm}: {err.value.message} (use --force to compensate it again)\n")

    station = (USES_OUTSIDE_DATA.replace("EXTAX", EXTAX)
               .replace("  ENDPROC", "    SearchL \\Stop, di1, pA, pA, v100, tool0;\n  ENDPROC"))
    result = rewrite_source(station.encode(), "station.mod", comp, RewriteOptions())
    reasons = [skipped.reason for skipped in result.skipped]
    assert any(r.endswith("(pass the file that declares it with Compensator.load(decl_files))")
               for r in reasons)
    prog = tmp_path / "station.mod"
    prog.write_text(station)
    assert main(["rewrite", str(prog), "--model", model, "-o", str(tmp_path / "s.mod")]) == 3
    err_text = capsys.readouterr().err
    assert "(pass the file that declares it with --decls)" in err_text
    assert "RewriteOptions" not in err_text and "Compensator" not in err_text


def test_the_library_names_no_command_line_flag():
    """No message of the post-processor (a string in its code) names a command-line flag:
    the commands put the flags in (rapidfix.commands.rewrite.FLAGS)."""
    import ast
    import re
    from pathlib import Path

    import rapidfix.postprocess

    flag = re.compile(r"(?<![\w-])--[a-z][\w-]*")
    found = []
    for path in sorted(Path(rapidfix.postprocess.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                found += [f"{path.name}:{node.lineno}: {m.group()}"
                          for m in flag.finditer(node.value)]
    assert not found, "\n".join(found)


def test_every_flag_of_the_table_is_put_in_where_the_library_names_its_option():
    from rapidfix.commands.rewrite import FLAGS, in_cli_words

    for words, flag in FLAGS.items():
        assert in_cli_words(f"use {words} here ({words})") == f"use {flag} here ({flag})"
    assert in_cli_words("target pA: no RewriteOptions here") == "target pA: no RewriteOptions here"


SEARCHES = """MODULE Seam
  CONST robtarget p10:=[[600,0,700],[0,0,1,0],[0,0,0,0],EXTAX];
  CONST robtarget p20:=[[600,100,700],[0,0,1,0],[0,0,0,0],EXTAX];
  PERS tooldata tWeld:=[TRUE,[[0,0,200],[1,0,0,0]],[2,[0,0,100],[1,0,0,0],0,0,0]];
  VAR pose found;
  PROC main()
    MoveL p10, v100, fine, tWeld;
    Search_1D found, p10, p20, v200, tWeld;
    MoveL p20, v100, fine, tWeld;
  ENDPROC
ENDMODULE
""".replace("EXTAX", EXTAX)


def test_targets_passed_to_an_unknown_procedure_are_named_and_left_as_written(
        cell, tmp_path, capsys):
    """A SmarTac search is not a motion rapidfix knows: its targets stay as written, and
    the user is told where (exit 3), not left to find out on the robot."""
    src, out = tmp_path / "seam.mod", tmp_path / "out.mod"
    src.write_text(SEARCHES)
    assert main(["rewrite", str(src), "--model", str(cell["model_path"]), "-o", str(out)]) == 3
    err = capsys.readouterr().err
    assert f"{src}:8:5: Search_1D is not a motion instruction rapidfix knows" in err
    assert "(p10, p20) are left as written" in err
    written = out.read_text()
    assert "    Search_1D found, p10, p20, v200, tWeld;\n" in written
    assert "CONST robtarget p10:=[[600,0,700]," in written  # still declared, unchanged
    assert "MoveL p10" not in written  # the moves themselves are compensated
    # without the search, nothing to say: exit 0
    src.write_text(SEARCHES.replace("    Search_1D found, p10, p20, v200, tWeld;\n", ""))
    assert main(["rewrite", str(src), "--model", str(cell["model_path"]), "-o", str(out),
                 "--force"]) == 0
    assert "not a motion instruction" not in capsys.readouterr().err


def test_a_program_failing_everywhere_lists_the_first_moves_and_counts_the_rest(
        cell, tmp_path, capsys):
    """A program written for tools this file does not declare leaves every move as it was:
    past 50 skipped moves, the first 20 are listed and the rest counted by the kind of
    their reason (each tool its own kind); --all-skipped lists every one."""
    from rapidfix.commands.rewrite import SKIP_LIST_HEAD, reason_kind

    moves = [f"    MoveL pA, v100, z1, {'tBar' if k % 10 else 'tCan'};" for k in range(70)]
    text = USES_OUTSIDE_DATA.replace("EXTAX", EXTAX).replace(
        "    MoveJ pA, v100, fine, tBar\\WObj:=wPlate;", "\n".join(moves))
    prog = tmp_path / "station.mod"
    prog.write_text(text)
    model = str(cell["model_path"])
    assert main(["rewrite", str(prog), "--model", model, "-o", str(tmp_path / "o.mod")]) == 3
    lines = capsys.readouterr().err.splitlines()
    listed = [line for line in lines if f"{prog}:" in line]
    assert [line.split(f"{prog}:")[1].split(":")[0] for line in listed] == [
        str(4 + k) for k in range(SKIP_LIST_HEAD)]
    assert lines[SKIP_LIST_HEAD] == ("rapidfix: warning: 50 more moves left as they were, not "
                                     "listed (--all-skipped lists them):")
    # moves 20..69: tCan on 20, 30, ... 60 (5), tBar on the other 45
    assert lines[SKIP_LIST_HEAD + 1:SKIP_LIST_HEAD + 3] == [
        "rapidfix: warning:   45 × tool tBar: tBar is not declared in this file …",
        "rapidfix: warning:   5 × tool tCan: tCan is not declared in this file …"]
    assert len(lines) == SKIP_LIST_HEAD + 3
    assert main(["rewrite", str(prog), "--model", model, "-o", str(tmp_path / "o.mod"),
                 "--all-skipped"]) == 3
    every = [line for line in capsys.readouterr().err.splitlines() if f"{prog}:" in line]
    assert len(every) == 70 and every[:SKIP_LIST_HEAD] == listed
    assert reason_kind("no solution on the branch its confdata [0, 0, 0, 0] names (it is "
                       "reachable with [0, -1, 0, 0], [0, 1, 2, 1])") == (
        "no solution on the branch its confdata … names …")
    assert reason_kind("joint 4 at 199.779° is outside [-200, 200] at p3_2") == (
        "joint … at …° is outside … at p3_2")


def test_moves_left_for_their_own_targets_are_counted_together():
    """A program of VAR targets assigned at run time, or of targets declared elsewhere,
    leaves each move for a reason that names its own target: past the listed head, more
    than a few such targets are counted as one kind of reason, not one line per target
    (a few keep their names). A tool's name stays in the kind, and so does a function
    the move calls."""
    from rapidfix.commands.rewrite import SKIP_LIST_HEAD, skipped_lines
    from rapidfix.postprocess.rewrite import Skipped

    moves = [Skipped(f"p.mod:{k}", f"MoveL p{k}", f"p{k}: VAR p{k} is assigned at line {k + 9}")
             for k in range(60)]
    moves += [Skipped(f"p.mod:{k}", f"MoveL Offs(q{k}, 0, 0, 10)",
                      f"q{k}: declared without a value") for k in range(30)]
    moves += [Skipped(f"p.mod:{k}", f"MoveL Offs(r{k},0,0,1)", "tool tBar: tBar is not declared "
                      "in this file (pass it)") for k in range(5)]
    moves += [Skipped("p.mod:1", "MoveL Offs(s,0,0,1)", "Offs: its result is out of reach")]
    # a few targets, named: pSafe is the one file to pass
    moves += [Skipped(f"p.mod:{k}", f"MoveJ {name}", f"{name} is not declared in this file "
                      "(pass it)") for k, name in enumerate(["pSafe"] * 3 + ["pHome"])]
    lines = skipped_lines(moves)
    assert lines[SKIP_LIST_HEAD:] == [
        "80 more moves left as they were, not listed (--all-skipped lists them):",
        "  40 × …: VAR … is assigned at line …",
        "  30 × …: declared without a value",
        "  5 × tool tBar: tBar is not declared in this file …",
        "  3 × pSafe is not declared in this file …",
        "  1 × Offs: its result is out of reach",
        "  1 × pHome is not declared in this file …"]
    assert len(skipped_lines(moves, every=True)) == len(moves)


@pytest.mark.parametrize(("own", "warned"), [
    ("  PERS tooldata tBar:=[TRUE,[[0,0,90],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];", True),
    ("  LOCAL PERS tooldata tBar:=[TRUE,[[0,0,90],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
     False),
])
def test_a_name_the_program_and_a_declaration_file_both_declare_is_warned_of(
        cell, tmp_path, capsys, own, warned):
    """The controller does not load a task where two modules declare the same global
    name; the program's own declaration is used, and a global one is warned of."""
    prog = tmp_path / "station.mod"
    prog.write_text(USES_OUTSIDE_DATA.replace("EXTAX", EXTAX).replace(
        "MODULE Station\n", "MODULE Station\n" + own + "\n"))
    decls = tmp_path / "base.sys"
    decls.write_text(DECLS)
    out = tmp_path / "out.mod"
    code = main(["rewrite", str(prog), "--model", str(cell["model_path"]), "-o", str(out),
                 "--decls", str(decls)])
    err = capsys.readouterr().err
    assert code == (3 if warned else 0)
    assert (f"{prog}: 1 name(s) this program declares are declared by a module read for its "
            f"data too: tBar (module BaseData of {decls}); the controller does not load"
            in err) == warned
    # the program's own tool (TCP z 90, not 100) was used either way: the same joints as
    # without the file (its work object given by a file of its own)
    wobj = tmp_path / "wobj.sys"
    wobj.write_text(DECLS.replace("PERS tooldata tBar", "PERS tooldata tOther"))
    alone = tmp_path / "alone.mod"
    assert main(["rewrite", str(prog), "--model", str(cell["model_path"]), "-o", str(alone),
                 "--decls", str(wobj)]) == 0

    def joints(path):
        return [line for line in path.read_text().splitlines() if "jointtarget jt_pA" in line]

    assert joints(out) == joints(alone) and len(joints(out)) == 1
