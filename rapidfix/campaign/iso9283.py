"""Pose and distance accuracy and repeatability in the terms of ISO 9283:1998.

Source: ISO 9283:1998 "Manipulating industrial robots — Performance criteria and
related test methods".

- Test cube and poses (6.2): a cube in the most used part of the work space, as
  large as it allows, edges parallel to the base frame; five poses on its
  diagonal plane C1-C2-C7-C8: P1 at the centre, P2–P5 on the diagonals at 10 % of
  the diagonal's length from the corners (`rapidfix.campaign.poses.iso_points`).
- Cycles (7.2.1): 30, each visiting P1, P5, P4, P3, P2, every pose approached
  the same way.
- Pose accuracy (7.2.1): AP = √((x̄ − x_c)² + (ȳ − y_c)² + (z̄ − z_c)²), the distance
  from the commanded position to the barycentre of the n attained ones; also per
  axis (AP_x = x̄ − x_c, …).
- Pose repeatability (7.2.2): RP = l̄ + 3 S_l, with l_j the distance of attained
  position j from the barycentre, l̄ their mean and
  S_l = √(Σ (l_j − l̄)² / (n − 1)).
- Distance accuracy (7.5.1): AD = D̄ − D_c, D_j = |P_a,j − P_b,j| the attained
  distance between two poses in cycle j, D_c the commanded one; distance
  repeatability (7.5.2) RD = ±3 S_D, S_D = √(Σ (D_j − D̄)² / (n − 1)). The standard
  measures it between P2 and P4 (reported first); the other pairs are added.

Positions only (the ball of a laser tracker), mm. "Robot frame": the tracker's
points mapped into the robot base frame with the registration of the campaign's
sweeps (the model file carries it); "registered": after the best rigid fit of all
attained points onto the commanded ones, which leaves only what a cell
calibration cannot absorb.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np

from rapidfix.exceptions import MeasurementError
from rapidfix.measure import PointTable, rigid_fit

PAIR_ORDER = [(2, 4)] + [p for p in combinations(range(1, 6), 2) if p != (2, 4)]


@dataclass(frozen=True)
class CubeRuns:
    """Commanded positions (5, 3) of P1..P5 and attained ones (C, 5, 3), C cycles."""

    commanded: np.ndarray
    attained: np.ndarray


def cube_runs(table: PointTable, commanded_by_row: np.ndarray) -> CubeRuns:
    """Group a measured ISO table (columns `cycle`, `iso_pose`) into cycles × poses.

    `commanded_by_row` (N, 3): each row's commanded position. Cycles missing a pose
    are an error naming the table."""
    for name in ("cycle", "iso_pose"):
        if name not in table.extra:
            raise MeasurementError("missing column (an ISO 9283 table from `rapidfix "
                                   "import` has cycle and iso_pose)", file=table.path, row=1,
                                   column=name)
    cycle = table.extra["cycle"].astype(int)
    pose = table.extra["iso_pose"].astype(int)
    bad = (pose < 1) | (pose > 5)
    if bad.any():
        i = int(np.argmax(bad))
        raise MeasurementError("iso_pose must be 1..5", file=table.path,
                               row=int(table.rows[i]), column="iso_pose")
    cycles = np.unique(cycle)
    grid = np.full((len(cycles), 5, 3), np.nan)
    grid[np.searchsorted(cycles, cycle), pose - 1] = table.xyz
    complete = ~np.isnan(grid).any(axis=(1, 2))
    if complete.sum() < 2:
        raise MeasurementError("fewer than two complete cycles of P1-P5", file=table.path)
    commanded = np.full((5, 3), np.nan)
    commanded[pose - 1] = commanded_by_row
    return CubeRuns(commanded, grid[complete])


def pose_accuracy(runs: CubeRuns) -> dict[str, np.ndarray]:
    """AP (5,), AP per axis (5, 3), RP (5,), l̄ and S_l (5,), all mm."""
    bary = runs.attained.mean(axis=0)
    ap_xyz = bary - runs.commanded
    ap = np.linalg.norm(ap_xyz, axis=1)
    l = np.linalg.norm(runs.attained - bary, axis=2)  # (C, 5)  # noqa: E741
    l_mean = l.mean(axis=0)
    s_l = l.std(axis=0, ddof=1)
    return {"AP": ap, "AP_xyz": ap_xyz, "RP": l_mean + 3.0 * s_l, "l_mean": l_mean, "S_l": s_l}


def distance_accuracy(runs: CubeRuns) -> list[dict[str, Any]]:
    """AD and RD for every pair of poses, P2–P4 first."""
    out = []
    for a, b in PAIR_ORDER:
        d_c = float(np.linalg.norm(runs.commanded[a - 1] - runs.commanded[b - 1]))
        d = np.linalg.norm(runs.attained[:, a - 1] - runs.attained[:, b - 1], axis=1)
        out.append({"pair": f"P{a}-P{b}", "Dc_mm": d_c, "AD_mm": float(d.mean() - d_c),
                    "RD_mm": float(3.0 * d.std(ddof=1))})
    return out


def registered(runs: CubeRuns) -> CubeRuns:
    """The attained points after the best rigid fit onto the commanded ones."""
    cmd = np.broadcast_to(runs.commanded, runs.attained.shape).reshape(-1, 3)
    R, t = rigid_fit(cmd, runs.attained.reshape(-1, 3))
    return CubeRuns(runs.commanded, (runs.attained - t) @ R)


def to_robot(runs: CubeRuns, R: np.ndarray, t: np.ndarray) -> CubeRuns:
    """Tracker-frame runs in the robot frame (p_tracker = R p_robot + t)."""
    return CubeRuns(runs.commanded, (runs.attained - t) @ R)


def evaluate(runs: CubeRuns) -> dict[str, Any]:
    """JSON-ready pose and distance figures of one run."""
    pa = pose_accuracy(runs)
    return {"cycles": int(runs.attained.shape[0]),
            "poses": [{"pose": f"P{k + 1}", "AP_mm": float(pa["AP"][k]),
                       "AP_xyz_mm": pa["AP_xyz"][k].tolist(), "RP_mm": float(pa["RP"][k]),
                       "l_mean_mm": float(pa["l_mean"][k]), "S_l_mm": float(pa["S_l"][k])}
                      for k in range(5)],
            "distances": distance_accuracy(runs)}
