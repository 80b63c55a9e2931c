"""Fitting the per-joint error model from the sweep analysis.

Input: for each joint the commanded angles of its sweep, the measured joint error
Δθ = θ_actual − θ_commanded at each (repeats averaged) and the repeat spread —
what `rapidfix.measure.sweeps.analyse_sweeps` returns as `SweepAnalysis.joints`.
Output: an ErrorModel holding one `JointRBF` effect, with per-joint statistics
(range, cross-validated RMS, fit RMS, repeatability) in degrees.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from rapidfix.error_model.joint_rbf import JointRBF, RBFNetwork, fit_network
from rapidfix.error_model.model import ErrorModel
from rapidfix.exceptions import ModelError


class JointSweepLike(Protocol):
    """What the fitter reads from one joint's sweep (rapidfix.measure.sweeps.JointSweep)."""

    theta_cmd: np.ndarray
    delta: np.ndarray
    repeat_std: np.ndarray


#: a hole in a sweep wider than this many median steps is reported as a gap
GAP_STEPS = 2.5


def sweep_gaps(theta: np.ndarray) -> list[list[float]]:
    """Intervals [lo, hi] (rad) between consecutive measured angles wider than GAP_STEPS steps.

    The network interpolates across a gap but has no data there: a gear harmonic
    shorter than the gap cannot be known inside it.
    """
    x = np.unique(np.asarray(theta, dtype=float))
    if x.shape[0] < 3:
        return []
    steps = np.diff(x)
    wide = np.flatnonzero(steps > GAP_STEPS * np.median(steps))
    return [[float(x[i]), float(x[i + 1])] for i in wide]


def joint_statistics(
    j: int, sweep: JointSweepLike, net: RBFNetwork, width_factor: float
) -> dict[str, Any]:
    """Per-joint fit statistics in degrees (JSON-ready)."""
    x = np.asarray(sweep.theta_cmd, dtype=float)
    y = np.asarray(sweep.delta, dtype=float)
    spread = np.asarray(sweep.repeat_std, dtype=float)
    resid = net.value(x) - y
    return {
        "joint": j + 1,
        "points": int(x.shape[0]),
        "range_deg": [float(np.degrees(net.lo)), float(np.degrees(net.hi))],
        "max_abs_error_deg": float(np.degrees(np.abs(y).max())),
        "cv_rms_deg": float(np.degrees(net.cv_rms or 0.0)),
        "fit_rms_deg": float(np.degrees(np.sqrt(np.mean(resid**2)))),
        "residuals_deg": [float(v) for v in np.degrees(resid)],
        "repeatability_deg": (
            float(np.degrees(np.sqrt(np.nanmean(spread**2))))
            if np.isfinite(spread).any() else None  # one repeat: no spread known
        ),
        "width_deg": float(np.degrees(net.width)),
        "width_factor": width_factor,
        "smoothing": net.smoothing,
        "gaps_deg": [[float(np.degrees(a)), float(np.degrees(b))] for a, b in sweep_gaps(x)],
    }


def fit_joint_rbf(
    joints: Sequence[JointSweepLike | None],
    *,
    policy: str = "clamp",
    folds: int = 5,
) -> tuple[JointRBF, list[dict[str, Any]]]:
    """One cross-validated network per swept joint; joints without a sweep stay unmodelled."""
    if len(joints) != 6:
        raise ModelError(f"sweeps for 6 joints expected, got {len(joints)}")
    networks: list[RBFNetwork | None] = []
    stats: list[dict[str, Any]] = []
    for j, sweep in enumerate(joints):  # six joints
        if sweep is None or np.asarray(sweep.theta_cmd).size == 0:
            networks.append(None)
            stats.append({"joint": j + 1, "points": 0})
            continue
        x = np.asarray(sweep.theta_cmd, dtype=float)
        y = np.asarray(sweep.delta, dtype=float)
        finite = np.isfinite(x) & np.isfinite(y)
        if not finite.all():
            raise ModelError(f"joint {j + 1}: the sweep analysis gave non-finite errors")
        try:
            net, cv = fit_network(x, y, folds=folds)
        except ModelError as err:
            raise ModelError(f"joint {j + 1}: {err.message}", hint=err.hint) from None
        networks.append(net)
        stats.append(joint_statistics(j, sweep, net, cv.width_factor))
    if all(n is None for n in networks):
        raise ModelError("no joint was swept: nothing to fit")
    return JointRBF(networks, policy=policy), stats


def fit_error_model(
    robot_name: str,
    joints: Sequence[JointSweepLike | None],
    *,
    data_files: Sequence[dict[str, str]] = (),
    extra_statistics: dict[str, Any] | None = None,
    policy: str = "clamp",
) -> ErrorModel:
    """An ErrorModel with the per-joint RBF effect fitted on the sweeps."""
    effect, stats = fit_joint_rbf(joints, policy=policy)
    statistics: dict[str, Any] = {"joints": stats}
    if extra_statistics:
        statistics.update(extra_statistics)
    return ErrorModel(robot_name, [effect], statistics, list(data_files))
