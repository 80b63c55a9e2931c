"""`rapidfix simulate --program MEASURE.mod --poses POSES.csv`: a campaign on the virtual robot.

Runs the measurement program (`rapidfix plan`) on the virtual robot drawn from
--seed and --effect (the same robot `rapidfix simulate OUT_DIR` draws) and writes
what the tracker saw as a tracker-style export, plus truth.json. Not a command of
its own: `simulate` adds these options and hands over.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rapidfix.exceptions import RapidfixError


def add_program_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of a program run."""
    g = parser.add_argument_group("running a measurement program (rapidfix plan)")
    g.add_argument("--program", metavar="MEASURE.mod", help="measurement program to run")
    g.add_argument("--poses", metavar="POSES.csv",
                   help="its pose table (payloads; plan.toml beside it gives the ball)")
    g.add_argument("--export", default="tracker_export.csv", metavar="NAME",
                   help="file name of the export in OUT_DIR (tracker_export.csv)")
    g.add_argument("--export-format", choices=("plain", "timed"), default="plain",
                   help="plain: id,X,Y,Z; timed: id,time,X,Y,Z (+ temperature with thermal "
                   "drift)")
    g.add_argument("--no-ids", action="store_true",
                   help="leave the id column out (a triggered tracker numbering its points)")
    g.add_argument("--units", choices=("mm", "m", "in"), default="mm")
    g.add_argument("--delimiter", choices=("comma", "semicolon", "tab", "space"),
                   default="comma")
    g.add_argument("--clock-offset", type=float, default=36000.0, metavar="S",
                   help="the tracker clock at the program's start (timed exports)")
    g.add_argument("--pause", type=float, default=60.0, metavar="S",
                   help="how long each Stop (payload change) lasts")


def run_program_command(args: argparse.Namespace) -> int:
    """Run the program on the virtual robot, write the export and truth.json."""
    from rapidfix.demo import ExportOptions, simulate_program

    if not (args.program and args.poses):
        raise RapidfixError("--program and --poses go together")
    out = Path(args.out_dir) if args.out_dir else Path(args.poses).parent
    delim = {"comma": ",", "semicolon": ";", "tab": "\t", "space": " "}[args.delimiter]
    export = ExportOptions(timed=args.export_format == "timed", ids=not args.no_ids,
                           units=args.units, delimiter=delim,
                           clock_offset_s=args.clock_offset, name=args.export)
    path, _, run = simulate_program(args.program, args.poses, out, seed=args.seed,
                                    effects=args.effect, robot=args.robot,
                                    payload_kg=args.payload, pause_s=args.pause,
                                    export=export, overwrite=args.force)
    print(f"ran {args.program} on the virtual robot (seed {args.seed}): {len(run.q)} "
          f"measurements in {run.total_s / 60:.1f} min")
    print(f"wrote {path} and {out / 'truth.json'}")
    return 0
