"""`rapidfix check FILE...`: parse RAPID files and report every problem as file:line:col."""

from __future__ import annotations

import argparse
import sys

from rapidfix.exceptions import RapidfixError
from rapidfix.rapid import load_program


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
            print(f"{name}: ok ({len(program.text.splitlines())} lines, module {modules}, "
                  f"{len(program.declarations)} declarations, "
                  f"{len(program.motions)} motion instructions)")
    if len(args.files) > 1 and not args.quiet:
        print(f"{len(args.files) - failed} of {len(args.files)} files parsed")
    return 1 if failed else 0
