"""A measurement campaign on the virtual robot: run a `rapidfix plan` program, write what
the tracker saw as a tracker-style export and, separately, truth.json.

The robot is the one `rapidfix simulate OUT_DIR` draws from the same seed and
effects; the noise of a run comes from the seed and the program's bytes, so a
rewritten program on the same robot gets noise of its own, reproducibly.
"""

from __future__ import annotations

import json
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.atomic import write_text_atomic
from rapidfix.campaign import MotionSettings, read_plan_meta, read_pose_table, write_export
from rapidfix.demo.program_run import Run, measure_run, run_program
from rapidfix.exceptions import OutputExistsError, RapidfixError
from rapidfix.kinematics import load_robot
from rapidfix.rapid import load_program
from rapidfix.sim import DEFAULT_ROBOT, DEFAULT_SMR_OFFSET_MM, VirtualRobot, joint1_gauge


@dataclass(frozen=True)
class ExportOptions:
    """How the virtual tracker writes: `timed` adds the time (and, with thermal drift,
    the temperature); `ids` the point ids (TPWrite's, else the table's); units mm, m
    or in; the delimiter; the tracker clock at the program's start; the file name."""

    timed: bool = False
    ids: bool = True
    units: str = "mm"
    delimiter: str = ","
    clock_offset_s: float = 36000.0
    name: str = "tracker_export.csv"


def simulate_program(program_path: str | Path, poses_path: str | Path, out_dir: str | Path,
                     *, seed: int = 0, effects: tuple[str, ...] | list[str] = (),
                     robot: str | None = None, payload_kg: float = 0.0, pause_s: float = 60.0,
                     export: ExportOptions | None = None, overwrite: bool = False
                     ) -> tuple[Path, dict[str, Any], Run]:
    """Run the program on the virtual robot; returns the export's path, the truth, the run."""
    export = export or ExportOptions()
    poses_path = Path(poses_path)
    table = read_pose_table(poses_path)
    meta = read_plan_meta(poses_path)
    model = load_robot(meta.get("robot", robot or DEFAULT_ROBOT))
    smr = np.asarray(meta.get("smr_offset_mm", DEFAULT_SMR_OFFSET_MM), dtype=float)
    out = Path(out_dir)
    export_path = out / export.name
    if not overwrite and (export_path.exists() or (out / "truth.json").exists()):
        raise OutputExistsError("the folder already holds an export or truth.json", file=out,
                                hint="choose another folder or pass --force")
    motion = MotionSettings(**{k: float(meta[k]) for k in (
        "tcp_speed_mm_s", "orient_speed_deg_s", "joint_speed_pct", "accel_s", "settle_s",
        "measure_s") if k in meta})
    program = load_program(program_path)
    run = run_program(program, model, motion=motion, tool_mm=smr, pause_s=pause_s)
    if len(run.q) != len(table):
        raise RapidfixError(f"the program measures {len(run.q)} poses, the pose table lists "
                            f"{len(table)}: are they from the same plan?", file=program_path)
    vr = VirtualRobot.create(model, seed=seed, effects=tuple(dict.fromkeys(effects)),
                             smr_offset_mm=smr, payload_kg=payload_kg)
    noise = np.random.SeedSequence([seed, 16, zlib.crc32(program.to_bytes())])
    xyz, clock, temp = measure_run(vr, run, table.payload_kg,
                                   seed=int(noise.generate_state(1)[0]),
                                   clock_offset_s=export.clock_offset_s)
    ids = None
    if export.ids:
        ids = [pid if pid is not None else str(table.point_id[k])
               for k, pid in enumerate(run.ids)]
    write_export(export_path, xyz, ids=ids, time_s=clock if export.timed else None,
                 temp_c=temp if (export.timed and temp is not None) else None,
                 unit=export.units, delimiter=export.delimiter)
    truth = vr.truth()
    c = float(vr.errors.joint(np.zeros((1, 6)))[0, 0])
    R_g, t_g = joint1_gauge(vr.tracker.R, vr.tracker.t, c, model, vr.tracker.scale)
    truth["gauge"] = {"rule": "the joint-1 error is zero at theta1 = 0",
                      "joint1_error_at_zero_deg": float(np.degrees(c)),
                      "R": R_g.tolist(), "t_mm": t_g.tolist()}
    for name in ("validation", "iso9283"):
        rows = table.set_name == name
        if rows.any():
            ctx = {"payload_kg": table.payload_kg[rows], "q_prev": run.q_prev[rows],
                   "time_s": run.time_s[rows]}
            key = "noise_floor" if name == "validation" else "noise_floor_iso9283"
            truth[key] = vr.noise_floor(run.q[rows], ctx, seed=seed)
    truth["program_run"] = {"program": str(program_path), "poses": str(poses_path),
                            "measurements": len(run.q), "run_time_s": run.total_s,
                            "clock_offset_s": export.clock_offset_s}
    write_text_atomic(out / "truth.json", json.dumps(truth, indent=2) + "\n")
    return export_path, truth, run
