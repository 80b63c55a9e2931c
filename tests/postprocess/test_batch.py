"""Batch: a broken file, a file with run-time targets and a good file, in parallel."""

from __future__ import annotations

import json
import shutil

from rapidfix.cli import main
from rapidfix.postprocess.batch import BatchSettings, run_batch
from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import load_program

RUNTIME = """MODULE Runtime
  VAR robtarget pHere;
  PROC main()
    pHere := CRobT(\\Tool:=tool0);
    MoveL Offs(pHere, 0, 0, 50), v100, fine, tool0;
  ENDPROC
ENDMODULE
"""
BROKEN = "MODULE Broken\n  PROC main()\n    MoveL p10, v100 fine, tool0;\n  ENDPROC\nENDMODULE\n"


def make_tree(root, samples):
    (root / "cell" / "sub").mkdir(parents=True)
    shutil.copy(samples / "ballbar.mod", root / "cell" / "sub" / "good.mod")
    (root / "cell" / "runtime.MOD").write_text(RUNTIME)
    (root / "broken.prg").write_text(BROKEN)
    (root / "notes.txt").write_text("not RAPID\n")
    return root


def test_one_error_one_warning_one_clean(cell, comp, samples, tmp_path):
    src = make_tree(tmp_path / "in", samples)
    out = tmp_path / "out"
    settings = BatchSettings(str(cell["model_path"]), None, None, (), RewriteOptions())
    summary = run_batch(src, out, settings, workers=2, progress=False)
    status = {f.path: f.status for f in summary.files}
    assert status == {
        "broken.prg": "error",
        "cell/runtime.MOD": "warnings",
        "cell/sub/good.mod": "ok",
        "notes.txt": "copied",
    }
    broken = next(f for f in summary.files if f.path == "broken.prg")
    assert "broken.prg:3:" in broken.message
    runtime = next(f for f in summary.files if f.path == "cell/runtime.MOD")
    assert runtime.moves_skipped == 1 and "runtime.MOD:5" in runtime.skipped[0]
    # the good output is complete: it parses, and it is exactly what a single rewrite gives
    good = out / "cell" / "sub" / "good.mod"
    single = rewrite_source(
        (src / "cell/sub/good.mod").read_bytes(),
        str(src / "cell/sub/good.mod"),
        comp,
        RewriteOptions(),
    )
    assert good.read_bytes() == single.data
    assert len(load_program(good).motions) == 21 + single.points_added
    assert (out / "notes.txt").read_text() == "not RAPID\n"
    assert not (out / "broken.prg").exists()
    assert not list(out.rglob("*.tmp"))
    totals = summary.to_dict()
    assert totals["errors"] == 1 and totals["with_warnings"] == 1
    assert totals["moves_compensated"] == 21
    # inputs untouched
    original = (samples / "ballbar.mod").read_bytes()
    assert (src / "cell" / "sub" / "good.mod").read_bytes() == original


def test_rerun_skips_files_already_up_to_date(cell, samples, tmp_path, capsys):
    src = make_tree(tmp_path / "in", samples)
    out = tmp_path / "out"
    args = [
        "batch",
        str(src),
        str(out),
        "--model",
        str(cell["model_path"]),
        "-j",
        "1",
        "--no-progress",
    ]
    assert main(args) == 1  # one file failed
    first = json.loads((out / "rapidfix-batch.json").read_text())
    assert first["errors"] == 1 and first["rewritten"] == 2
    stamp = (out / "cell" / "sub" / "good.mod").stat().st_mtime_ns
    assert main(args) == 1
    second = json.loads((out / "rapidfix-batch.json").read_text())
    # runtime.MOD had nothing compensated: its output carries no header (so it is not
    # taken for a compensated program) and it is looked at again
    assert second["up_to_date"] == 1 and second["with_warnings"] == 1
    # the counts recorded in the outputs' headers are reported again
    assert second["moves_skipped"] == 1 and second["moves_compensated"] == 21
    assert (out / "cell" / "sub" / "good.mod").stat().st_mtime_ns == stamp
    table = capsys.readouterr().out
    assert "up-to-date" in table and "broken.prg" in table
    # a changed input is rewritten again
    good = src / "cell" / "sub" / "good.mod"
    good.write_bytes(good.read_bytes().replace(b"v50, fine", b"v40, fine", 1))
    assert main(args) == 1
    third = json.loads((out / "rapidfix-batch.json").read_text())
    assert third["up_to_date"] == 0 and third["rewritten"] == 2


