"""The accuracy report: how the model was fitted and the error before and after compensation.

Sections (each optional): per-joint fit statistics with the paper's Figure 7,
the TCP position error on the validation points, and the ballbar test beside the
source paper's numbers. Inputs are plain arrays in degrees and mm; this module
knows nothing about how they were obtained (measured, predicted or simulated).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rapidfix.report.document import Report, Table
from rapidfix.report.figures import (
    ballbar_figure,
    joint_error_figure,
    position_error_figure,
)
from rapidfix.report.metrics import (
    PAPER_BALLBAR_MM,
    ballbar_stats,
    improvement,
    position_error_stats,
)


@dataclass(frozen=True)
class BeforeAfter:
    """Intended and reached positions (N, 3) mm without and with compensation."""

    intended: np.ndarray
    before: np.ndarray
    after: np.ndarray


@dataclass(frozen=True)
class BallbarRun:
    """Ballbar length deviations (N,) mm along the semicircle (angles in degrees)."""

    angle_deg: np.ndarray
    before_mm: np.ndarray
    after_mm: np.ndarray


def fit_table(joint_stats: Sequence[dict[str, Any]]) -> Table:
    """Per-joint fit statistics (from rapidfix.error_model.fit) as a table."""
    rows = []
    for s in joint_stats:
        if not s.get("points"):
            rows.append([f"J{s['joint']}", "not measured", 0, None, None, None, None])
            continue
        lo, hi = s["range_deg"]
        rows.append([f"J{s['joint']}", f"{lo:.1f} … {hi:.1f}", s["points"],
                     s["max_abs_error_deg"], s["cv_rms_deg"], s["repeatability_deg"],
                     s["width_deg"]])
    return Table(
        "Joint error model (per joint)",
        ["joint", "valid range (°)", "points", "max |Δθ| (°)", "CV RMS (°)",
         "repeatability (°)", "RBF width (°)"],
        rows,
        "CV RMS: k-fold cross-validated prediction error of the network between sweep "
        "points. Repeatability: RMS standard deviation of the repeated measurements.",
    )


def validation_section(run: BeforeAfter) -> tuple[Table, dict[str, Any]]:
    """The before/after TCP error table and its numbers."""
    before = position_error_stats(run.intended, run.before)
    after = position_error_stats(run.intended, run.after)
    rows = []
    for label, s in (("before", before), ("after", after)):
        axes = s["per_axis"]
        rows.append([label, s["mean_mm"], s["rms_mm"], s["max_mm"], axes["x"]["rms_mm"],
                     axes["y"]["rms_mm"], axes["z"]["rms_mm"]])
    gain = improvement(before["mean_mm"], after["mean_mm"])
    table = Table(
        f"TCP position error on {before['points']} validation points (mm)",
        ["", "mean", "RMS", "max", "RMS x", "RMS y", "RMS z"],
        rows,
        f"Mean error reduced by {100 * gain:.1f} %.",
    )
    return table, {"before": before, "after": after, "mean_reduction": gain}


def ballbar_section(run: BallbarRun) -> tuple[Table, dict[str, Any]]:
    """The ballbar table with the paper's numbers beside ours."""
    before = ballbar_stats(run.before_mm)
    after = ballbar_stats(run.after_mm)
    paper = PAPER_BALLBAR_MM
    rows = [
        ["max |deviation|", before["max_mm"], after["max_mm"], paper["before"]["max_mm"],
         paper["after"]["max_mm"]],
        ["mean |deviation|", before["mean_mm"], after["mean_mm"], paper["before"]["mean_mm"],
         paper["after"]["mean_mm"]],
    ]
    table = Table(
        f"Ballbar test, {len(run.angle_deg)} points (mm)",
        ["", "before", "after", "paper before", "paper after"],
        rows,
        "The paper's values are for its own IRB 1600 and ballbar, shown for reference.",
    )
    return table, {"before": before, "after": after, "paper": paper}


def accuracy_report(
    title: str,
    *,
    joint_stats: Sequence[dict[str, Any]] | None = None,
    joint_curves: Sequence[dict[str, np.ndarray] | None] | None = None,
    validation: BeforeAfter | None = None,
    ballbar: BallbarRun | None = None,
    notes: Sequence[str] = (),
    summary: dict[str, Any] | None = None,
) -> Report:
    """Assemble the report from whichever sections are given."""
    report = Report(title, dict(summary or {}), notes=list(notes))
    if validation is not None:
        table, numbers = validation_section(validation)
        report.tables.append(table)
        report.summary["validation"] = numbers
        report.figures.append(position_error_figure(validation.before - validation.intended,
                                                     validation.after - validation.intended))
    if ballbar is not None:
        table, numbers = ballbar_section(ballbar)
        report.tables.append(table)
        report.summary["ballbar"] = numbers
        report.figures.append(ballbar_figure(ballbar.angle_deg, ballbar.before_mm,
                                             ballbar.after_mm, PAPER_BALLBAR_MM))
    if joint_stats is not None:
        report.tables.append(fit_table(joint_stats))
        report.summary["joints"] = list(joint_stats)
    if joint_curves is not None:
        report.figures.append(joint_error_figure(joint_curves))
    return report
