"""`rapidfix simulate OUT_DIR`: write a measurement set made by a virtual robot cell."""

from __future__ import annotations

import argparse
import json

from rapidfix.exceptions import RapidfixError
from rapidfix.paths import check_output_dir
from rapidfix.sim import DEFAULT_ROBOT, EFFECTS, simulate_cell


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `simulate` subcommand."""
    parser = subparsers.add_parser(
        "simulate",
        help="make a measurement set from a virtual robot with known errors",
        description="Simulate a calibration session on a virtual robot (per-joint errors, "
        "optional hidden effects, a tracker placed where nobody says) and write setup.toml, "
        "sweeps.csv, calibration.csv, validation.csv, ballbar.toml, ballbar.csv and, "
        "separately, truth.json.",
    )
    parser.add_argument("out_dir", metavar="OUT_DIR", nargs="?",
                        help="folder to write the set to (with --program: the export and "
                        "truth.json; default the pose table's folder)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--effect", action="append", default=[], choices=EFFECTS,
                        metavar="NAME", help="add a hidden effect; repeatable. One of: "
                        + ", ".join(EFFECTS))
    parser.add_argument("--robot", default=DEFAULT_ROBOT, help=f"robot model ({DEFAULT_ROBOT})")
    parser.add_argument("--calibration-points", type=int, default=60, metavar="N",
                        help="random poses measured for calibration.csv (default 60)")
    parser.add_argument("--validation-points", type=int, default=40, metavar="N",
                        help="random poses measured for validation.csv (default 40)")
    parser.add_argument("--repeats", type=int, default=3, metavar="N",
                        help="measurements of each sweep angle (default 3)")
    parser.add_argument("--step", type=float, default=5.0, metavar="DEG",
                        help="sweep step in degrees (default 5)")
    parser.add_argument("--outliers", type=int, default=0, metavar="N",
                        help="gross tracker errors added to N sweep rows")
    parser.add_argument("--payload", type=float, default=0.0, metavar="KG",
                        help="payload of the sweeps and the ballbar run")
    parser.add_argument("--balls", type=int, default=2, choices=(1, 2), metavar="N",
                        help="target-ball nests the calibration and validation points are "
                        "measured on, row by row (default 2: the flange's turn is measured; "
                        "1: one ball, as older sets)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing set")
    from rapidfix.commands.simulate_program import add_program_arguments

    add_program_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Simulate and write one set; say where and what the noise floor is."""
    if args.program or args.poses:
        from rapidfix.commands.simulate_program import run_program_command

        return run_program_command(args)
    if args.out_dir is None:
        raise RapidfixError("give OUT_DIR, the folder to write the set to")
    for name, value in (("--calibration-points", args.calibration_points),
                        ("--validation-points", args.validation_points),
                        ("--repeats", args.repeats)):
        if value < 1:
            raise RapidfixError(f"{name} must be at least 1")
    if not 0.5 <= args.step <= 45.0:
        raise RapidfixError("--step must be between 0.5 and 45 degrees")
    if args.outliers < 0 or args.payload < 0:
        raise RapidfixError("--outliers and --payload must not be negative")
    out_dir = check_output_dir(args.out_dir, "measurement set folder")
    out = simulate_cell(out_dir, seed=args.seed, effects=tuple(dict.fromkeys(args.effect)),
                        robot=args.robot, overwrite=args.force,
                        n_calibration=args.calibration_points,
                        n_validation=args.validation_points, repeats=args.repeats,
                        step_deg=args.step, n_outliers=args.outliers, payload_kg=args.payload,
                        balls=args.balls)
    truth = json.loads((out / "truth.json").read_text(encoding="utf-8"))
    effects = ", ".join(truth["errors"]["effects"]) or "per-joint errors only"
    floor = truth["noise_floor"]["mean_tcp_error_mm"]
    print(f"wrote a measurement set to {out} ({effects}; seed {args.seed})")
    print(f"noise floor {floor:.4f} mm mean TCP error; the truth is in {out / 'truth.json'}")
    return 0
