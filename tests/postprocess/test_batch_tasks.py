"""A batch over a controller backup: the modules of one task see each other's data.

The sample ballbar program is split as a backup keeps a cell: its tool and work
object in `RAPID/TASK1/SYSMOD/CalibData.sys`, the moves in `PROGMOD/Ballbar.mod`.
The truth is the same program rewritten whole (everything declared in one file).
"""

from __future__ import annotations

import json
import re
from pathlib import Path, PurePath

import pytest

from rapidfix.cli import main
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.postprocess.task_modules import task_folder

FRAMES = re.compile(r"^    PERS (tooldata|wobjdata) .*\n", re.MULTILINE)
JOINTTARGETS = re.compile(r"^\s*CONST jointtarget .*$", re.MULTILINE)


def _calib(frames: str) -> str:
    return f"MODULE CalibData(SYSMODULE)\n{frames}ENDMODULE\n"


@pytest.fixture
def backup(samples, tmp_path):
    """A backup with two tasks (TASK2 lacks the data module) and a plain folder holding
    the same two files, which are not one task."""
    text = (samples / "ballbar.mod").read_text()
    frames = "".join(m.group() for m in FRAMES.finditer(text))
    assert frames.count("PERS") == 2
    program = FRAMES.sub("", text)
    root = tmp_path / "backup"
    for task, files in (("TASK1", {"PROGMOD/Ballbar.mod": program,
                                   "SYSMOD/CalibData.sys": _calib(frames)}),
                        ("TASK2", {"PROGMOD/Ballbar.mod": program})):
        for rel, content in files.items():
            path = root / "RAPID" / task / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(content)
    (root / "loose").mkdir()
    (root / "loose" / "Ballbar.mod").write_text(program)
    (root / "loose" / "CalibData.sys").write_text(_calib(frames))
    return root, text


def _args(src, model, *more):
    return ["batch", str(src), *more, "--model", str(model), "-j", "2", "--no-progress"]


def test_task_folders_are_found_where_a_backup_keeps_them():
    assert task_folder(PurePath("B/RAPID/TASK1/PROGMOD/M.mod")) == PurePath("B/RAPID/TASK1")
    assert task_folder(PurePath("rapid/task12/x.sys")) == PurePath("rapid/task12")
    assert task_folder(PurePath("RAPID/TASK1.mod")) is None
    assert task_folder(PurePath("cell/TASK1/M.mod")) is None  # not under RAPID
    assert task_folder(PurePath("RAPID/T_ROB1/M.mod")) is None
    # a task's folder saved on its own: the folder holding PROGMOD and SYSMOD
    assert task_folder(PurePath("welder/RAPID/PROGMOD/M.mod")) == PurePath("welder/RAPID")
    assert task_folder(PurePath("SYSMOD/user.sys")) == PurePath()
    assert task_folder(PurePath("cell/progs/M.mod")) is None
    # a file further down is not one of the task's modules
    assert task_folder(PurePath("RAPID/TASK1/SYSMOD/old/M.sys")) is None
    assert task_folder(PurePath("RAPID/TASK1/extra/M.mod")) is None
    assert task_folder(PurePath("RAPID/TASK1/M.mod")) == PurePath("RAPID/TASK1")


def test_a_module_uses_the_data_of_its_task_and_only_of_its_task(cell, comp, backup,
                                                               tmp_path, capsys):
    root, whole = backup
    out = tmp_path / "out"
    assert main(_args(root, cell["model_path"], str(out))) == 3
    summary = json.loads((out / "rapidfix-batch.json").read_text())
    files = {f["path"]: f for f in summary["results"]}
    task1 = files["RAPID/TASK1/PROGMOD/Ballbar.mod"]
    assert task1["status"] == "ok" and task1["moves_compensated"] == 21
    truth = rewrite_source(whole.encode(), "whole.mod", comp, RewriteOptions()).data.decode()
    written = (out / "RAPID/TASK1/PROGMOD/Ballbar.mod").read_text()
    assert JOINTTARGETS.findall(written) == JOINTTARGETS.findall(truth)
    for other in ("RAPID/TASK2/PROGMOD/Ballbar.mod", "loose/Ballbar.mod"):
        assert files[other]["moves_compensated"] == 0, other
        assert all("tBallbar is not declared in this file" in s
                   for s in files[other]["skipped"]), files[other]["skipped"]
    capsys.readouterr()
    # the data module is part of what the output depends on: a changed tool load is seen
    # (this model has no payload effect: the same joints, written again)
    calib = root / "RAPID/TASK1/SYSMOD/CalibData.sys"
    calib.write_text(calib.read_text().replace("[1.2,[0,0,60]", "[1.3,[0,0,60]", 1))
    assert main(_args(root, cell["model_path"], str(out))) == 3
    third = {f["path"]: f for f in json.loads((out / "rapidfix-batch.json").read_text())["results"]}
    assert third["RAPID/TASK1/PROGMOD/Ballbar.mod"]["status"] == "ok"  # not up to date
    assert third["RAPID/TASK1/PROGMOD/Ballbar.mod"]["moves_compensated"] == 21


