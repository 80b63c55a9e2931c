"""The campaign step of `rapidfix demo`: the ISO 9283 cube planned, run on the virtual
robot, compensated with the demo's model and checked in the standard's terms.

The demo's model was fitted on the sweeps of the same virtual robot (same seed),
so the cube program goes plan → run → import → rewrite → run → import → report.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.campaign import (
    PlanSettings,
    ProgramOptions,
    ball_positions,
    cube_runs,
    evaluate,
    import_export,
    make_plan,
    to_robot,
    write_plan,
)
from rapidfix.demo.campaign_run import simulate_program
from rapidfix.kinematics import load_robot
from rapidfix.measure import read_points
from rapidfix.sim import DEFAULT_ROBOT, DEFAULT_SMR_OFFSET_MM

CYCLES = 10


def demo_campaign(out: Path, model_path: Path, seed: int) -> dict[str, Any]:
    """Run the cube before and after compensation; AP per pose (robot frame) and floor."""
    from rapidfix.postprocess import Compensator, RewriteOptions, rewrite_file

    robot = load_robot(DEFAULT_ROBOT)
    plan = make_plan(robot, PlanSettings(
        smr_offset_mm=DEFAULT_SMR_OFFSET_MM, sweep_joints=(), n_calibration=0,
        n_validation=0, iso=True, iso_cycles=CYCLES,
        program=ProgramOptions(trigger="tpwrite")))
    paths = write_plan(plan, out / "plan")
    comp_program = out / "plan" / "measure_comp.mod"
    rewrite_file(paths["program"], comp_program, Compensator.load(str(model_path)),
                 RewriteOptions())
    model = json.loads(Path(model_path).read_text(encoding="utf-8"))
    reg = model["statistics"]["sweep_analysis"]["registration"]
    results: dict[str, Any] = {}
    for label, program in (("before", paths["program"]), ("after", comp_program)):
        _, truth, _ = simulate_program(program, paths["poses"], out / f"run_{label}",
                                       seed=seed, overwrite=True)
        imported = import_export(out / f"run_{label}" / "tracker_export.csv", paths["poses"],
                                 out / f"set_{label}", overwrite=True)
        if imported.problems:
            raise imported.problems[0]
        table = read_points(out / f"set_{label}" / "iso9283.csv")
        runs = cube_runs(table, ball_positions(robot, table.q, plan.settings.smr_offset_mm))
        results[label] = evaluate(to_robot(runs, np.asarray(reg["R"]),
                                           np.asarray(reg["t_mm"])))
        results["noise_floor_mm"] = truth["noise_floor_iso9283"]["mean_tcp_error_mm"]
    results["cube"] = plan.summary["iso9283"]
    results["folder"] = str(out)
    return results


def format_campaign(result: dict[str, Any]) -> str:
    """A few lines: AP per pose before and after, against the noise floor."""
    cube = result["cube"]
    lines = [f"ISO 9283 cube (side {cube['side_mm']:.0f} mm, {cube['cycles']} cycles) planned, "
             f"run, compensated and run again: {result['folder']}"]
    for label in ("before", "after"):
        ap = " ".join(f"{p['AP_mm']:.4f}" for p in result[label]["poses"])
        lines.append(f"  AP P1..P5 {label:<6} {ap} mm")
    lines.append(f"  noise floor {result['noise_floor_mm']:.4f} mm")
    return "\n".join(lines)
