"""`rapidfix targets FILE`: list every target with its value, or why it is not static."""

from __future__ import annotations

import argparse
import csv
import io
import json
import sys

from rapidfix.rapid import format_value, load_program, target_rows

_COLUMNS = ("name", "line", "column", "kind", "source", "static", "value", "reason")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `targets` subcommand."""
    parser = subparsers.add_parser(
        "targets",
        help="list the targets of a RAPID program (CSV or JSON)",
        description="List every robtarget and jointtarget: declarations and the inline, "
        "Offs and RelTool targets of motion instructions, with their values or the "
        "reason they are known only at run time.",
    )
    parser.add_argument("file", metavar="FILE", help="RAPID file")
    parser.add_argument("--format", choices=("csv", "json"), default="csv",
                        help="output format (default: csv)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the target table of one file to standard output."""
    program = load_program(args.file)
    rows = target_rows(program)
    if args.format == "json":
        records = [{
            "name": r.name, "line": r.line, "column": r.column, "kind": r.kind,
            "source": r.source, "static": r.static, "value": r.value, "reason": r.reason,
        } for r in rows]
        json.dump({"file": args.file, "targets": records}, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(_COLUMNS)
    for r in rows:
        value = "" if r.value is None else format_value(r.value, decimals=9)
        writer.writerow([r.name, r.line, r.column, r.kind, r.source,
                         "yes" if r.static else "no", value, r.reason or ""])
    sys.stdout.write(out.getvalue())
    return 0
