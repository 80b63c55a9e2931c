"""`rapidfix import EXPORT --poses POSES.csv -o DIR`: tracker export → measurement files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rapidfix.exceptions import MeasurementError, OutputExistsError, RapidfixError


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `import` command."""
    from rapidfix.campaign.matching import MODES

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
    from rapidfix.campaign.matching import match_export
    from rapidfix.campaign.measurement_set import FILES, measurement_tables, write_measurement_set
    from rapidfix.campaign.pose_table import read_pose_table
    from rapidfix.campaign.tracker_export import read_export
    from rapidfix.commands.simulate_program import _plan_meta
    from rapidfix.kinematics import load_robot
    from rapidfix.measure.files import Setup

    poses = Path(args.poses)
    table = read_pose_table(poses)
    meta = _plan_meta(poses)
    robot_name = args.robot or meta.get("robot")
    smr = meta.get("smr_offset_mm")
    if args.smr_offset:
        from rapidfix.commands.plan import _numbers

        smr = _numbers(args.smr_offset, 3, "--smr-offset")
    if robot_name is None or smr is None:
        raise RapidfixError("no plan.toml beside the pose table: give --robot and --smr-offset")
    out = Path(args.output)
    targets = [*FILES.values(), "setup.toml"]
    existing = [n for n in targets if (out / n).exists()]
    if existing and not args.force:
        raise OutputExistsError(f"the folder already holds {', '.join(existing)}", file=out,
                                hint="choose another folder or pass --force")
    columns = [c.strip().lower() for c in args.columns.split(",")] if args.columns else None
    export = read_export(args.export, columns=columns)
    robot = load_robot(robot_name)
    match = match_export(export, table, robot, np.asarray(smr, dtype=float), mode=args.match,
                         units=args.units, time_tolerance_s=args.time_tolerance)
    problems = list(match.problems)
    missing = match.missing
    if missing and not args.allow_missing:
        shown = ", ".join(missing[:10]) + (f" and {len(missing) - 10} more"
                                           if len(missing) > 10 else "")
        problems.append(MeasurementError(f"{len(missing)} poses of the pose table were not "
                                         f"measured: {shown}", file=export.path,
                                         hint="--allow-missing writes the rest"))
    if problems:
        for extra in problems[1:]:
            print(f"rapidfix: error: {extra}", file=sys.stderr)
        first = problems[0]
        if len(problems) > 1:
            first.hint = f"{len(problems) - 1} more problems listed above"
        raise first
    for text in match.assumptions:
        print(f"{export.path.name}: {text}")
    tables = measurement_tables(match, table, export)
    setup = None if args.no_setup else Setup(robot=robot.name,
                                              smr_offset_mm=np.asarray(smr, dtype=float))
    paths = write_measurement_set(out, tables, setup)
    counts = ", ".join(f"{len(t)} {n}" for n, t in tables.items())
    print(f"matched {len(match.table_index)} points of {len(table)} ({counts})")
    print("wrote " + ", ".join(str(p) for p in paths))
    if missing:
        print(f"rapidfix: warning: {len(missing)} poses not measured: "
              + ", ".join(missing[:20]) + (" …" if len(missing) > 20 else ""), file=sys.stderr)
        return 3
    return 0
