"""Interrupted runs (issue #15 acceptance): `rewrite` and `batch` killed with SIGINT,
SIGTERM or SIGKILL at a random (seeded) moment leave each output either complete under
its real name or absent; temporary files left by SIGKILL are removed by the next run."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .long_program import long_program
from .test_hard_stops import ctrl_c_as_at_a_terminal

CLI = [sys.executable, "-c", "import sys; from rapidfix.cli import main; sys.exit(main())"]
MOVES = 4000
BATCH_FILES = 4
EXPECTED_STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGKILL: -signal.SIGKILL}


def _env() -> dict[str, str]:
    return dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")


@pytest.fixture(scope="module")
def program_and_reference(cell, tmp_path_factory):
    """A long program and its uninterrupted rewrite (the only complete output)."""
    folder = tmp_path_factory.mktemp("signals")
    src = folder / "long.mod"
    src.write_text(long_program(MOVES))
    ref = folder / "reference.mod"
    start = time.monotonic()
    done = subprocess.run([*CLI, "rewrite", str(src), "--model", str(cell["model_path"]),
                           "-o", str(ref)], capture_output=True, text=True, env=_env(),
                          timeout=300)
    assert done.returncode == 0, done.stderr
    return src, ref.read_bytes(), time.monotonic() - start


def _catches_sigterm(pid: int) -> bool:
    """Whether `pid` has a SIGTERM handler installed (Linux /proc: the SigCgt mask). rapidfix's
    `main` installs one when it starts and puts the old one back when it ends, so this tells
    the moment the command runs, whatever the interpreter's start-up took."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = next((line.split()[1] for line in status.splitlines()
                 if line.startswith("SigCgt:")), "0")
    return bool(int(mask, 16) >> (signal.SIGTERM - 1) & 1)


def _children(pid: int) -> list[int]:
    """The child processes of `pid` (Linux /proc), [] where unknown."""
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]


