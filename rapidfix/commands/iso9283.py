"""`rapidfix iso9283 BEFORE.csv [--after AFTER.csv]`: the ISO 9283 report of a cube run."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.exceptions import ModelError, RapidfixError


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `iso9283` command."""
    p = subparsers.add_parser(
        "iso9283",
        help="pose and distance accuracy/repeatability (ISO 9283) of a measured cube run",
        description="Read the measured cycles of the ISO 9283 cube poses (iso9283.csv of "
        "`rapidfix import`) and report, per pose, pose accuracy AP and repeatability RP, and "
        "distance accuracy AD and repeatability RD between poses (ISO 9283:1998, 7.2 and "
        "7.5), before and after compensation side by side, in the robot frame (with "
        "--model) and after a rigid registration; HTML and JSON with a plot.",
    )
    p.add_argument("before", metavar="BEFORE.csv", help="the cube run as programmed")
    p.add_argument("--after", metavar="AFTER.csv", help="the cube run of the compensated program")
    p.add_argument("--setup", required=True, metavar="SETUP.toml",
                   help="setup.toml (robot and ball offset)")
    p.add_argument("--model", metavar="MODEL.json",
                   help="model whose sweep registration maps the tracker into the robot frame")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="folder for iso9283.html and iso9283.json")
    p.set_defaults(func=run)


def _registration(path: str) -> tuple[np.ndarray, np.ndarray]:
    data = json.loads(Path(path).read_text(encoding="utf-8"))
    try:
        reg = data["statistics"]["sweep_analysis"]["registration"]
        return np.asarray(reg["R"], dtype=float), np.asarray(reg["t_mm"], dtype=float)
    except (KeyError, TypeError):
        raise ModelError("the model holds no tracker registration (fit it from sweeps)",
                         file=path, column="statistics.sweep_analysis.registration") from None


def iso_figures(results: dict[str, dict[str, Any]]) -> Any:
    """AP and RP per pose, each run and frame side by side (bar chart)."""
    from matplotlib.figure import Figure as MplFigure

    from rapidfix.report import Figure

    fig = MplFigure(figsize=(10, 4), layout="constrained")
    axes = fig.subplots(1, 2)
    labels = [f"P{k}" for k in range(1, 6)]
    data: dict[str, Any] = {}
    keys = list(results)
    width = 0.8 / max(1, len(keys))
    for ax, what in zip(axes, ("AP_mm", "RP_mm")):
        for n, key in enumerate(keys):
            values = [p[what] for p in results[key]["poses"]]
            ax.bar(np.arange(5) + n * width, values, width, label=key)
            data[f"{key} {what}"] = values
        ax.set_xticks(np.arange(5) + width * (len(keys) - 1) / 2, labels)
        ax.set_ylabel(f"{what[:2]} (mm)")
        ax.set_title("pose accuracy AP" if what == "AP_mm" else "pose repeatability RP")
    axes[0].legend(fontsize=8)
    return Figure("iso9283", "ISO 9283 pose accuracy and repeatability",
                  "Per pose of the cube: AP (distance from the commanded position to the "
                  "barycentre of the attained ones) and RP (l̄ + 3·S_l), ISO 9283:1998 7.2.",
                  data, fig)


def run(args: argparse.Namespace) -> int:
    """Evaluate the run(s), print the table, write the report."""
    from rapidfix.campaign import ball_positions, cube_runs, evaluate, registered, to_robot
    from rapidfix.kinematics import load_robot
    from rapidfix.measure import read_points, read_setup
    from rapidfix.report import Report, Table, write_report

    setup = read_setup(args.setup)
    robot = load_robot(setup.robot)
    reg = _registration(args.model) if args.model else None
    results: dict[str, dict[str, Any]] = {}
    for label, path in (("before", args.before), ("after", args.after)):
        if path is None:
            continue
        table = read_points(path)
        runs = cube_runs(table, ball_positions(robot, table.q, setup.smr_offset_mm))
        if reg is not None:
            results[f"{label}, robot frame"] = evaluate(to_robot(runs, *reg))
        results[f"{label}, registered"] = evaluate(registered(runs))
    if not results:
        raise RapidfixError("nothing to report")
    keys = list(results)
    report = Report("rapidfix ISO 9283 report", summary={"runs": results})
    report.notes.append("ISO 9283:1998: cube on the most used part of the work space, poses "
                        "P1-P5 on its diagonal plane (P2-P5 at 10 % of the diagonal from the "
                        "corners), cycles P1, P5, P4, P3, P2 (30 by the standard); AP = "
                        "|barycentre - commanded|, RP = mean(l) + 3 S_l, AD = mean(D) - Dc, "
                        "RD = 3 S_D (7.2.1, 7.2.2, 7.5.1, 7.5.2). Positions only, mm.")
    if reg is None:
        report.notes.append("No --model: the robot-frame figures need the sweep registration.")
    report.tables.append(Table(
        "Pose accuracy AP and repeatability RP (mm)",
        ["pose", *[f"AP {k}" for k in keys], *[f"RP {k}" for k in keys]],
        [[f"P{i + 1}", *[results[k]["poses"][i]["AP_mm"] for k in keys],
          *[results[k]["poses"][i]["RP_mm"] for k in keys]] for i in range(5)]))
    report.tables.append(Table(
        "Distance accuracy AD and repeatability RD (mm); ISO 9283 uses P2-P4",
        ["pair", "Dc", *[f"AD {k}" for k in keys], *[f"RD {k}" for k in keys]],
        [[d["pair"], d["Dc_mm"], *[results[k]["distances"][i]["AD_mm"] for k in keys],
          *[results[k]["distances"][i]["RD_mm"] for k in keys]]
         for i, d in enumerate(results[keys[0]]["distances"])]))
    report.figures.append(iso_figures(results))
    html_path, json_path = write_report(report, args.output, stem="iso9283")
    width = max(len(k) for k in keys) + 2
    print(f"{'':<{width}}" + "".join(f"{'AP P' + str(i + 1):>10}" for i in range(5))
          + f"{'RP max':>10}{'AD P2-P4':>10}")
    for k in keys:
        r = results[k]
        print(f"{k:<{width}}" + "".join(f"{p['AP_mm']:>10.4f}" for p in r["poses"])
              + f"{max(p['RP_mm'] for p in r['poses']):>10.4f}"
              + f"{r['distances'][0]['AD_mm']:>10.4f}")
    print(f"wrote {html_path} and {json_path}")
    return 0
