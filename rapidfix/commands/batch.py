"""`rapidfix batch`: every RAPID program in a folder tree compensated, in parallel."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from rapidfix.commands.rewrite import (
    add_common_options,
    in_cli_words,
    options_from_args,
    reword,
)
from rapidfix.exceptions import RapidfixError, UsageError
from rapidfix.paths import check_output_dir, check_output_file


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `batch` command."""
    parser = subparsers.add_parser(
        "batch",
        help="compensate every RAPID program in a folder tree",
        description="Rewrite every .mod/.modx/.prg/.sys file under IN_DIR into the same "
        "place under OUT_DIR (other files are copied), in parallel. Files already up to "
        "date are skipped. Exit status 1 when a file failed, 3 when targets were skipped.",
    )
    parser.add_argument("in_dir", metavar="IN_DIR", help="folder of RAPID programs")
    parser.add_argument("out_dir", metavar="OUT_DIR", nargs="?",
                        help="output folder (not needed with --in-place)")
    add_common_options(parser)
    parser.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                        help=f"worker processes (default: all {os.cpu_count() or 1} cores)")
    parser.add_argument("--summary", metavar="FILE",
                        help="JSON summary file (default: OUT_DIR/rapidfix-batch.json)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the batch, print the table, write the JSON summary."""
    from rapidfix.postprocess import BatchSettings, run_batch, write_summary

    if args.out_dir is None and not args.in_place:
        raise UsageError("an output folder OUT_DIR is needed unless --in-place is given")
    if args.out_dir is not None and args.in_place:
        raise UsageError("give either OUT_DIR or --in-place, not both")
    if args.out_dir is not None:
        check_output_dir(args.out_dir)
    if args.summary:
        check_output_file(args.summary, what="summary file")
    settings = BatchSettings(
        model_path=str(args.model),
        robot=args.robot,
        robot_file=args.robot_file,
        decl_files=tuple(args.decls),
        options=options_from_args(args),
        in_place=args.in_place,
        task_modules=not args.no_task_modules,
    )
    try:
        summary = run_batch(args.in_dir, args.out_dir, settings, workers=args.jobs,
                            progress=not args.no_progress)
    except RapidfixError as err:
        reword(err)
        raise
    for outcome in summary.files:  # the table and the summary file in the command's words
        outcome.message = in_cli_words(outcome.message)
        outcome.skipped = [in_cli_words(line) for line in outcome.skipped]
        outcome.warnings = [in_cli_words(line) for line in outcome.warnings]
    print(summary.table())
    totals = summary.to_dict()
    worst = totals["worst_predicted_mm"]
    print(
        f"{totals['files']} files: {totals['rewritten']} rewritten "
        f"({totals['with_warnings']} with warnings), {totals['errors']} errors, "
        f"{totals['up_to_date']} up to date, {totals['copied']} copied; "
        f"{totals['moves_compensated']} moves compensated, {totals['moves_skipped']} skipped, "
        f"{totals['points_added']} points added; worst predicted TCP deviation "
        + ("n/a" if worst is None else f"{worst:.4f} mm")
    )
    if args.summary:
        summary_path = Path(args.summary)
    elif args.out_dir:
        summary_path = Path(args.out_dir) / "rapidfix-batch.json"
    else:
        summary_path = Path(args.in_dir) / "rapidfix-batch.json"
    write_summary(summary, summary_path)
    print(f"summary: {summary_path}")
    if totals["errors"]:
        return 1
    return 3 if totals["with_warnings"] or totals["moves_skipped"] else 0
