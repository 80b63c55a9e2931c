"""The modules of one controller task in a batch, which see each other's data.

A RobotStudio or controller backup keeps each task's modules under
`RAPID/TASK<n>/` (`PROGMOD/*.mod`, `SYSMOD/*.sys`); a task's folder saved on its
own holds the same `PROGMOD` and `SYSMOD` folders; a saved program is a folder
whose `.pgf` file lists its modules. The controller loads them
together, so a program module uses the tools, work objects and targets another
module of its task declares (`CalibData.sys`, `user.sys`, ...). A batch over such
a tree gives each file the other modules of its task as declaration files, as
`Compensator.load(decl_files)` would; a folder outside that layout is a set of
unrelated programs and gets nothing (one program must not take another's `tGripper`).
"""

from __future__ import annotations

import re
import shutil
import tempfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path, PurePath

from rapidfix.exceptions import RapidfixError
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.header import read_header

_TASK_DIR = re.compile(r"TASK\d+", re.IGNORECASE)
_MODULE_DIRS = frozenset({"PROGMOD", "SYSMOD"})
#: the file kinds that hold RAPID modules (and that a batch rewrites)
RAPID_SUFFIXES = (".mod", ".modx", ".prg", ".sys")


def is_rapid(path: PurePath) -> bool:
    """True for the file kinds that hold RAPID modules (and that a batch rewrites)."""
    return path.suffix.lower() in RAPID_SUFFIXES


def task_folder(rel: PurePath) -> PurePath | None:
    """The task folder of a module file: the folder above the `PROGMOD` or `SYSMOD`
    folder it lies in, or the `RAPID/TASK<n>` folder it lies in itself; None for a file
    anywhere else (a task's modules lie there, not in folders further down)."""
    parts = rel.parts[:-1]
    if parts and parts[-1].upper() in _MODULE_DIRS:
        return PurePath(*parts[:-1])
    if len(parts) >= 2 and _TASK_DIR.fullmatch(parts[-1]) and parts[-2].upper() == "RAPID":
        return PurePath(*parts)
    return None


def task_neighbours(files: Sequence[PurePath], root: Path | None = None
                    ) -> dict[PurePath, tuple[PurePath, ...]]:
    """For each RAPID file of a task: the other RAPID files of that task, sorted (the
    order fixes the declarations' hash in the output's header). `files` are relative to
    `root`; with `root`, the `.pgf` program files among them are read too, each naming
    the modules of one program in its folder."""
    groups: dict[object, set[PurePath]] = {}
    for rel in files:
        folder = task_folder(rel)
        if folder is not None and is_rapid(rel):
            groups.setdefault(folder, set()).add(rel)
    if root is not None:
        present = {(rel.parent, rel.name.lower()): rel for rel in files
                   if is_rapid(rel)}
        for rel in files:
            if rel.suffix.lower() == ".pgf":
                listed = {present.get((rel.parent, name.lower()))
                          for name in program_modules(root / rel)}
                groups[rel] = listed - {None}
    out: dict[PurePath, set[PurePath]] = {}
    for group in groups.values():
        for rel in group:
            out.setdefault(rel, set()).update(group - {rel})
    return {rel: tuple(sorted(others)) for rel, others in out.items() if others}


#: a program file larger than this is not a program file
_PGF_LIMIT = 1 << 20


def program_modules(pgf: Path) -> list[str]:
    """The module file names a `.pgf` program file lists (`<Module>Main.mod</Module>`),
    or none when it cannot be read as one."""
    import xml.etree.ElementTree as ET

    try:
        if pgf.stat().st_size > _PGF_LIMIT:
            return []
        tree = ET.parse(pgf)
    except (OSError, ET.ParseError):
        return []
    names = [(node.text or "").strip() for node in tree.getroot().iter()
             if node.tag.lower() == "module"]
    return [PurePath(n.replace("\\", "/")).name for n in names if n]


