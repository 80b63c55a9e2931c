"""`rapidfix rewrite`: one RAPID program compensated with an error model."""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from rapidfix.commands.robot_options import add_robot_arguments
from rapidfix.exceptions import InvalidOption, RapidfixError, UsageError
from rapidfix.paths import check_output_file

if TYPE_CHECKING:
    from rapidfix.postprocess import RewriteOptions, Skipped


def add_common_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by `rewrite` and `batch`."""
    parser.add_argument("--model", required=True, metavar="MODEL",
                        help="error model file (from `rapidfix fit` or `rapidfix diagnose`)")
    add_robot_arguments(parser, default=None, default_text="the robot the model was made for")
    parser.add_argument("--decls", action="append", default=[], metavar="FILE",
                        help="RAPID file declaring tooldata/wobjdata/robtargets the program "
                        "uses but does not declare (may be repeated)")
    parser.add_argument("--no-task-modules", action="store_true",
                        help="do not read the other modules of a controller task (a file "
                        "in RAPID/TASK<n>/, in a task's PROGMOD/SYSMOD, or listed in a .pgf "
                        "program file) for the data it uses")
    parser.add_argument("--emit", choices=("jointtargets", "robtargets"), default="jointtargets",
                        help="jointtargets: MoveAbsJ to compensated joint targets (default); "
                        "robtargets: keep the instructions, write filtered robtargets")
    parser.add_argument("--path-tolerance", type=float, default=0.1, metavar="MM",
                        help="largest TCP deviation from a MoveL line or MoveC arc allowed "
                        "between points; intermediate points are added (default 0.1 mm)")
    parser.add_argument("--strict", action="store_true",
                        help="fail, writing nothing, when any target cannot be compensated")
    parser.add_argument("--force", action="store_true",
                        help="rewrite a program that is already compensated")
    parser.add_argument("--in-place", action="store_true",
                        help="overwrite the input (a backup is kept beside it)")
    parser.add_argument("--temperature", type=float, metavar="C",
                        help="cell temperature (°C) the program will run at; needed by a "
                        "model with thermal drift (recorded in the header; without it the "
                        "calibration's reference is assumed and the exit status is 3)")
    parser.add_argument("--approach", action="store_true",
                        help="put an approach point before every compensated fine point so "
                        "that each joint with play (a model with backlash) arrives from one "
                        "known side, as machine tools position (recorded in the header)")
    parser.add_argument("--static-external-axes", action="store_true",
                        help="the external axes carry neither the robot nor the work (a "
                        "servo gun, a positioner whose work objects are not coordinated): "
                        "compensate targets whatever their external axis values; without "
                        "it, a target with an external axis anywhere but 0 is left as it "
                        "was, since a track may carry the robot there (recorded in the "
                        "header)")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `rewrite` command."""
    parser = subparsers.add_parser(
        "rewrite",
        help="write a compensated copy of a RAPID program",
        description="Compensate every motion target known before run time with an error "
        "model and write the program back; everything else stays byte-identical. Exit "
        "status 3 when targets were left as they were (listed), 1 on failure.",
    )
    parser.add_argument("program", metavar="PROG", help="RAPID program (.mod, .modx, .prg, .sys)")
    parser.add_argument("-o", "--output", metavar="OUT", help="output file")
    add_common_options(parser)
    parser.add_argument("--all-skipped", action="store_true",
                        help=f"list every move left as it was (by default, past "
                        f"{SKIP_LIST_LIMIT} the first {SKIP_LIST_HEAD} are listed and the "
                        "rest counted by reason)")
    parser.set_defaults(func=run)


#: A program that fails everywhere (written for another work object or robot) can leave
#: tens of thousands of moves as they were: past SKIP_LIST_LIMIT, the first SKIP_LIST_HEAD
#: are listed and the rest counted by the kind of their reason.
SKIP_LIST_LIMIT = 50
SKIP_LIST_HEAD = 20
#: the most kinds of reason, differing only in the moves' own targets, counted apart
NAMED_KINDS = 3
_PARTICULARS = re.compile(r"\[[^\[\]]*\]|\([^()]*\)|(?<![\w.])-?\d+(?:\.\d+)?(?![\w.])")


def reason_kind(reason: str) -> str:
    """A skip reason with its particulars (numbers, bracketed lists, remarks in
    parentheses) shown as '…': what moves skipped for the same cause share."""
    while True:
        kind = _PARTICULARS.sub("…", reason)
        if kind == reason:
            return kind
        reason = kind


