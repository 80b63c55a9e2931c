"""Interruptions and awkward folders (issue #15, items 10–12 and 14): stale temporary
files, broken symlinks in a batch, Ctrl-C with workers, path tolerances and the reasons
moves are kept."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rapidfix import atomic
from rapidfix.cli import main
from rapidfix.exceptions import RapidfixError
from rapidfix.postprocess.rewrite import RewriteOptions

from .long_program import long_program

# ---- 10: temporary files of interrupted writes ------------------------------------------


def _dead_pid() -> int:
    """The pid of a process that has exited (and been reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_stale_temporaries_of_this_output_are_removed_by_the_next_write(tmp_path):
    target = tmp_path / "out.mod"
    dead = tmp_path / f".out.mod.{_dead_pid()}-a1b2c3d4.tmp"  # writer killed (SIGKILL)
    old = tmp_path / ".out.mod.k9x8y7z6.tmp"  # an old-style leftover, two hours old
    live = tmp_path / f".out.mod.{os.getppid()}-q1w2e3r4.tmp"  # a running writer's
    other = tmp_path / f".other.mod.{_dead_pid()}-a1b2c3d4.tmp"  # another output's
    mine = tmp_path / ".out.mod.notes.tmp"  # not the pattern: not ours
    for path in (dead, old, live, other, mine):
        path.write_bytes(b"x" * 1000)
    hours_ago = time.time() - 2 * 3600
    os.utime(old, (hours_ago, hours_ago))
    atomic.write_bytes_atomic(target, b"new")
    assert target.read_bytes() == b"new"
    assert not dead.exists() and not old.exists()
    assert live.exists() and other.exists() and mine.exists()
    # nothing else is left behind by the write itself
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["out.mod", live.name, other.name, mine.name])


def test_rewrite_cleans_up_after_a_killed_run_and_says_so(cell, samples, tmp_path, capsys):
    leftover = tmp_path / f".out.mod.{_dead_pid()}-zz00zz00.tmp"
    leftover.write_bytes(b"half a program")
    out = tmp_path / "out.mod"
    assert main(["rewrite", str(samples / "ballbar.mod"), "--model", str(cell["model_path"]),
                 "-o", str(out)]) == 0
    assert not leftover.exists()
    assert str(leftover) in capsys.readouterr().err


def test_a_fresh_leftover_of_unknown_writer_is_kept(tmp_path):
    fresh = tmp_path / ".out.mod.k9x8y7z6.tmp"
    fresh.write_bytes(b"x")
    atomic.write_bytes_atomic(tmp_path / "out.mod", b"new")
    assert fresh.exists()


# ---- 11: one bad entry is one failed row ------------------------------------------------


def test_dangling_symlink_and_loop_are_failed_rows(cell, samples, tmp_path, capsys):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(samples / "ballbar.mod", src / "a.mod")
    shutil.copy(samples / "ballbar.mod", src / "z.mod")
    (src / "dangling.mod").symlink_to(src / "nowhere.mod")
    (src / "loop.mod").symlink_to(src / "loop.mod")
    (src / "notes.txt").symlink_to(src / "missing.txt")
    out = tmp_path / "out"
    status = main(["batch", str(src), str(out), "--model", str(cell["model_path"]), "-j", "1",
                   "--no-progress"])
    assert status == 1
    rows = {r["path"]: r for r in json.loads((out / "rapidfix-batch.json").read_text())
            ["results"]}
    assert {p: r["status"] for p, r in rows.items()} == {
        "a.mod": "ok", "z.mod": "ok", "dangling.mod": "error", "loop.mod": "error",
        "notes.txt": "error"}
    assert "dangling.mod" in rows["dangling.mod"]["message"]
    assert (out / "a.mod").exists() and (out / "z.mod").exists()
    capsys.readouterr()


# ---- 12: Ctrl-C stops a parallel batch at once --------------------------------------------


