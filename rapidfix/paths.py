"""Checks of the paths a command was given, made before any work is done.

A command that will fail on its output (a folder where a file is needed, a file
where a folder is needed, an input it would overwrite) or on a missing input must
say so at once, in one line naming the path, and not after minutes of work or
with the name of an internal temporary file.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from rapidfix.exceptions import OutputExistsError, RapidfixError


def _blocking_parent(path: Path) -> Path | None:
    """The first existing ancestor of `path` that is not a folder, if any."""
    for parent in path.parents:
        if parent.exists():
            return None if parent.is_dir() else parent
    return None


def check_input_file(path: str | Path, what: str = "input file") -> Path:
    """An existing, readable regular file (symlinks followed)."""
    p = Path(path)
    if not p.exists():
        raise RapidfixError(f"{what} not found", file=p)
    if p.is_dir():
        raise RapidfixError(f"is a folder, {what} expected", file=p)
    if not os.access(p, os.R_OK):
        raise RapidfixError(f"{what} is not readable", file=p)
    return p


def check_output_file(path: str | Path, *, inputs: Iterable[str | Path] = (),
                      what: str = "output file", overwrite: bool = True) -> Path:
    """A file that can be written: not a folder, not under a file, not one of `inputs`."""
    p = Path(path)
    if p.is_dir():
        raise OutputExistsError(f"is a folder; the {what} must be a file name", file=p)
    blocking = _blocking_parent(p)
    if blocking is not None:
        raise OutputExistsError(f"is a file, not a folder; cannot write the {what} "
                                f"{p.name} into it", file=blocking)
    if p.exists():
        for other in inputs:
            q = Path(other)
            if q.exists() and q.resolve() == p.resolve():
                raise OutputExistsError(f"the {what} would overwrite the input", file=p,
                                        hint="choose another name")
        if not overwrite:
            raise OutputExistsError(f"the {what} already exists", file=p,
                                    hint="choose another name or pass --force")
    return p


def check_output_dir(path: str | Path, what: str = "output folder") -> Path:
    """A folder that exists or can be made: not an existing file, not under a file."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise OutputExistsError(f"exists and is not a folder; the {what} must be a folder",
                                file=p)
    blocking = _blocking_parent(p)
    if blocking is not None:
        raise OutputExistsError(f"is a file, not a folder; cannot make the {what} {p} "
                                "under it", file=blocking)
    return p
