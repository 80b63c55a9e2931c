"""Atomic file output: write to a temporary file beside the target, then rename.

An interrupted run leaves either the old file or the new one, never half of one:

- Ctrl-C and SIGTERM unwind through `write_bytes_atomic`, which removes its
  temporary file (`exit_on_sigterm` does the same for a process that exits at once,
  e.g. a batch worker);
- after SIGKILL or a power cut the temporary file stays. Its name records the
  writer: `.NAME.PID-XXXXXXXX.tmp` beside NAME. The next write of NAME removes such
  leftovers whose writer is no longer running (or that are older than
  STALE_AFTER_S, for a writer on another machine) and says so on stderr.
"""

from __future__ import annotations

import errno
import os
import re
import sys
import time
from pathlib import Path
from typing import Any

#: a leftover temporary file this old is stale whoever wrote it (seconds)
STALE_AFTER_S = 3600.0

#: temporary files being written by this process (removed on SIGTERM)
_IN_PROGRESS: set[str] = set()


def _temp_pattern(name: str) -> re.Pattern[str]:
    """Names of the temporary files of target `name` (8 random characters)."""
    return re.compile(rf"^\.{re.escape(name)}\.(?:(\d+)-)?[A-Za-z0-9_]{{8}}\.tmp$")


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def remove_stale_temporaries(target: str | Path, *, now: float | None = None) -> list[Path]:
    """Remove leftovers of interrupted writes of `target`; returns what was removed."""
    target = Path(target)
    pattern = _temp_pattern(target.name)
    now = time.time() if now is None else now
    removed = []
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.match(entry.name)
        if not match or not entry.is_file(follow_symlinks=False):
            continue
        try:
            age = now - entry.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        pid = int(match[1]) if match[1] else None
        mine = pid == os.getpid() and entry.path in _IN_PROGRESS
        if mine or not (age > STALE_AFTER_S or (pid is not None and not _running(pid))):
            continue
        try:
            os.unlink(entry.path)
        except OSError:
            continue
        removed.append(Path(entry.path))
        print(f"rapidfix: removed {entry.path}, left by an interrupted write",
              file=sys.stderr)
    return removed


def _create_temporary(target: Path) -> tuple[int, str]:
    """Create the temporary file for `target`; returns its descriptor and path.

    The name is registered in `_IN_PROGRESS` before the file exists: a SIGTERM handler
    runs as soon as the call that creates it returns, and must find it to remove it.
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        tmp = os.path.join(os.path.abspath(target.parent),
                           f".{target.name}.{os.getpid()}-{os.urandom(4).hex()}.tmp")
        _IN_PROGRESS.add(tmp)
        try:
            return os.open(tmp, flags, 0o600), tmp
        except FileExistsError:
            _IN_PROGRESS.discard(tmp)
        except BaseException:  # e.g. Ctrl-C raised as the file was made
            try:
                os.unlink(tmp)
            except OSError:
                pass
            _IN_PROGRESS.discard(tmp)
            raise
    raise FileExistsError(errno.EEXIST, "no free name for a temporary file", str(target))


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write `data` to `path` atomically, creating parent folders; return the path."""
    target = Path(path)
    if target.is_dir():  # name the target, not the temporary file os.replace would name
        raise IsADirectoryError(errno.EISDIR, "is a folder, a file name is needed", str(target))
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(target)
    fd, tmp = _create_temporary(target)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        if target.exists():
            os.chmod(tmp, target.stat().st_mode & 0o7777)
        else:
            os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    finally:
        _IN_PROGRESS.discard(tmp)
    return target


def write_text_atomic(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    """Write text atomically with the given encoding and no newline translation."""
    return write_bytes_atomic(path, text.encode(encoding))


def remove_own_temporaries() -> None:
    """Remove the temporary files this process is writing (before an abrupt exit)."""
    for tmp in list(_IN_PROGRESS):
        try:
            os.unlink(tmp)
        except OSError:
            pass
        _IN_PROGRESS.discard(tmp)


def exit_on_sigterm(signum: int, frame: Any) -> None:
    """A SIGTERM handler: remove this process's temporary files and exit (status 143)."""
    remove_own_temporaries()
    os._exit(128 + signum)
