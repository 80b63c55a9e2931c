"""The diagnosis' inputs: measured point sets as the fitter sees them, and the noise level.

A points file (calibration or validation) becomes `MeasuredPoints`: commanded
joints, tracker-frame positions, and the context each row ran under (payload from
the file or the setup's default, time, temperature, and the previous row's pose
for the motion direction, rows taken in file order).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rapidfix.error_model import Context, MeasuredPoints, last_motion_direction
from rapidfix.measure import PointTable, Setup, ball_offsets

#: per-axis tracker σ assumed when neither the model nor the setup states one (mm)
DEFAULT_SIGMA_MM = 0.01
#: mean length of a 3-D vector of independent N(0, σ²) coordinates, in units of σ
MEAN_NORM_PER_SIGMA = float(np.sqrt(8.0 / np.pi))


def measured_points(table: PointTable, setup: Setup) -> MeasuredPoints:
    """A points table as the fitter's input (payload defaults to the setup's)."""
    payload = table.payload_kg if table.payload_kg is not None else setup.payload_kg
    ctx = Context.from_rows(table.q, payload_kg=payload, time_s=table.time_s,
                            temp_c=table.temp_c)
    balls = None if table.ball is None else ball_offsets(table, setup)
    return MeasuredPoints(np.asarray(table.q, dtype=float), np.asarray(table.xyz, dtype=float),
                          ctx, np.asarray(setup.smr_offset_mm, dtype=float), balls)


def with_known_history(points: MeasuredPoints) -> MeasuredPoints:
    """The points reached after every joint has moved at least once within the set.

    Before that a joint's last direction of motion is unknown, so the side of its
    backlash is too: a first pose mispredicted by up to half the play would bend a
    fit, and the model cannot tell. Such points (usually only the first) are left out
    of fitting, and of scoring on the validation set, for every candidate alike (the
    report counts them): no model predicts them without their history.
    """
    known = (last_motion_direction(points.q, points.ctx.q_prev) != 0).all(axis=1)
    if known.all() or known.sum() < len(known) // 2:
        return points
    return points.take(known)


def noise_sigma_mm(statistics: dict[str, Any], setup: Setup) -> tuple[float, str]:
    """Per-axis measurement noise σ (mm) and where it came from.

    Best: the scatter the sweep analysis found (tracker noise and joint
    repeatability together, on the same tracker); else the setup's stated
    tracker σ; else a default.
    """
    sweep = statistics.get("sweep_analysis") if isinstance(statistics, dict) else None
    if isinstance(sweep, dict):
        value = sweep.get("noise_sigma_mm")
        if isinstance(value, (int, float)) and np.isfinite(value) and value > 0:
            return float(value), "scatter of the sweep measurements"
    if setup.tracker_sigma_mm:
        return float(setup.tracker_sigma_mm), "tracker σ stated in the setup"
    return DEFAULT_SIGMA_MM, "default (no σ stated)"
