"""`rapidfix check FILE...`: parse RAPID files and report every problem as file:line:col."""

from __future__ import annotations

import argparse
import sys

from rapidfix.exceptions import RapidfixError
from rapidfix.rapid import Program, load_program, placeholders_in


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `check` subcommand."""
    parser = subparsers.add_parser(
        "check",
        help="parse RAPID programs and report syntax errors",
        description="Parse each RAPID file (.mod, .modx, .prg, .sys) and report problems "
        "as file:line:col. Every file is checked even when an earlier one fails; "
        "the exit status is 1 if any failed.",
    )
    parser.add_argument("files", nargs="+", metavar="FILE", help="RAPID files to check")
    parser.add_argument("-q", "--quiet", action="store_true", help="print only problems")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Check every file; 0 when all parse, 1 otherwise."""
    failed = 0
    for name in args.files:
        try:
            program = load_program(name)
        except RapidfixError as err:
            failed += 1
            print(str(err), file=sys.stderr)
            continue
        except OSError as err:
            failed += 1
            print(f"{name}: {err.strerror or err}", file=sys.stderr)
            continue
        if not args.quiet:
            modules = ", ".join(m.name for m in program.modules)
            print(f"{name}: ok ({program.source.line_count} lines, module {modules}, "
                  f"{len(program.declarations)} declarations, "
                  f"{len(program.motions)} motion instructions{_placeholders(program)})")
    if len(args.files) > 1 and not args.quiet:
        print(f"{len(args.files) - failed} of {len(args.files)} files parsed")
    return 1 if failed else 0


def _placeholders(program: Program) -> str:
    """', N placeholders (code not yet written, the first <SMT> at 12:5)', or ''.

    RobotStudio's placeholders are RAPID (the controller loads the program) but
    the program stops with an error where it meets one: say so.
    """
    found = placeholders_in(program.text)
    if not found:
        return ""
    offset, text = found[0]
    where = program.span(offset, offset + len(text))
    count = f"{len(found)} placeholder{'s' if len(found) > 1 else ''}"
    return f", {count} (code not yet written, the first {text} at {where.line}:{where.column})"