def test_in_place_reads_the_task_as_it_was_before_the_batch(cell, backup, tmp_path):
    root, _ = backup
    out = tmp_path / "out"
    assert main(_args(root, cell["model_path"], str(out))) == 3
    assert main(_args(root, cell["model_path"], "--in-place")) == 3
    in_place = (root / "RAPID/TASK1/PROGMOD/Ballbar.mod").read_text()
    assert JOINTTARGETS.findall(in_place) == JOINTTARGETS.findall(
        (out / "RAPID/TASK1/PROGMOD/Ballbar.mod").read_text())
    assert not list(tmp_path.glob("rapidfix-task-*"))


def test_an_ambiguous_or_local_name_in_the_task_is_named(cell, backup, tmp_path):
    root, _ = backup
    calib = root / "RAPID/TASK1/SYSMOD/CalibData.sys"
    (calib.parent / "Spare.sys").write_text(calib.read_text().replace("CalibData", "Spare"))
    out = tmp_path / "out"
    assert main(_args(root, cell["model_path"], str(out))) == 3
    files = {f["path"]: f for f in json.loads((out / "rapidfix-batch.json").read_text())["results"]}
    skipped = files["RAPID/TASK1/PROGMOD/Ballbar.mod"]["skipped"]
    assert skipped and all("tBallbar is declared in module CalibData of" in s
                           and "and in module Spare of" in s for s in skipped), skipped


def _mark_compensated(module: Path) -> None:
    """Give a module the header line of a compensated output."""
    lines = module.read_text().splitlines(keepends=True)
    lines.insert(1, "  ! rapidfix-compensated version: rapidfix 0.1.0\n")
    module.write_text("".join(lines))


def test_a_compensated_module_lends_nothing(cell, backup, tmp_path):
    """A module of the task that is itself a compensated output (its targets may be
    compensated already) is not read for declarations: what it declares stays unknown
    rather than compensated twice."""
    root, _ = backup
    _mark_compensated(root / "RAPID/TASK1/SYSMOD/CalibData.sys")
    out = tmp_path / "out"
    assert main(_args(root, cell["model_path"], str(out), "--force")) == 3
    results = json.loads((out / "rapidfix-batch.json").read_text())["results"]
    files = {f["path"]: f for f in results}
    assert files["RAPID/TASK1/PROGMOD/Ballbar.mod"]["moves_compensated"] == 0