# a name (RAPID's letters are ISO 8859-1's), and whether a call's parenthesis follows it
_NAME_IN_LABEL = re.compile(r"(?<![\w.])([^\W\d_]\w*)(\s*\()?")
_WORD = re.compile(r"(?<![\w.])[^\W\d_]\w*")


def _own_names(label: str) -> frozenset[str]:
    """The data names a skipped move's label holds (`MoveL Offs(p7,0,0,10)` -> p7): not
    its instruction, nor the functions it calls."""
    return frozenset(m.group(1) for m in list(_NAME_IN_LABEL.finditer(label))[1:]
                     if m.group(2) is None)


def _without(names: frozenset[str], reason: str) -> str:
    """`reason` with each whole word of `names` shown as '…'."""
    if not any(name in reason for name in names):  # (a substring test spares the words)
        return reason
    return _WORD.sub(lambda m: "…" if m.group() in names else m.group(), reason)


def skipped_lines(skipped: list[Skipped], every: bool = False) -> list[str]:
    """The lines listing skipped moves, reasons in the command's words: every one, or past
    SKIP_LIST_LIMIT the first SKIP_LIST_HEAD and a count per kind of reason for the rest,
    most frequent first. Where more than NAMED_KINDS kinds differ only in the move's own
    target (`p7 is not declared`, `p8 is not declared`, ...: each target of a program
    its own), that name is a particular too, and they are counted as one kind; a tool's
    or a work object's name always stays."""
    if every or len(skipped) <= SKIP_LIST_LIMIT:
        return [str(replace(move, reason=in_cli_words(move.reason))) for move in skipped]
    # kind without the move's own names -> kind as written -> count
    groups: dict[str, dict[str, int]] = {}
    kinds: dict[tuple[str, str], tuple[str, str]] = {}  # (label, reason) -> both kinds
    for move in skipped[SKIP_LIST_HEAD:]:
        both = kinds.get((move.label, move.reason))
        if both is None:
            reason = in_cli_words(move.reason)
            kind = reason_kind(reason)
            without = _without(_own_names(move.label), reason)
            both = kinds[(move.label, move.reason)] = (
                kind if without == reason else reason_kind(without), kind)
        named = groups.setdefault(both[0], {})
        named[both[1]] = named.get(both[1], 0) + 1
    rest: list[tuple[str, int]] = []
    for kind, named in groups.items():
        rest.extend(named.items() if len(named) <= NAMED_KINDS
                    else [(kind, sum(named.values()))])
    counted = sorted(rest, key=lambda item: -item[1])
    head = skipped[:SKIP_LIST_HEAD]
    return [*(str(replace(move, reason=in_cli_words(move.reason))) for move in head),
            f"{len(skipped) - SKIP_LIST_HEAD:,} more moves left as they were, not listed "
            "(--all-skipped lists them):",
            *(f"  {count:,} × {kind}" for kind, count in counted)]


#: How the library's messages name an option -> the command line's flag. The library
#: speaks to a Python caller (`use RewriteOptions(force=True) to compensate it again`), the
#: command line to its user (`use --force …`): the library's notes, warnings, skip reasons
#: and errors (message and hint) are printed through `in_cli_words`.
FLAGS = {
    "RewriteOptions.emit": "--emit",
    "RewriteOptions.path_tolerance_mm": "--path-tolerance",
    "RewriteOptions(strict=True)": "--strict",
    "RewriteOptions(force=True)": "--force",
    "RewriteOptions.temperature_c": "--temperature",
    "RewriteOptions(static_external_axes=True)": "--static-external-axes",
    "Compensator.load(decl_files)": "--decls",
    "BatchSettings(in_place=True)": "--in-place",
}
_LIBRARY_WORDS = re.compile("|".join(map(re.escape, sorted(FLAGS, key=len, reverse=True))))


def in_cli_words(text: str) -> str:
    """A library message with each option it names replaced by the command-line flag."""
    return _LIBRARY_WORDS.sub(lambda found: FLAGS[found.group()], text)


def reword(err: RapidfixError) -> None:
    """Put a library error's message and hint in the command line's words (in place)."""
    err.message = in_cli_words(err.message)
    err.hint = in_cli_words(err.hint) if err.hint else err.hint


