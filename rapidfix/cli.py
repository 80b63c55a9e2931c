"""The `rapidfix` command line: one subcommand per module in rapidfix.commands.

Exit status: 0 success, 1 failure (a user error, printed as one line per
problem), 2 wrong usage, 3 finished with warnings (something was skipped).

Every Python warning raised while a command runs is printed once, as
`rapidfix: warning: …`, and turns a successful exit status into 3. SIGTERM
unwinds like Ctrl-C (temporary files are removed on the way out) and exits 143.
"""

from __future__ import annotations

import _thread
import argparse
import gc
import importlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from rapidfix.exceptions import RapidfixError, UsageError

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_WARNINGS = 3
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143

# Subcommand modules under rapidfix.commands, in the order `--help` lists them: the
# word that runs each and the line `rapidfix --help` shows for it, the same as the
# module's own register() gives (tests/cli/test_start_up.py checks they agree). Only
# the module of the command being run is imported: `rapidfix --help` and a light
# command do not pay for the imports of the heavy ones.
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("demo", "run the whole loop on a built-in virtual robot"),
    "check": ("check", "parse RAPID programs and report syntax errors"),
    "targets": ("targets", "list the targets of a RAPID program (CSV or JSON)"),
    "plan": ("plan", "write the RAPID measurement program and pose table of a tracker campaign"),
    "simulate": ("simulate", "make a measurement set from a virtual robot with known errors"),
    "import_tracker": ("import", "turn a laser tracker's export into the measurement files"),
    "iso9283": ("iso9283",
                "pose and distance accuracy/repeatability (ISO 9283) of a measured cube run"),
    "fit": ("fit", "fit a joint motion error model from joint sweeps"),
    "diagnose": ("diagnose", "trace the residual error to a missing physical effect and add it"),
    "rewrite": ("rewrite", "write a compensated copy of a RAPID program"),
    "batch": ("batch", "compensate every RAPID program in a folder tree"),
    "upload": ("upload", "send a program to the controller over a serial link"),
}

EXIT_STATUS_EPILOG = ("exit status: 0 success, 1 failure, 2 wrong usage, "
                      "3 finished with warnings (printed as 'rapidfix: warning: …')")


class Terminated(BaseException):
    """Raised in the main thread on SIGTERM, so the command unwinds like on Ctrl-C."""