def _gone(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state in ("Z", "X")


def _temporaries(folder: Path) -> list[Path]:
    return sorted(folder.rglob(".*.tmp"))


def _run_and_signal(args: list[str], sig: signal.Signals, delay: float) -> tuple[int, str]:
    """Start `rapidfix ARGS`, wait until its `main` runs, then `delay` s more, and signal it."""
    proc = subprocess.Popen([*CLI, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=_env(), preexec_fn=ctrl_c_as_at_a_terminal)
    started = time.monotonic() + 120
    while proc.poll() is None and not _catches_sigterm(proc.pid) and time.monotonic() < started:
        time.sleep(0.002)
    end = time.monotonic() + delay
    while proc.poll() is None and time.monotonic() < end:
        time.sleep(0.01)
    workers = _children(proc.pid)
    if proc.poll() is None:
        proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    deadline = time.monotonic() + 30  # orphaned workers stop by themselves
    while not all(_gone(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert all(_gone(w) for w in workers), "batch workers outlived the killed batch"
    return proc.returncode, err


@pytest.mark.slow
@pytest.mark.parametrize("command", ["rewrite", "batch"])
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL],
                         ids=["SIGINT", "SIGTERM", "SIGKILL"])
def test_interrupted_run_leaves_complete_output_or_nothing(cell, program_and_reference,
                                                           tmp_path, command, sig):
    src, reference, duration = program_and_reference
    rng = random.Random(f"{command}-{sig.name}")
    # a moment while it works, counted from when rapidfix's main runs (before that Python
    # itself answers Ctrl-C), scaled by how long the uninterrupted rewrite took here
    delay = rng.uniform(0.1, 0.7) * duration
    model = str(cell["model_path"])
    if command == "rewrite":
        out_dir = tmp_path / "out"
        out_dir.mkdir()
        outputs = [out_dir / "long.mod"]
        args = ["rewrite", str(src), "--model", model, "-o", str(outputs[0])]
    else:
        in_dir, out_dir = tmp_path / "in", tmp_path / "out"
        in_dir.mkdir()
        for k in range(BATCH_FILES):
            (in_dir / f"p{k}.mod").write_bytes(src.read_bytes())
        outputs = [out_dir / f"p{k}.mod" for k in range(BATCH_FILES)]
        args = ["batch", str(in_dir), str(out_dir), "--model", model, "-j", "2",
                "--no-progress"]
    status, err = _run_and_signal(args, sig, delay)
    # -sig: the signal came as the finished run was exiting, after its handler was put
    # back (a shell shows it as 128 + sig, like the handled exit): all outputs are done
    assert status in (0, EXPECTED_STATUS[sig], -sig), err
    if status == -sig and sig != signal.SIGKILL:
        assert all(out.exists() for out in outputs), err
    assert "Traceback" not in err, err
    for out in outputs:  # complete under its real name, or nothing
        assert not out.exists() or out.read_bytes() == reference, (out, status, err)
    if sig != signal.SIGKILL:
        assert _temporaries(out_dir) == [], (status, err)
    # the next run finishes the job and leaves no temporary file behind
    done = subprocess.run([*CLI, *args], capture_output=True, text=True, env=_env(),
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert all(out.read_bytes() == reference for out in outputs)
    assert _temporaries(out_dir) == []


KILLED_IN_WRITE = """
import os, sys, time
from rapidfix import atomic
def slow_fsync(fd):
    print("writing", flush=True)
    time.sleep(60)
atomic.os.fsync = slow_fsync
atomic.write_bytes_atomic(sys.argv[1], b"half" * 1000)
"""


def test_sigkill_in_the_middle_of_a_write_is_cleaned_by_the_next_run(cell, samples, tmp_path):
    out = tmp_path / "out.mod"
    proc = subprocess.Popen([sys.executable, "-c", KILLED_IN_WRITE, str(out)],
                            stdout=subprocess.PIPE, text=True, env=_env())
    assert proc.stdout.readline().strip() == "writing"
    proc.kill()
    proc.wait()
    left = _temporaries(tmp_path)
    assert len(left) == 1 and not out.exists()  # SIGKILL leaves the temporary file
    done = subprocess.run([*CLI, "rewrite", str(samples / "ballbar.mod"), "--model",
                           str(cell["model_path"]), "-o", str(out)], capture_output=True,
                          text=True, env=_env(), timeout=300)
    assert done.returncode == 0, done.stderr
    assert _temporaries(tmp_path) == [] and out.exists()
    assert f"removed {left[0]}" in done.stderr


TERMINATED_IN_WRITE = """
import signal, sys, time
from rapidfix import atomic, cli
def slow_fsync(fd):
    print("writing", flush=True)
    time.sleep(60)
atomic.os.fsync = slow_fsync
handler = cli._raise_terminated if sys.argv[2] == "main" else atomic.exit_on_sigterm
signal.signal(signal.SIGTERM, handler)
try:
    atomic.write_bytes_atomic(sys.argv[1], b"half" * 1000)
except cli.Terminated:
    sys.exit(143)
"""


@pytest.mark.parametrize("process", ["main", "worker"])
def test_sigterm_in_the_middle_of_a_write_removes_the_temporary_file(tmp_path, process):
    out = tmp_path / "out.mod"
    proc = subprocess.Popen([sys.executable, "-c", TERMINATED_IN_WRITE, str(out), process],
                            stdout=subprocess.PIPE, text=True, env=_env())
    assert proc.stdout.readline().strip() == "writing"
    assert len(_temporaries(tmp_path)) == 1
    proc.terminate()
    assert proc.wait(timeout=60) == 143
    assert _temporaries(tmp_path) == [] and not out.exists()


def _stopped_as_the_file_is_made(stop):
    """An `os.open` that makes the file, then runs `stop` as a signal handler would:
    as soon as the call returns, before the writer holds the name."""
    real_open = os.open

    def open_then_stop(path, flags, mode=0o777, **kwargs):
        fd = real_open(path, flags, mode, **kwargs)
        if str(path).endswith(".tmp"):
            os.close(fd)
            stop()
        return fd

    return open_then_stop


def test_sigterm_as_the_temporary_file_is_made_leaves_nothing(tmp_path, monkeypatch):
    from rapidfix import atomic

    def exit_on_sigterm():  # what the worker's handler does, without leaving pytest
        atomic.remove_own_temporaries()
        raise SystemExit(143)

    monkeypatch.setattr(atomic.os, "open", _stopped_as_the_file_is_made(exit_on_sigterm))
    with pytest.raises(SystemExit):
        atomic.write_bytes_atomic(tmp_path / "out.mod", b"data")
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_as_the_temporary_file_is_made_leaves_nothing(tmp_path, monkeypatch):
    from rapidfix import atomic

    def ctrl_c():
        raise KeyboardInterrupt

    monkeypatch.setattr(atomic.os, "open", _stopped_as_the_file_is_made(ctrl_c))
    with pytest.raises(KeyboardInterrupt):
        atomic.write_bytes_atomic(tmp_path / "out.mod", b"data")
    assert list(tmp_path.iterdir()) == [] and not atomic._IN_PROGRESS
