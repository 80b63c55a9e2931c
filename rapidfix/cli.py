"""The `rapidfix` command line: one subcommand per module in rapidfix.commands.

Exit status: 0 success, 1 failure (a user error, printed as one line per
problem), 2 wrong usage, 3 finished with warnings (something was skipped).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from rapidfix import __version__
from rapidfix.exceptions import RapidfixError

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_WARNINGS = 3

# Subcommand modules under rapidfix.commands, in the order `--help` lists them.
COMMANDS: tuple[str, ...] = (
    "demo",
    "check",
    "targets",
    "plan",
    "simulate",
    "import_tracker",
    "iso9283",
    "fit",
    "diagnose",
    "rewrite",
    "batch",
    "upload",
)


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every registered subcommand."""
    parser = argparse.ArgumentParser(
        prog="rapidfix",
        description="Accurate ABB robots without touching the controller.",
    )
    parser.add_argument("--version", action="version", version=f"rapidfix {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the full traceback of an error"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        module = importlib.import_module(f"rapidfix.commands.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit status (also used by the console script)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except RapidfixError as err:
        if args.debug:
            raise
        print(f"rapidfix: error: {err}", file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        print("rapidfix: interrupted", file=sys.stderr)
        return 130
    except OSError as err:
        if args.debug:
            raise
        where = f"{err.filename}: " if getattr(err, "filename", None) else ""
        print(f"rapidfix: error: {where}{err.strerror or err}", file=sys.stderr)
        return EXIT_FAILURE


if __name__ == "__main__":
    sys.exit(main())