class _VersionAction(argparse.Action):
    """`--version`, reading the installed version only when asked."""

    def __init__(self, option_strings: list[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        from rapidfix import __version__

        print(f"rapidfix {__version__}")
        parser.exit()


def _command_in(argv: Sequence[str] | None) -> str | None:
    """The module of the command `argv` runs (its first word that is not an option)."""
    word = next((a for a in argv or () if not a.startswith("-")), None)
    return next((module for module, (name, _) in COMMANDS.items() if name == word), None)


def build_parser(argv: Sequence[str] | None = None, every: bool = False
                 ) -> argparse.ArgumentParser:
    """The top-level parser. The command `argv` runs (or, with `every`, each command) is
    registered by its module; the others are only listed, with their one-line help."""
    parser = argparse.ArgumentParser(
        prog="rapidfix",
        description="Accurate ABB robots without touching the controller.",
        epilog=EXIT_STATUS_EPILOG,
    )
    parser.add_argument("--version", action=_VersionAction,
                        help="show program's version number and exit")
    parser.add_argument(
        "--debug", action="store_true", help="show the full traceback of an error"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    chosen = _command_in(argv)
    for module, (name, summary) in COMMANDS.items():
        if every or module == chosen:
            importlib.import_module(f"rapidfix.commands.{module}").register(sub)
        else:
            sub.add_parser(name, help=summary, add_help=False)
    return parser


@contextmanager
def user_warnings(debug: bool = False) -> Iterator[list[str]]:
    """Print every user warning once as `rapidfix: warning: …`; yields the messages printed.

    User warnings are UserWarning subclasses (a joint clamped to the model's range,
    an ignored setup key, …). Others — numpy's floating-point RuntimeWarnings, a
    library's DeprecationWarning — are internal and shown only with `--debug`.
    """
    printed: list[str] = []
    original = warnings.showwarning

    def show(message: Any, category: type[Warning], filename: str, lineno: int,
             file: Any = None, line: str | None = None) -> None:
        if not issubclass(category, UserWarning):
            if debug:
                original(message, category, filename, lineno, file, line)
            return
        text = str(message)
        if text not in printed:
            printed.append(text)
            print(f"rapidfix: warning: {text}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("always", UserWarning)
        warnings.showwarning = show
        yield printed


#: how long after a signal lost in a callback it is delivered again (the hook returns in
#: microseconds)
REDELIVER_S = 0.01


def _raise_terminated(signum: int, frame: Any) -> None:
    raise Terminated()


@contextmanager
def signals_unwind() -> Iterator[None]:
    """SIGTERM raises Terminated in the main thread (Ctrl-C raises KeyboardInterrupt).

    A signal's handler runs wherever the main thread is, and where that is a callback
    Python calls for itself (a weak reference's, the import system's, a `__del__`), the
    exception cannot go up: Python prints it as "Exception ignored" with a traceback
    and goes on. The hook for those (`sys.unraisablehook`) delivers the signal again,
    silently, a moment later (from another thread: in the hook it would be lost too),
    to whatever the main thread runs then."""
    try:
        previous = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread (e.g. called from a test's thread)
        yield
        return
    hook = sys.unraisablehook

    def again(unraisable: Any) -> None:
        caught = unraisable.exc_value
        if isinstance(caught, (Terminated, KeyboardInterrupt)):
            signum = signal.SIGTERM if isinstance(caught, Terminated) else signal.SIGINT
            later = threading.Timer(REDELIVER_S, _thread.interrupt_main, args=(signum,))
            later.daemon = True
            later.start()
            return
        hook(unraisable)

    sys.unraisablehook = again
    try:
        yield
    finally:
        sys.unraisablehook = hook
        signal.signal(signal.SIGTERM, previous)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit status (`console_main` exits with it)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    with signals_unwind():
        return _main(argv)


def _main(argv: list[str]) -> int:
    debug = "--debug" in argv
    try:
        args = build_parser(argv).parse_args(argv)
        with user_warnings(args.debug) as printed:
            status = int(args.func(args) or 0)
        return EXIT_WARNINGS if status == EXIT_OK and printed else status
    except KeyboardInterrupt:
        print("rapidfix: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print("rapidfix: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except Exception as err:
        if debug:
            raise
        status, line = _error_line(err)
        print(line, file=sys.stderr)
        return status


def _error_line(err: Exception) -> tuple[int, str]:
    """The exit status and the one line an error is reported with."""
    if isinstance(err, UsageError):
        return EXIT_USAGE, f"rapidfix: error: {err}"
    if isinstance(err, RapidfixError):
        return EXIT_FAILURE, f"rapidfix: error: {err}"
    if isinstance(err, OSError):
        where = f"{err.filename}: " if getattr(err, "filename", None) else ""
        return EXIT_FAILURE, f"rapidfix: error: {where}{err.strerror or err}"
    if isinstance(err, MemoryError):
        return EXIT_FAILURE, "rapidfix: error: out of memory"
    # a bug: one line, the traceback with --debug
    return EXIT_FAILURE, (f"rapidfix: internal error: {type(err).__name__}: {err} "
                          "(run with --debug for the traceback, and please report it)")


def prepare_process() -> None:
    """What the console script sets before anything imports numpy: no transparent huge
    pages for numpy's large arrays (NumPy's own switch NUMPY_MADVISE_HUGEPAGE, unless
    the environment sets it). A rewrite's arrays are made once and read a few times,
    and the kernel zeroing 2 MB pages cost more system time than the TLB misses they
    save (0.35 s of a 200,000-line inline rewrite on a 2-core VM)."""
    os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")


def console_main() -> None:
    """The console script (and `python -m rapidfix.cli`): `prepare_process`, `main`, then
    exit with its status.

    What the run left (after a large rewrite: numba's and LLVM's objects) is frozen
    before the exit, so the interpreter's last full collection does not walk it all
    once more (0.15 s). Every file is written and closed by then; atexit handlers and
    finalizers still run.
    """
    prepare_process()
    try:
        status = main()
    except Terminated:  # (the signal came while `main` was putting its handler back)
        status = EXIT_TERMINATED
    except KeyboardInterrupt:
        status = EXIT_INTERRUPTED
    gc.freeze()
    sys.exit(status)


if __name__ == "__main__":
    console_main()
