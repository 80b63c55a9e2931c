"""Accuracy figures of merit: TCP position error statistics and ballbar length deviation.

All inputs and outputs in mm. A position error is reached − intended, per axis in
the robot base frame. The ballbar measures the distance from a fixed pivot to
the target ball along a circle of nominal radius R: its length deviation at a
point is |p − c| − R; the reported maximum and mean are of its absolute value.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: the source paper's ballbar result (mm), shown beside ours for reference
PAPER_BALLBAR_MM = {
    "before": {"max_mm": 0.7582, "mean_mm": 0.2456},
    "after": {"max_mm": 0.2593, "mean_mm": 0.0716},
}


def position_error_stats(intended: np.ndarray, reached: np.ndarray) -> dict[str, Any]:
    """Mean, RMS and max of |error| and, per axis, mean, RMS and max |error| (mm)."""
    err = np.asarray(reached, dtype=float) - np.asarray(intended, dtype=float)
    norm = np.linalg.norm(err, axis=1)
    per_axis = {
        axis: {
            "mean_mm": float(np.mean(err[:, i])),
            "rms_mm": float(np.sqrt(np.mean(err[:, i] ** 2))),
            "max_abs_mm": float(np.abs(err[:, i]).max()),
        }
        for i, axis in enumerate("xyz")
    }
    return {
        "points": int(err.shape[0]),
        "mean_mm": float(norm.mean()),
        "rms_mm": float(np.sqrt(np.mean(norm**2))),
        "max_mm": float(norm.max()),
        "per_axis": per_axis,
    }


def ballbar_deviation(points: np.ndarray, centre: np.ndarray, radius_mm: float) -> np.ndarray:
    """Signed length deviation |p − c| − R (N,) mm of ball centres p (N, 3)."""
    d = np.asarray(points, dtype=float) - np.asarray(centre, dtype=float)
    return np.linalg.norm(d, axis=1) - float(radius_mm)


def ballbar_stats(deviation: np.ndarray) -> dict[str, float]:
    """Maximum and mean absolute length deviation (mm), as the paper reports them."""
    dev = np.abs(np.asarray(deviation, dtype=float))
    return {"max_mm": float(dev.max()), "mean_mm": float(dev.mean())}


def improvement(before: float, after: float) -> float:
    """Relative reduction (0..1) from before to after; 0 when before is 0."""
    return 0.0 if before <= 0 else 1.0 - after / before