def ctrl_c_as_at_a_terminal() -> None:
    """In the child: Ctrl-C's default disposition. A test run started in the background
    of a non-interactive shell ignores SIGINT, and a child Python that starts with it
    ignored never raises KeyboardInterrupt (it respects that, as `nohup` expects)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_stops_a_parallel_batch_and_starts_no_new_file(cell, tmp_path):
    src, out = tmp_path / "in", tmp_path / "out"
    src.mkdir()
    text = long_program(2500)
    files = 12
    for k in range(files):
        (src / f"p{k:02d}.mod").write_text(text)
    proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; from rapidfix.cli import main; sys.exit(main())",
         "batch", str(src), str(out), "--model", str(cell["model_path"]), "-j", "2"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=ctrl_c_as_at_a_terminal)
    try:
        while proc.poll() is None and not (out.exists() and list(out.glob("p*.mod"))):
            time.sleep(0.02)  # until the first file is done
        done_at_signal = len(list(out.glob("p*.mod")))
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    written = sorted(out.glob("p*.mod"))
    # the two files in progress may have finished, no other one started
    assert done_at_signal <= len(written) <= done_at_signal + 2 < files
    assert not list(out.glob(".*.tmp"))



def _hang_while_writing(target: str) -> None:
    """A worker stuck in a write that SIGTERM does not end (e.g. in a long C call)."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    atomic._create_temporary(Path(target))
    time.sleep(600)


def test_a_worker_that_does_not_stop_is_killed_and_its_temporary_removed(tmp_path,
                                                                        monkeypatch):
    from concurrent.futures import ProcessPoolExecutor

    from rapidfix.postprocess import batch

    target = tmp_path / "p.mod"
    pool = ProcessPoolExecutor(max_workers=1)
    pool.submit(_hang_while_writing, str(target))
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob(".*.tmp")) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert len(list(tmp_path.glob(".*.tmp"))) == 1
    workers = list(pool._processes.values())
    monkeypatch.setattr(batch, "STOP_WAIT_S", 0.5)
    batch._stop(pool, [target])
    assert not any(w.is_alive() for w in workers)
    assert list(tmp_path.iterdir()) == []

# ---- 14: path tolerance and the true reasons ---------------------------------------------


def test_path_tolerance_below_resolution_is_refused(cell, samples, tmp_path, capsys):
    with pytest.raises(RapidfixError, match=r"0\.001 mm"):
        RewriteOptions(path_tolerance_mm=1e-9)
    out = tmp_path / "o.mod"
    status = main(["rewrite", str(samples / "cell.mod"), "--model", str(cell["model_path"]),
                   "-o", str(out), "--path-tolerance", "1e-9"])
    err = capsys.readouterr().err
    assert status == 1 and "below what the model can resolve" in err and not out.exists()
    RewriteOptions(path_tolerance_mm=0.001)  # the finest accepted


ARC = """MODULE Arc
    PERS tooldata tBar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
    PERS wobjdata wBar:=[FALSE,TRUE,"",[[850,80,450],[0.923879533,0,-0.382683432,0]],
                         [[0,0,0],[1,0,0,0]]];
    CONST robtarget pA:=[[100,0,0],[0,0.258819045,0.965925826,0],[0,0,0,1],EXTAX];
    CONST robtarget pB:=[[50,50,0],[0,0.258819045,0.965925826,0],[0,0,0,1],EXTAX];
    CONST robtarget pC:=[[0,100,0],[0,0.258819045,0.965925826,0],[0,0,0,1],EXTAX];
    PROC main()
        MoveJ pA, v100, fine, tBar\\WObj:=wBar;
        MoveC pB, pC, v100, fine, tBar\\WObj:=wBar;
    ENDPROC
ENDMODULE
""".replace("EXTAX", "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]")


def test_a_kept_move_is_given_its_true_reason(cell, tmp_path, capsys):
    # MoveC through three points on a line: its start is known, its arc is not an arc
    src = tmp_path / "arc.mod"
    src.write_text(ARC)
    assert main(["rewrite", str(src), "--model", str(cell["model_path"]), "-o",
                 str(tmp_path / "o.mod")]) == 0
    out = capsys.readouterr().out
    assert "1 move kept its instruction with a filtered robtarget" in out
    assert "its arc is degenerate" in out and "start not known" not in out


