"""`rapidfix plan OUT_DIR`: the measurement program and pose table of a campaign."""

from __future__ import annotations

import argparse

import numpy as np

from rapidfix.exceptions import OutputExistsError, RapidfixError


def parse_numbers(text: str, n: int | None, what: str) -> list[float]:
    try:
        values = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise RapidfixError(f"{what}: {text!r} is not a list of numbers") from None
    if (n is not None and len(values) != n) or not values or not np.all(np.isfinite(values)):
        raise RapidfixError(f"{what} needs {n or 'some'} numbers separated by commas, "
                            f"got {text!r}")
    return values


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `plan` command."""
    from rapidfix.campaign import APPROACH_MODES, TRIGGERS
    from rapidfix.commands.robot_options import add_robot_arguments

    p = subparsers.add_parser(
        "plan",
        help="write the RAPID measurement program and pose table of a tracker campaign",
        description="Plan a laser-tracker campaign: joint sweeps (the paper's protocol), "
        "space-filling calibration and validation poses in your work envelope, optionally "
        "the ISO 9283 cube; every pose checked (limits, reach on its confdata, envelope, "
        "joint speed, line of sight) before OUT_DIR/measure.mod, OUT_DIR/poses.csv and "
        "OUT_DIR/plan.toml are written. Prints the number of points and the run time.",
    )
    p.add_argument("out_dir", metavar="OUT_DIR", help="folder to write into")
    add_robot_arguments(p)
    p.add_argument("--smr-offset", default="60,80,90", metavar="X,Y,Z",
                   help="target ball centre in the flange frame, mm (default 60,80,90)")
    g = p.add_argument_group("sweeps")
    g.add_argument("--joints", default="1,2,3,4,5,6", metavar="LIST",
                   help="joints to sweep (default all; '' for none)")
    g.add_argument("--step", type=float, default=5.0, metavar="DEG", help="sweep step (5)")
    g.add_argument("--repeats", type=int, default=3, help="repeats of each sweep (3)")
    g.add_argument("--sweep-range", action="append", default=[], metavar="J:LO:HI",
                   help="limit joint J's sweep to LO..HI degrees; repeatable")
    g.add_argument("--sweep-payload", type=float, default=0.0, metavar="KG")
    g = p.add_argument_group("calibration and validation points")
    g.add_argument("--calibration-points", type=int, default=60, metavar="N")
    g.add_argument("--validation-points", type=int, default=40, metavar="N")
    g.add_argument("--payload", default="0", metavar="KG[,KG...]",
                   help="payload schedule: points are dealt these payloads in turn and run "
                   "grouped by payload, with a Stop to change it (default 0)")
    g.add_argument("--seed", type=int, default=0, help="random seed of the poses (0)")
    g = p.add_argument_group("work envelope (mm, base frame unless --box-frame)")
    g.add_argument("--box", metavar="XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
                   help="box the ball stays in at calibration/validation/ISO poses")
    g.add_argument("--box-frame", metavar="X,Y,Z,Q1,Q2,Q3,Q4",
                   help="the box is in this work-object frame (uframe∘oframe, [w,x,y,z])")
    g.add_argument("--floor", type=float, metavar="Z",
                   help="no ball below this height (all poses, sweeps included)")
    g.add_argument("--keep-out", action="append", default=[], metavar="BOX",
                   help="a box no ball may enter (all poses); repeatable")
    g.add_argument("--margin", type=float, default=0.0, metavar="MM",
                   help="clearance kept from the floor and keep-out boxes")
    g = p.add_argument_group("tracker")
    g.add_argument("--tracker", metavar="X,Y,Z",
                   help="tracker head position in the base frame: check line of sight")
    g.add_argument("--smr-normal", metavar="X,Y,Z",
                   help="the reflector's opening direction in the flange frame (default: "
                   "along the ball offset)")
    g.add_argument("--acceptance", type=float, default=30.0, metavar="DEG",
                   help="reflector's half acceptance angle (30)")
    g = p.add_argument_group("ISO 9283 cube")
    g.add_argument("--iso", action="store_true", help="add the ISO 9283 cube poses P1-P5")
    g.add_argument("--iso-cycles", type=int, default=30, metavar="N", help="cycles (30)")
    g.add_argument("--iso-centre", metavar="X,Y,Z", help="cube centre (default: the box's)")
    g.add_argument("--iso-side", type=float, metavar="MM",
                   help="cube side (default: the largest the box holds and the robot reaches)")
    g = p.add_argument_group("motion and trigger")
    g.add_argument("--approach", choices=APPROACH_MODES, default="same",
                   help="same: every joint arrives moving up (default); both: each pose "
                   "from both sides (backlash); none: no approach moves")
    g.add_argument("--approach-deg", type=float, default=2.0, metavar="DEG")
    g.add_argument("--settle", type=float, default=1.0, metavar="S",
                   help="WaitTime before the trigger (1 s)")
    g.add_argument("--measure-time", type=float, default=0.5, metavar="S",
                   help="time the robot stays still after the trigger (0.5 s)")
    g.add_argument("--trigger", choices=TRIGGERS, default="none",
                   help="none, pulse (PulseDO of --signal) or tpwrite (the point id)")
    g.add_argument("--signal", default="doTrackerTrigger", metavar="NAME")
    g.add_argument("--speed", type=float, default=200.0, metavar="MM_S",
                   help="TCP speed of the measurement moves (200)")
    g.add_argument("--orient-speed", type=float, default=60.0, metavar="DEG_S")
    g.add_argument("--joint-speed", type=float, default=100.0, metavar="PCT",
                   help="cap every joint at PCT %% of its rated speed (100)")
    g.add_argument("--module", default="RfMeasure", help="RAPID module name")
    p.add_argument("--force", action="store_true", help="overwrite an earlier plan")
    p.set_defaults(func=run)


def _settings(args: argparse.Namespace):
    from rapidfix.campaign import (
        Box,
        Envelope,
        MotionSettings,
        PlanSettings,
        ProgramOptions,
        TrackerView,
    )
    from rapidfix.kinematics import pose

    smr = parse_numbers(args.smr_offset, 3, "--smr-offset")
    joints = tuple(int(v) for v in parse_numbers(args.joints, None, "--joints")) if \
        args.joints.strip() else ()
    if any(j < 1 or j > 6 for j in joints):
        raise RapidfixError("--joints takes joint numbers 1 to 6")
    ranges = {}
    for text in args.sweep_range:
        parts = text.split(":")
        values = parse_numbers(",".join(parts), 3, "--sweep-range J:LO:HI") if len(parts) == 3 \
            else parse_numbers(text, 3, "--sweep-range J:LO:HI")
        ranges[int(values[0])] = (values[1], values[2])
    for name, value, low in (("--step", args.step, 0.5), ("--repeats", args.repeats, 1),
                             ("--iso-cycles", args.iso_cycles, 2), ("--speed", args.speed, 1),
                             ("--orient-speed", args.orient_speed, 1),
                             ("--joint-speed", args.joint_speed, 1),
                             ("--settle", args.settle, 0), ("--measure-time", args.measure_time,
                                                            0)):
        if value < low:
            raise RapidfixError(f"{name} must be at least {low}")
    if args.joint_speed > 100:
        raise RapidfixError("--joint-speed is a share of the rated speed: at most 100 %")
    if args.calibration_points < 0 or args.validation_points < 0:
        raise RapidfixError("point counts must not be negative")
    payloads = tuple(parse_numbers(args.payload, None, "--payload"))
    if any(v < 0 for v in payloads) or args.sweep_payload < 0:
        raise RapidfixError("payloads must not be negative")
    frame = np.eye(4)
    if args.box_frame:
        v = parse_numbers(args.box_frame, 7, "--box-frame")
        frame = pose(v[:3], v[3:])
    envelope = Envelope(box=Box.parse(args.box) if args.box else None, frame=frame,
                        floor_z_mm=args.floor,
                        keep_out=tuple(Box.parse(b, "--keep-out") for b in args.keep_out),
                        margin_mm=args.margin)
    view = None
    if args.tracker:
        normal = parse_numbers(args.smr_normal, 3, "--smr-normal") if args.smr_normal else smr
        if np.linalg.norm(normal) == 0:
            raise RapidfixError("--smr-normal (or the ball offset) must not be zero")
        view = TrackerView(np.array(parse_numbers(args.tracker, 3, "--tracker")), np.array(normal),
                           args.acceptance)
    motion = MotionSettings(tcp_speed_mm_s=args.speed, orient_speed_deg_s=args.orient_speed,
                            joint_speed_pct=args.joint_speed, settle_s=args.settle,
                            measure_s=args.measure_time)
    return PlanSettings(
        smr_offset_mm=tuple(smr), sweep_joints=joints, step_deg=args.step,
        repeats=args.repeats, sweep_ranges_deg=ranges, sweep_payload_kg=args.sweep_payload,
        n_calibration=args.calibration_points, n_validation=args.validation_points,
        payloads_kg=payloads, envelope=envelope, tracker=view, iso=args.iso,
        iso_cycles=args.iso_cycles,
        iso_centre_mm=tuple(parse_numbers(args.iso_centre, 3, "--iso-centre"))
        if args.iso_centre else None,
        iso_side_mm=args.iso_side, approach=args.approach, approach_deg=args.approach_deg,
        seed=args.seed,
        program=ProgramOptions(module=args.module, trigger=args.trigger, signal=args.signal,
                               motion=motion))


def run(args: argparse.Namespace) -> int:
    """Plan, check, write; print what was written, the point count and the run time."""
    from pathlib import Path

    from rapidfix.campaign import make_plan, write_plan
    from rapidfix.commands.robot_options import robot_from_args

    out = Path(args.out_dir)
    names = ("measure.mod", "poses.csv", "plan.toml")
    existing = [n for n in names if (out / n).exists()]
    if existing and not args.force:
        raise OutputExistsError(f"the folder already holds {', '.join(existing)}", file=out,
                                hint="choose another folder or pass --force")
    robot = robot_from_args(args)
    plan = make_plan(robot, _settings(args))
    paths = write_plan(plan, out)
    s = plan.summary
    per_set = ", ".join(f"{n} {k}" for k, n in s["per_set"].items())
    t = s["run_time_s"]
    print(f"{s['points']} measured poses ({per_set}); {s['approach_moves']} approach moves; "
          f"{s['payload_changes']} payload changes")
    print(f"estimated run time {int(t // 3600)} h {int(t % 3600 // 60):02d} min "
          f"{int(t % 60):02d} s; fastest joint at {100 * s['fastest_joint_share_of_rated']:.0f}"
          f" % of its rated speed (cap {args.joint_speed:g} %)")
    if "iso9283" in s:
        iso = s["iso9283"]
        c = ", ".join(f"{v:.1f}" for v in iso["centre_mm"])
        print(f"ISO 9283 cube: side {iso['side_mm']:.1f} mm, centre ({c}) mm, "
              f"{iso['cycles']} cycles")
    print(f"wrote {paths['program']}, {paths['poses']} and {paths['plan']}")
    return 0