def options_from_args(args: argparse.Namespace) -> RewriteOptions:
    """RewriteOptions from parsed command-line arguments; a bad value is refused in the
    command's words (its flag), not the library's (its field name)."""
    from rapidfix.postprocess import RewriteOptions

    if args.approach and args.emit != "jointtargets":
        raise UsageError(f"--approach needs --emit jointtargets (not {args.emit}): approach "
                         "points are joint positions, and a robtarget leaves the joints to "
                         "the controller")
    try:
        return RewriteOptions(
            emit=args.emit,
            path_tolerance_mm=args.path_tolerance,
            strict=args.strict,
            force=args.force,
            temperature_c=args.temperature,
            approach=args.approach,
            static_external_axes=args.static_external_axes,
        )
    except InvalidOption as err:
        flag = FLAGS.get(f"RewriteOptions.{err.option}", err.option)
        raise RapidfixError(f"{flag} {err.detail}") from None


#: a program at least this large (bytes, about 10,000 lines) shows the step its rewrite is
#: at, on a terminal: a million lines take up to a minute
STEP_BAR_FROM_BYTES = 1_000_000


@contextmanager
def step_bar(source: Path) -> Iterator[Callable[[str], None] | None]:
    """A progress callback showing the rewrite's steps on standard error (REWRITE_STEPS),
    or None: not a terminal (no bars in logs), or a program too small to wait for."""
    try:
        large = source.stat().st_size >= STEP_BAR_FROM_BYTES
    except OSError:  # the rewrite reports it
        large = False
    if not (large and sys.stderr.isatty()):
        yield None
        return
    from tqdm import tqdm

    from rapidfix.postprocess import REWRITE_STEPS as STEPS

    with tqdm(total=len(STEPS), initial=1, desc=f"rapidfix rewrite: {STEPS[0]}", leave=False,
              bar_format="{desc} (step {n_fmt} of {total_fmt}, {elapsed})") as bar:
        def progress(step: str) -> None:  # six steps: each one shown as it starts
            bar.n = STEPS.index(step) + 1
            bar.set_description_str(f"rapidfix rewrite: {step}")

        yield progress


def run(args: argparse.Namespace) -> int:
    """Rewrite one program; print the skipped targets and the predicted deviation."""
    from rapidfix.postprocess import (
        Compensator,
        modules_beside,
        rewrite_file,
        unread_task_modules,
        with_task_modules,
    )

    source = Path(args.program)
    if args.in_place:
        if args.output is not None:
            raise UsageError("give either -o OUT or --in-place, not both")
        target = source
    elif args.output is None:
        raise UsageError("no output file given", hint="use -o OUT, or --in-place")
    else:
        target = check_output_file(args.output, inputs=[source])
    options = options_from_args(args)
    unread: list[tuple[str, str]] = []
    try:
        comp = Compensator.load(args.model, args.robot, args.robot_file, args.decls)
        task = None if args.no_task_modules else modules_beside(source)
        if task is not None and task[1]:
            modules = [(str(m), str(m)) for m in task[1]]
            comp = with_task_modules(comp, modules)
            used = len(comp.decl_paths) - len(args.decls)
            if used:
                print(f"declarations also read from {used} other module(s) of its task "
                      f"({task[0]})")
            unread = unread_task_modules(modules)
            for name, why in unread:  # what they declare is unknown to this program
                print(f"rapidfix: warning: {name}: this module of the task is not read for "
                      f"its declarations: {why}", file=sys.stderr)
        with step_bar(source) as progress:
            result = rewrite_file(source, target, comp, options, in_place=args.in_place,
                                  progress=progress)
    except RapidfixError as err:
        reword(err)
        raise
    notes = [in_cli_words(note) for note in result.notes]
    for line in replace(result, notes=notes).report_lines():
        print(line)
    for line in skipped_lines(result.skipped, args.all_skipped):
        print(f"rapidfix: warning: {line}", file=sys.stderr)
    for warning in result.warnings:
        print(f"rapidfix: warning: {in_cli_words(warning)}", file=sys.stderr)
    if result.skipped and options.strict:
        print(f"rapidfix: error: {len(result.skipped)} target(s) cannot be compensated "
              "(--strict): nothing written", file=sys.stderr)
        return 1
    return 3 if result.skipped or result.warnings or unread else 0
