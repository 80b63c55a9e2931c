"""`rapidfix import EXPORT --poses POSES.csv -o DIR`: tracker export → measurement files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `import` command."""
    from rapidfix.campaign import MODES

    p = subparsers.add_parser(
        "import",
        help="turn a laser tracker's export into the measurement files",
        description="Merge a tracker export (id, X, Y, Z as tracker software writes it; "
        "any delimiter, header or not, mm/m/inch; optional time and temperature) with the "
        "pose table of `rapidfix plan`, check it (missing, extra, duplicated or unknown "
        "points, wrong order, points measured while the robot moved, wrong units) and "
        "write sweeps.csv, calibration.csv, validation.csv, iso9283.csv and setup.toml.",
    )
    p.add_argument("export", metavar="EXPORT", help="the tracker's export file")
    p.add_argument("--poses", required=True, metavar="POSES.csv",
                   help="the pose table (plan.toml beside it gives robot and ball)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write to")
    p.add_argument("--match", choices=MODES, default="auto",
                   help="match points by id, time or order (default: id when the ids are "
                   "the table's, else time when there are timestamps, else order)")
    p.add_argument("--units", choices=("mm", "m", "in"),
                   help="units of X, Y, Z (default: detected and checked against the plan)")
    p.add_argument("--columns", metavar="LIST",
                   help="column roles of a file without header, e.g. id,time,x,y,z (- skips)")
    p.add_argument("--time-tolerance", type=float, default=0.3, metavar="S",
                   help="how far a timestamp may stray from the plan's schedule (0.3 s)")
    p.add_argument("--robot", metavar="NAME", help="robot (default: plan.toml's)")
    p.add_argument("--smr-offset", metavar="X,Y,Z", help="ball offset (default: plan.toml's)")
    p.add_argument("--allow-missing", action="store_true",
                   help="write what was measured when poses are missing (listed; exit 3)")
    p.add_argument("--no-setup", action="store_true", help="do not write setup.toml")
    p.add_argument("--force", action="store_true", help="overwrite earlier files")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Read, match, check, write; every problem is printed, the first is the error."""
    from rapidfix.campaign import import_export

    smr = None
    if args.smr_offset:
        from rapidfix.commands.plan import parse_numbers

        smr = parse_numbers(args.smr_offset, 3, "--smr-offset")
    columns = [c.strip().lower() for c in args.columns.split(",")] if args.columns else None
    result = import_export(args.export, args.poses, args.output, mode=args.match,
                           units=args.units, columns=columns,
                           time_tolerance_s=args.time_tolerance, robot=args.robot,
                           smr_offset_mm=smr, allow_missing=args.allow_missing,
                           write_setup=not args.no_setup, overwrite=args.force)
    if result.problems:
        for extra in result.problems[1:]:
            print(f"rapidfix: error: {extra}", file=sys.stderr)
        first = result.problems[0]
        if len(result.problems) > 1:
            first.hint = f"{len(result.problems) - 1} more problems listed above"
        raise first
    name = Path(args.export).name
    for text in result.match.assumptions:
        print(f"{name}: {text}")
    counts = ", ".join(f"{len(t)} {n}" for n, t in result.tables.items())
    print(f"matched {len(result.match.table_index)} points of {result.poses} ({counts})")
    print("wrote " + ", ".join(str(p) for p in result.paths))
    missing = result.match.missing
    if missing:
        print(f"rapidfix: warning: {len(missing)} poses not measured: "
              + ", ".join(missing[:20]) + (" …" if len(missing) > 20 else ""), file=sys.stderr)
        return 3
    return 0