def test_rewrite_of_one_module_reads_its_task_and_no_further(cell, comp, backup, tmp_path,
                                                            capsys):
    """`rewrite` of one module of a backup reads the other modules of its task where the
    controller keeps them (PROGMOD, SYSMOD), as the batch does; `--no-task-modules`, or a
    file outside a task folder, reads nothing more."""
    root, whole = backup
    # a RAPID file further down the task folder is not one of its modules
    (root / "RAPID/TASK1/SYSMOD/old").mkdir()
    (root / "RAPID/TASK1/SYSMOD/old/Spare.sys").write_text(
        (root / "RAPID/TASK1/SYSMOD/CalibData.sys").read_text().replace("CalibData", "Spare"))
    program = root / "RAPID/TASK1/PROGMOD/Ballbar.mod"
    model = str(cell["model_path"])
    out = tmp_path / "one.mod"
    assert main(["rewrite", str(program), "--model", model, "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"declarations also read from 1 other module(s) of its task ({root / 'RAPID/TASK1'})" \
        in printed
    truth = rewrite_source(whole.encode(), "whole.mod", comp, RewriteOptions()).data.decode()
    assert JOINTTARGETS.findall(out.read_text()) == JOINTTARGETS.findall(truth)
    assert main(["rewrite", str(program), "--model", model, "-o", str(out), "--force",
                 "--no-task-modules"]) == 3
    assert "declarations also read" not in capsys.readouterr().out
    assert main(["rewrite", str(root / "loose/Ballbar.mod"), "--model", model,
                 "-o", str(out), "--force"]) == 3
    assert "declarations also read" not in capsys.readouterr().out


def test_batch_without_task_modules_reads_each_file_alone(cell, backup, tmp_path):
    root, _ = backup
    out = tmp_path / "out"
    assert main(_args(root, cell["model_path"], str(out), "--no-task-modules")) == 3
    results = json.loads((out / "rapidfix-batch.json").read_text())["results"]
    assert sum(f["moves_compensated"] for f in results) == 0


PGF = """<?xml version="1.0" encoding="ISO-8859-1" ?>
<Program>
\t<Module>Ballbar.mod</Module>
\t<Module>CalibData.sys</Module>
</Program>
"""


def test_a_saved_program_folder_is_one_task(cell, comp, backup, tmp_path, capsys):
    """A program saved with its .pgf file: the modules it lists see each other's data, in
    `batch` and in `rewrite`; a module of the folder it does not list sees nothing."""
    root, whole = backup
    saved = root / "saved"
    saved.mkdir()
    for name in ("Ballbar.mod", "CalibData.sys"):
        (saved / name).write_text((root / "loose" / name).read_text())
    (saved / "Other.mod").write_text((root / "loose" / "Ballbar.mod").read_text()
                                     .replace("MODULE Ballbar", "MODULE Other", 1))
    (saved / "Cell.pgf").write_text(PGF)
    truth = rewrite_source(whole.encode(), "whole.mod", comp, RewriteOptions()).data.decode()
    out = tmp_path / "out"
    assert main(_args(saved, cell["model_path"], str(out))) == 3
    files = {f["path"]: f for f in
             json.loads((out / "rapidfix-batch.json").read_text())["results"]}
    assert files["Ballbar.mod"]["moves_compensated"] == 21
    assert files["Other.mod"]["moves_compensated"] == 0
    assert JOINTTARGETS.findall((out / "Ballbar.mod").read_text()) == JOINTTARGETS.findall(truth)
    assert (out / "Cell.pgf").read_text() == PGF  # copied as it is
    one = tmp_path / "one.mod"
    assert main(["rewrite", str(saved / "Ballbar.mod"), "--model", str(cell["model_path"]),
                 "-o", str(one)]) == 0
    assert f"1 other module(s) of its task ({saved})" in capsys.readouterr().out
    # a file that is not a program file lends nothing and stops nothing
    (saved / "Cell.pgf").write_text("<Program><Module>Ballbar.mod</Modu")
    assert main(_args(saved, cell["model_path"], str(tmp_path / "out2"))) == 3
    broken = {f["path"]: f for f in
              json.loads((tmp_path / "out2/rapidfix-batch.json").read_text())["results"]}
    assert broken["Ballbar.mod"]["moves_compensated"] == 0


def test_rewrite_says_when_a_module_of_its_task_is_not_read(cell, backup, tmp_path, capsys):
    root, _ = backup
    calib = root / "RAPID/TASK1/SYSMOD/CalibData.sys"
    calib.write_text(calib.read_text().replace("ENDMODULE", "ENDMOD"))
    assert main(["rewrite", str(root / "RAPID/TASK1/PROGMOD/Ballbar.mod"), "--model",
                 str(cell["model_path"]), "-o", str(tmp_path / "one.mod")]) == 3
    out, err = capsys.readouterr()
    assert "declarations also read" not in out
    assert (f"rapidfix: warning: {calib}: this module of the task is not read for its "
            "declarations: it does not parse (line ") in err


def test_an_unread_module_of_the_task_alone_gives_exit_status_3(cell, backup, tmp_path,
                                                                  capsys):
    """A module of the task left unread (here a compensated program: its targets may be
    compensated already) is named with the reason, and the exit status says a warning
    was given, also when the program itself moves nowhere."""
    root, _ = backup
    calib = root / "RAPID/TASK1/SYSMOD/CalibData.sys"
    text = calib.read_text()
    _mark_compensated(calib)
    idle = root / "RAPID/TASK1/PROGMOD/Idle.mod"
    idle.write_text('MODULE Idle\n  PROC wait()\n    WaitTime 1;\n  ENDPROC\nENDMODULE\n')
    assert main(["rewrite", str(idle), "--model", str(cell["model_path"]),
                 "-o", str(tmp_path / "idle.mod")]) == 3
    err = capsys.readouterr().err
    assert (f"rapidfix: warning: {calib}: this module of the task is not read for its "
            "declarations: it is a compensated program") in err
    calib.write_text(text)  # as it was: read again, nothing to say
    assert main(["rewrite", str(idle), "--model", str(cell["model_path"]),
                 "-o", str(tmp_path / "idle.mod"), "--force"]) == 0
    assert "warning" not in capsys.readouterr().err
