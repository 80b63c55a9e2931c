"""`rapidfix demo`: the whole loop on a built-in virtual robot, in well under a minute.

Simulate a calibration session on a virtual IRB 1600 with per-joint errors and a
hidden tracker; fit the per-joint model on the sweeps only; compensate the
validation and ballbar targets; execute them before and after on the virtual
robot, measured by its tracker and mapped into the robot frame by the fitted
registration (what a user with a tracker does); write the report.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rapidfix.exceptions import OutputExistsError

DEFAULT_OUT = Path("rapidfix-out") / "demo"
#: a file marking a folder as the demo's own output, which a later demo may replace
MARKER = ".rapidfix-demo"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `demo` command."""
    parser = subparsers.add_parser(
        "demo",
        help="run the whole loop on a built-in virtual robot",
        description="Simulate a measurement set on a virtual robot, fit the joint error "
        "model on its sweeps, compensate the validation and ballbar targets, run them "
        "on the virtual robot before and after, and write an HTML + JSON report.",
    )
    parser.add_argument("--out", default=str(DEFAULT_OUT), metavar="DIR",
                        help=f"output folder (default: ./{DEFAULT_OUT.as_posix()}); only a "
                        "previous demo's output is ever replaced")
    parser.add_argument("--seed", type=int, default=1,
                        help="seed of the virtual robot and its noise (default: 1)")
    parser.set_defaults(func=run)


def claim_output(out: Path) -> None:
    """Make `out` the demo's folder; refuse a non-empty folder the demo did not write."""
    if out.exists():
        if not out.is_dir():
            raise OutputExistsError("exists and is not a folder", file=out)
        if any(out.iterdir()) and not (out / MARKER).exists():
            raise OutputExistsError(
                "folder is not empty and was not written by `rapidfix demo`", file=out,
                hint="choose another --out")
    out.mkdir(parents=True, exist_ok=True)
    (out / MARKER).write_text("written by `rapidfix demo`; the next demo may replace it\n")


def run(args: argparse.Namespace) -> int:
    """Simulate → fit → compensate → execute → report; exit status 3 if the model warned."""
    from tqdm import tqdm

    from rapidfix import pipeline
    from rapidfix.error_model import save_model
    from rapidfix.report import write_report
    from rapidfix.sim import VirtualRobot, simulate_cell

    out = Path(args.out)
    claim_output(out)
    cell = out / "measurements"
    steps = tqdm(total=6, desc="rapidfix demo", unit="step", leave=False,
                 disable=not sys.stderr.isatty())

    steps.set_postfix_str("simulating the cell")
    simulate_cell(cell, seed=args.seed, overwrite=True)
    truth = json.loads((cell / "truth.json").read_text(encoding="utf-8"))
    virtual = VirtualRobot.from_truth(truth)
    noise_floor = float(truth["noise_floor"]["mean_tcp_error_mm"])
    steps.update()

    steps.set_postfix_str("fitting the model on the sweeps")
    outcome = pipeline.fit_from_files(cell / "setup.toml", [cell / "sweeps.csv"])
    model_path = save_model(outcome.model, out / "model.json")
    steps.update()

    with pipeline.model_warnings() as warned:
        steps.set_postfix_str("validation points before/after")
        validation = pipeline.run_points_before_after(
            outcome, virtual, cell / "validation.csv", seed=args.seed)
        steps.update()

        steps.set_postfix_str("ballbar before/after")
        ballbar = pipeline.run_ballbar_before_after(
            outcome, virtual, cell / "ballbar.toml", seed=args.seed)
        steps.update()

    steps.set_postfix_str("writing the report")
    report = pipeline.accuracy_report_for(
        outcome, validation=validation, ballbar=ballbar,
        title=f"rapidfix demo: virtual {outcome.robot.name}, seed {args.seed}",
        notes=[
            "Fitted on the sweeps only. Validation and ballbar targets executed on the "
            "virtual robot without and with compensation, measured by its tracker and "
            "mapped into the robot frame with the registration found from the sweeps.",
            "Noise floor stated by the simulator (mean TCP error that noise and "
            f"repeatability alone leave on the validation points): {noise_floor:.4f} mm.",
        ],
        summary={"noise_floor_mm": noise_floor, "seed": args.seed},
    )
    html_path, json_path = write_report(report, out)
    steps.update()

    # post-processor step: rewrite the sample programs (the ballbar among them) with the
    # fitted model and run original and rewritten on the virtual robot
    steps.set_postfix_str("rewriting and running the sample programs")
    from rapidfix.demo import format_table, rewrite_and_run

    programs = rewrite_and_run(None, out / "programs", model_path, virtual)
    steps.update()
    steps.close()

    print(pipeline.before_after_table(report.summary))
    print(f"noise floor (validation, mean): {noise_floor:.4f} mm")
    print(f"measurements: {cell}")
    print(f"model:        {model_path}")
    print(f"report:       {html_path}")
    print(f"report data:  {json_path}")
    print(format_table(programs))
    # closing the loop: a robot with a hidden effect, its per-joint fit, the diagnosis
    from rapidfix.demo import demo_loop, format_demo

    loop = demo_loop(out / "diagnosis", seed=args.seed)
    print(format_demo(loop))
    # the loop on the robot: a cell program rewritten with each model, run as it executes
    from rapidfix.demo import demo_on_robot, format_on_robot

    models = {"per-joint model": loop["files"]["per_joint_model"],
              "diagnosed model": loop["files"]["model"]}
    print(format_on_robot(demo_on_robot(out / "diagnosis" / "measurements", models,
                                        out / "diagnosis" / "programs", args.seed)))
    # the measurement campaign: the ISO 9283 cube planned, run, compensated and checked
    from rapidfix.demo import demo_campaign, format_campaign

    print(format_campaign(demo_campaign(out / "campaign", model_path, args.seed)))
    for text in warned:
        print(f"rapidfix: warning: {text}", file=sys.stderr)
    return 3 if warned else 0