def test_a_move_after_a_call_keeps_the_start_reason(cell, tmp_path, capsys):
    src = tmp_path / "call.mod"
    src.write_text(ARC.replace("MoveJ pA, v100, fine, tBar\\WObj:=wBar;", "Other;")
                   .replace("MoveC pB, pC,", "MoveL pB,").replace(
                       "    ENDPROC\nENDMODULE", "    ENDPROC\n    PROC Other()\n"
                       "        MoveJ pA, v100, fine, tBar\\WObj:=wBar;\n"
                       "    ENDPROC\nENDMODULE"))
    assert main(["rewrite", str(src), "--model", str(cell["model_path"]), "-o",
                 str(tmp_path / "o.mod")]) == 0
    assert "(start not known before run time)" in capsys.readouterr().out


def _worker_signals() -> tuple[bool, object]:
    """In a batch worker: whether Ctrl-C or SIGTERM is held back, and Ctrl-C's handler."""
    held = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    return bool({signal.SIGINT, signal.SIGTERM} & held), signal.getsignal(signal.SIGINT)


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="POSIX signal masks")
def test_workers_are_forked_with_ctrl_c_held_back_and_take_it_once_ready(monkeypatch):
    """Ctrl-C to the process group while a batch worker was being forked raised
    KeyboardInterrupt inside Python's after-fork hooks in the child (a traceback in a CI
    run). The batch now forks with SIGINT and SIGTERM held back; a worker lets them
    through once it ignores Ctrl-C, and the main process gets them after the fork."""
    from concurrent.futures import ProcessPoolExecutor

    from rapidfix.postprocess import batch

    held_at_submit: list[bool] = []
    submit = ProcessPoolExecutor.submit

    def probe(self, fn, *args):  # run the probe in place of each file's job
        held_at_submit.append(signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, []))
        return submit(self, _worker_signals)

    monkeypatch.setattr(ProcessPoolExecutor, "submit", probe)
    results: list[tuple[bool, object]] = []
    jobs = [("a", "b", f"f{k}", None, ()) for k in range(3)]
    batch._run_parallel(jobs, 2, results, None, None)
    assert held_at_submit == [True, True, True]
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])  # let go after
    assert results == [(False, signal.SIG_IGN)] * 3


def test_a_file_waiting_for_a_worker_is_not_begun_once_the_batch_is_stopped(monkeypatch):
    """Each worker has a second file waiting (batch.IN_FLIGHT_PER_WORKER), so it starts
    the next at once; once Ctrl-C has set the stop flag, a worker that takes up a waiting
    file does not begin it."""
    import multiprocessing

    from rapidfix.postprocess import batch

    begun: list[tuple] = []
    monkeypatch.setattr(batch, "_job", lambda job: begun.append(job) or "done")
    stop = multiprocessing.get_context().Event()
    monkeypatch.setattr(batch, "_STOP_FLAG", stop)
    assert batch._job_unless_stopped(("a",)) == "done"
    stop.set()
    assert batch._job_unless_stopped(("b",)) is None
    assert begun == [("a",)]


def test_each_worker_has_a_file_waiting(monkeypatch):
    """Two workers are given four of five files before the first result is awaited."""
    from concurrent.futures import ProcessPoolExecutor

    from rapidfix.postprocess import batch

    submit, wait = ProcessPoolExecutor.submit, batch.wait
    given: list[int] = []
    monkeypatch.setattr(ProcessPoolExecutor, "submit",
                        lambda self, fn, *args: submit(self, _worker_signals))

    def counting_wait(running, **kwargs):
        given.append(len(running))
        return wait(running, **kwargs)

    monkeypatch.setattr(batch, "wait", counting_wait)
    results: list[tuple[bool, object]] = []
    batch._run_parallel([("a", "b", f"f{k}", None, ()) for k in range(5)], 2, results,
                        None, None)
    assert given[0] == 4 and len(results) == 5
