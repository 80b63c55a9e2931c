"""`rapidfix simulate --program MEASURE.mod --poses POSES.csv`: a campaign on the virtual robot.

Runs the measurement program (`rapidfix plan`) on the virtual robot drawn from
--seed and --effect (the same robot `rapidfix simulate OUT_DIR` draws) and writes
what the tracker saw as a tracker-style export, plus truth.json. Not a command of
its own: `simulate` adds these options and hands over.
"""

from __future__ import annotations

import argparse
import json
import sys
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.exceptions import MeasurementError, OutputExistsError, RapidfixError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib


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


def _plan_meta(poses: Path) -> dict[str, Any]:
    path = poses.parent / "plan.toml"
    if not path.exists():
        return {}
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise MeasurementError(f"not valid TOML: {err}", file=path) from None


def run_program_command(args: argparse.Namespace) -> int:
    """Run the program on the virtual robot, write the export and truth.json."""
    from rapidfix.atomic import write_text_atomic
    from rapidfix.campaign.pose_table import read_pose_table
    from rapidfix.campaign.timing import MotionSettings
    from rapidfix.campaign.tracker_export import write_export
    from rapidfix.kinematics import load_robot
    from rapidfix.rapid import load_program
    from rapidfix.sim.cell import joint1_gauge
    from rapidfix.sim.program_run import measure_run, run_program
    from rapidfix.sim.virtual_robot import DEFAULT_SMR_OFFSET_MM, VirtualRobot

    if not (args.program and args.poses):
        raise RapidfixError("--program and --poses go together")
    poses_path = Path(args.poses)
    table = read_pose_table(poses_path)
    meta = _plan_meta(poses_path)
    robot_name = meta.get("robot", args.robot)
    smr = np.asarray(meta.get("smr_offset_mm", DEFAULT_SMR_OFFSET_MM), dtype=float)
    out = Path(args.out_dir) if args.out_dir else poses_path.parent
    export_path = out / args.export
    if not args.force and (export_path.exists() or (out / "truth.json").exists()):
        raise OutputExistsError("the folder already holds an export or truth.json", file=out,
                                hint="choose another folder or pass --force")
    motion = MotionSettings(**{k: float(meta[k]) for k in (
        "tcp_speed_mm_s", "orient_speed_deg_s", "joint_speed_pct", "accel_s", "settle_s",
        "measure_s") if k in meta})
    program = load_program(args.program)
    robot = load_robot(robot_name)
    run = run_program(program, robot, motion=motion, tool_mm=smr, pause_s=args.pause)
    if len(run.q) != len(table):
        raise RapidfixError(f"the program measures {len(run.q)} poses, the pose table lists "
                            f"{len(table)}: are they from the same plan?", file=args.program)
    vr = VirtualRobot.create(robot, seed=args.seed, effects=tuple(dict.fromkeys(args.effect)),
                             smr_offset_mm=smr, payload_kg=args.payload)
    # the noise of a run: from the seed and the program, so that a rewritten program run
    # on the same robot gets noise of its own (a new run), reproducibly
    noise = np.random.SeedSequence([args.seed, 16, zlib.crc32(program.to_bytes())])
    xyz, clock, temp = measure_run(vr, run, table.payload_kg,
                                   seed=int(noise.generate_state(1)[0]),
                                   clock_offset_s=args.clock_offset)
    ids = None
    if not args.no_ids:
        ids = [pid if pid is not None else str(table.point_id[k])
               for k, pid in enumerate(run.ids)]
    delim = {"comma": ",", "semicolon": ";", "tab": "\t", "space": " "}[args.delimiter]
    timed = args.export_format == "timed"
    write_export(export_path, xyz, ids=ids, time_s=clock if timed else None,
                 temp_c=temp if (timed and temp is not None) else None, unit=args.units,
                 delimiter=delim)
    truth = vr.truth()
    c = float(vr.errors.joint(np.zeros((1, 6)))[0, 0])
    R_g, t_g = joint1_gauge(vr.tracker.R, vr.tracker.t, c, robot, vr.tracker.scale)
    truth["gauge"] = {"rule": "the joint-1 error is zero at theta1 = 0",
                      "joint1_error_at_zero_deg": float(np.degrees(c)),
                      "R": R_g.tolist(), "t_mm": t_g.tolist()}
    for name in ("validation", "iso9283"):
        rows = table.set_name == name
        if rows.any():
            ctx = {"payload_kg": table.payload_kg[rows], "q_prev": run.q_prev[rows],
                   "time_s": run.time_s[rows]}
            key = "noise_floor" if name == "validation" else "noise_floor_iso9283"
            truth[key] = vr.noise_floor(run.q[rows], ctx, seed=args.seed)
    truth["program_run"] = {"program": str(args.program), "poses": str(poses_path),
                            "measurements": len(run.q), "run_time_s": run.total_s,
                            "clock_offset_s": args.clock_offset}
    write_text_atomic(out / "truth.json", json.dumps(truth, indent=2) + "\n")
    print(f"ran {args.program} on the virtual robot (seed {args.seed}): {len(run.q)} "
          f"measurements in {run.total_s / 60:.1f} min")
    print(f"wrote {export_path} and {out / 'truth.json'}")
    return 0