def test_in_place_keeps_backups(cell, samples, tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(samples / "ballbar.mod", src / "a.mod")
    original = (src / "a.mod").read_bytes()
    args = [
        "batch",
        str(src),
        "--in-place",
        "--model",
        str(cell["model_path"]),
        "-j",
        "1",
        "--no-progress",
    ]
    assert main(args) == 0
    assert (src / "a.mod.bak").read_bytes() == original
    assert b"rapidfix-compensated" in (src / "a.mod").read_bytes()
    assert main(args) == 0  # already compensated: skipped, not compensated twice
    assert not (src / "a.mod.bak2").exists()


def test_strict_batch_fails_the_file_with_skipped_targets(cell, samples, tmp_path):
    src = make_tree(tmp_path / "in", samples)
    out = tmp_path / "out"
    settings = BatchSettings(str(cell["model_path"]), None, None, (), RewriteOptions(strict=True))
    summary = run_batch(src, out, settings, workers=1, progress=False)
    status = {f.path: f.status for f in summary.files}
    assert status["cell/runtime.MOD"] == "error" and status["cell/sub/good.mod"] == "ok"
    assert not (out / "cell" / "runtime.MOD").exists()
    assert (out / "cell" / "sub" / "good.mod").exists()


SEARCH_AND_RUNTIME = """MODULE Seam
  CONST robtarget p10:=[[600,0,700],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  VAR robtarget pHere;
  VAR pose found;
  PROC main()
    MoveL p10, v100, fine, tool0;
    pHere := CRobT(\\Tool:=tool0);
    MoveL Offs(pHere, 0, 0, 50), v100, fine, tool0;
    Search_1D found, p10, Offs(p10,0,0,20), v200, tool0;
  ENDPROC
ENDMODULE
"""


def test_the_summary_keeps_every_warning_of_a_file(cell, tmp_path):
    """A file with a skipped target and a target left to an unknown procedure: the
    summary file lists the skipped target and the warning, in the command's words."""
    src, out = tmp_path / "in", tmp_path / "out"
    src.mkdir()
    (src / "seam.mod").write_text(SEARCH_AND_RUNTIME)
    assert main(["batch", str(src), str(out), "--model", str(cell["model_path"]), "-j", "1",
                 "--no-progress"]) == 3
    (entry,) = json.loads((out / "rapidfix-batch.json").read_text())["results"]
    assert entry["status"] == "warnings" and entry["moves_skipped"] == 1
    assert any("CRobT" in line or "pHere" in line for line in entry["skipped"])
    assert any(w.startswith("seam.mod:9:5: Search_1D is not a motion instruction")
               for w in entry["warnings"]), entry["warnings"]


def test_a_named_pipe_in_the_folder_is_left_alone_not_waited_on(cell, samples, tmp_path):
    """A pipe nobody writes to would block a read for ever: the batch names it as a file
    it left alone and rewrites the others (in two workers and in one, out of place and in
    place); a pipe among a task's modules lends nothing either (an alarm fails the test
    instead of letting it wait)."""
    import os
    import signal

    src = make_tree(tmp_path / "in", samples)
    os.mkfifo(src / "cell" / "waiting.mod")
    os.mkfifo(src / "pipe.txt")
    task = src / "RAPID" / "TASK1" / "PROGMOD"
    task.mkdir(parents=True)
    shutil.copy(samples / "ballbar.mod", task / "main.mod")
    os.mkfifo(task / "data.sys")

    def waited(*_):
        raise TimeoutError("the batch waited on a named pipe")

    previous = signal.signal(signal.SIGALRM, waited)
    signal.alarm(120)
    try:
        settings = BatchSettings(str(cell["model_path"]), None, None, (), RewriteOptions())
        for workers in (2, 1):
            summary = run_batch(src, tmp_path / f"out{workers}", settings, workers=workers,
                                progress=False)
            status = {f.path: f.status for f in summary.files}
            assert status["cell/sub/good.mod"] == "ok" and status["notes.txt"] == "copied"
            assert status["RAPID/TASK1/PROGMOD/main.mod"] == "ok"
            assert (status["cell/waiting.mod"] == status["pipe.txt"]
                    == status["RAPID/TASK1/PROGMOD/data.sys"] == "error")
            waiting = next(f for f in summary.files if f.path == "cell/waiting.mod")
            assert waiting.message.endswith("waiting.mod: not a regular file (a named pipe, "
                                            "a socket or a device): left alone")
            assert not (tmp_path / f"out{workers}" / "pipe.txt").exists()
        in_place = BatchSettings(str(cell["model_path"]), None, None, (), RewriteOptions(),
                                 in_place=True)
        summary = run_batch(src, None, in_place, workers=1, progress=False)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    status = {f.path: f.status for f in summary.files}
    assert status["cell/waiting.mod"] == "error" and status["cell/sub/good.mod"] == "ok"
    assert "pipe.txt" not in status  # in place: RAPID files only