def modules_beside(path: Path) -> tuple[Path, list[Path]] | None:
    """For one program file: its task folder and the task's other RAPID modules, or None
    outside a task. Only where the controller keeps a task's modules is looked at (the
    task folder itself for `RAPID/TASK<n>`, and its `PROGMOD` and `SYSMOD`), not every
    folder below it; outside a task folder, the modules a `.pgf` program file of the
    file's folder lists with it."""
    real = Path(path).resolve()
    folder = task_folder(PurePath(real))
    if folder is None:
        return _program_beside(real)
    task = Path(folder)
    try:
        places = [task, *(d for d in task.iterdir()
                          if d.is_dir() and d.name.upper() in _MODULE_DIRS)]
        modules = sorted(f for place in places for f in place.iterdir()
                         if f.is_file() and is_rapid(f) and f != real
                         and not (f.name.startswith(".") and f.name.endswith(".tmp"))
                         and task_folder(PurePath(f)) == folder)
    except OSError:  # a folder that cannot be listed lends nothing
        return task, []
    return task, modules


def _program_beside(real: Path) -> tuple[Path, list[Path]] | None:
    """The modules listed with `real` in a `.pgf` program file of its folder, or None."""
    try:
        beside = [f for f in real.parent.iterdir() if f.is_file()]
    except OSError:
        return None
    name = real.name.lower()
    modules: set[Path] = set()
    for pgf in sorted(f for f in beside if f.suffix.lower() == ".pgf"):
        listed = {n.lower() for n in program_modules(pgf)}
        if name in listed:
            modules.update(f for f in beside if f.name.lower() in listed and f != real
                           and is_rapid(f))
    return (real.parent, sorted(modules)) if modules else None


@contextmanager
def task_snapshot(root: Path, neighbours: dict[PurePath, tuple[PurePath, ...]],
                  in_place: bool) -> Iterator[Callable[[PurePath], str]]:
    """Where the jobs read each task module from: the input itself, or, when the batch
    rewrites its inputs in place, a copy taken before any job starts (a module another
    worker has meanwhile rewritten must not lend its compensated targets to a second
    compensation). The copies go when the batch ends."""
    modules = sorted({m for group in neighbours.values() for m in group})
    if not in_place or not modules:
        yield lambda rel: str(root / rel)
        return
    with tempfile.TemporaryDirectory(prefix="rapidfix-task-") as tmp:
        for rel in modules:
            copy = Path(tmp) / rel
            copy.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(root / rel, copy)
        yield lambda rel: str(Path(tmp) / rel)


#: parsed task modules per worker process: (file read, size, mtime) -> program, or why
#: the module is not used (see `_read`)
_PARSED: dict[tuple[str, int, int], object] = {}


def _read(name: str, read_from: str) -> object:
    """The module's program, or why it is not used (a str): it cannot be read, it does
    not parse (its own job reports why), or it carries a compensated program's header:
    its targets may already be compensated, and a second compensation through them
    would be wrong without a word."""
    from rapidfix.rapid import parse_program

    try:
        stat = Path(read_from).stat()
    except OSError as err:
        return f"cannot be read ({err.strerror or err})"
    key = (read_from, stat.st_size, stat.st_mtime_ns)
    if key not in _PARSED:
        try:
            data = Path(read_from).read_bytes()
            if read_header(data.decode("latin-1")) is not None:
                _PARSED[key] = "it is a compensated program"
            else:
                _PARSED[key] = parse_program(data, name)
        except OSError as err:
            _PARSED[key] = f"cannot be read ({err.strerror or err})"
        except RapidfixError as err:
            where = (f"line {err.line}" if err.column is None
                     else f"line {err.line}, column {err.column}") if err.line else ""
            _PARSED[key] = f"it does not parse ({where}{': ' if where else ''}{err.message})"
    return _PARSED[key]


def unread_task_modules(modules: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """(name, why) of each module `with_task_modules` leaves out, in the same order."""
    return [(name, found) for name, read_from in modules
            if isinstance(found := _read(name, read_from), str)]


def with_task_modules(comp: Compensator, modules: Sequence[tuple[str, str]]) -> Compensator:
    """`comp` with the task's other modules (those that parse) after its declaration
    files; each module is (its name in messages, the file to read it from: the input,
    or a copy taken before an in-place batch rewrites it)."""
    programs, used = [], []
    for name, read_from in modules:
        program = _read(name, read_from)
        if not isinstance(program, str):
            programs.append(program)
            used.append(name)
    if not programs:
        return comp
    return replace(comp, decls=[*comp.decls, *programs], decl_paths=[*comp.decl_paths, *used])


__all__ = ["RAPID_SUFFIXES", "is_rapid", "modules_beside", "program_modules", "task_folder",
           "task_neighbours", "task_snapshot", "unread_task_modules",
           "with_task_modules"]
