"""Which measured point is which pose: a tracker export matched to the pose table.

Three ways, chosen automatically (or by the user):

- by id — the export's ids are the pose table's point ids (the program wrote them
  with TPWrite, or the operator named the points): ids not in the table,
  duplicated ids and points out of execution order are errors;
- by time — the export has timestamps: each must fall in a pose's settled window
  [t_trigger_s, t_leave_s] of the plan's schedule. The tracker's clock origin is
  found from the first points, and the mapping is re-anchored at every matched
  point, so the schedule's error (allowed: the tolerance plus 15 % of the motion
  time) does not accumulate; after a `Stop` (payload change, any duration) the
  next point is the next pose. A timestamp between two windows is a point measured
  while the robot was still moving; one before its window's settle time, one
  taken before the robot settled;
- by order — neither: the export's rows are the table's rows, one for one.

Units (mm, m, inch) are decided by comparing the distances between consecutive
measured points with the distances the plan's poses put between them (invariant
to where the tracker stands); a header that names other units is an error.
Nothing is dropped silently: every problem names the export's row and column, or
the pose table's point id.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rapidfix.campaign.pose_table import PoseTable
from rapidfix.campaign.poses import ball_positions
from rapidfix.campaign.tracker_export import UNITS_MM, TrackerExport
from rapidfix.exceptions import MeasurementError
from rapidfix.kinematics import RobotModel

MODES = ("auto", "id", "time", "order")
#: share of the planned motion time since the last matched point a timestamp may be off
TIME_DRIFT = 0.15
#: measured/planned distance ratios closer than this (relative) to a unit's are that unit
UNIT_TOLERANCE = 0.02


@dataclass
class Matching:
    """Export row `export_index[k]` is pose-table row `table_index[k]`; positions in mm."""

    table_index: np.ndarray
    export_index: np.ndarray
    xyz_mm: np.ndarray
    mode: str
    unit: str
    assumptions: list[str] = field(default_factory=list)
    problems: list[MeasurementError] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)


def _problem(export: TrackerExport, i: int | None, role: str | None, message: str
             ) -> MeasurementError:
    column = export.columns.get(role) if role else None
    row = int(export.rows[i]) if i is not None else None
    return MeasurementError(message, file=export.path, row=row, column=column)


def _by_id(export: TrackerExport, table: PoseTable, problems: list) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    index = table.index()
    seen: dict[int, int] = {}
    t_rows, e_rows = [], []
    last = -1
    for i, pid in enumerate(export.ids.tolist()):
        k = index.get(pid)
        if k is None:
            problems.append(_problem(export, i, "id", f"point id {pid!r} is not in the pose "
                                     f"table {table.path.name if table.path else ''}".rstrip()))
            continue
        if k in seen:
            problems.append(_problem(export, i, "id", f"point {pid} measured twice (first "
                                     f"in row {int(export.rows[seen[k]])})"))
            continue
        if k < last:
            problems.append(_problem(export, i, "id", f"points in the wrong order: {pid} "
                                     f"comes after {table.point_id[last]}, which the robot "
                                     "measures later"))
        seen[k] = i
        last = max(last, k)
        t_rows.append(k)
        e_rows.append(i)
    return np.array(t_rows, dtype=int), np.array(e_rows, dtype=int)


def _by_time(export: TrackerExport, table: PoseTable, tol: float, problems: list
             ) -> tuple[np.ndarray, np.ndarray]:
    """Sequential matching on the plan's schedule, re-anchored at every matched point.

    From the last matched point (the anchor) the schedule of the next poses is trusted
    to `tol` plus `TIME_DRIFT` of the motion time since the anchor; a pose after a
    `Stop` takes any time after its predecessor was left (the pause has no duration).
    """
    t = export.time_s
    arrive, trig, leave = (table.times[c] for c in ("t_arrive_s", "t_trigger_s", "t_leave_s"))
    pause = table.ints["pause_before"].astype(bool)
    n = len(table)
    offset = _first_offset(t, arrive, trig, leave, tol)
    anchor = float(trig[0]) - float(arrive[0])  # plan time of the anchor
    t_rows, e_rows = [], []
    j_next = 0
    for i in range(len(t)):
        tau = t[i] - offset
        k = j_next
        while k < n:
            if pause[k] and k > 0:
                if tau > leave[k - 1] + tol:  # after a Stop: the first point is this pose
                    offset += tau - trig[k]
                    tau = trig[k]
                break
            slack = tol + TIME_DRIFT * max(0.0, arrive[k] - anchor)
            if tau <= leave[k] + slack:
                break
            k += 1
        if k >= n:
            problems.append(_problem(export, i, "time", f"measured {tau - leave[-1]:.1f} s "
                                     "after the robot left the last pose: an extra point"))
            continue
        slack = tol + TIME_DRIFT * max(0.0, arrive[k] - anchor)
        if tau < arrive[k] - slack:
            if k == j_next and k > 0 and tau <= leave[k - 1]:
                problems.append(_problem(export, i, "time", "a second measurement of "
                                         f"{table.point_id[k - 1]}"))
            else:
                problems.append(_problem(export, i, "time", "measured while the robot was "
                                         f"still moving ({arrive[k] - tau:.2f} s before it "
                                         f"reached {table.point_id[k]})"))
            continue
        if tau < trig[k] - slack:
            problems.append(_problem(export, i, "time", "measured while the robot was still "
                                     f"settling at {table.point_id[k]} ({trig[k] - tau:.2f} s "
                                     "before its settle time ended)"))
            j_next = k + 1
            continue
        t_rows.append(k)
        e_rows.append(i)
        j_next = k + 1
        offset = t[i] - trig[k]
        anchor = float(trig[k])
    return np.array(t_rows, dtype=int), np.array(e_rows, dtype=int)


def _first_offset(t: np.ndarray, arrive: np.ndarray, trig: np.ndarray, leave: np.ndarray,
                  tol: float) -> float:
    """The tracker clock at the plan's zero: the alignment of one of the first three
    points with one of the first three poses that puts most of the first 30 points in a
    pose's still window."""
    n = len(trig)
    head = t[:30]
    best, offset = -1, float(t[0] - trig[0])
    for i in range(min(3, len(t))):
        for j in range(min(3, n)):
            off = t[i] - trig[j]
            k = np.searchsorted(leave + tol, head - off)
            inside = (k < n) & (head - off >= arrive[np.minimum(k, n - 1)] - tol)
            if inside.sum() > best:
                best, offset = int(inside.sum()), float(off)
    return offset


def _moving_by_time(export: TrackerExport, table: PoseTable, t_rows: np.ndarray,
                    e_rows: np.ndarray, tol: float, problems: list) -> np.ndarray:
    """With ids and timestamps: flag points measured before their pose was settled.

    The clock offset is the running median of (time − planned trigger) over 11 points,
    so a drifting schedule does not matter; returns the mask of points kept."""
    if len(t_rows) < 3:
        return np.ones(len(t_rows), dtype=bool)
    off = export.time_s[e_rows] - table.times["t_trigger_s"][t_rows]
    pad = np.pad(off, 5, mode="edge")
    local = np.median(np.lib.stride_tricks.sliding_window_view(pad, 11), axis=1)
    early = (off - local) < -tol
    for k in np.flatnonzero(early):
        problems.append(_problem(export, int(e_rows[k]), "time", "measured while the robot "
                                 f"was still moving or settling at "
                                 f"{table.point_id[t_rows[k]]} ({local[k] - off[k]:.2f} s "
                                 "early)"))
    return ~early


def _unit(export: TrackerExport, table: PoseTable, robot: RobotModel, smr_mm: np.ndarray,
          t_rows: np.ndarray, e_rows: np.ndarray, stated: str | None) -> tuple[str, str]:
    nominal = ball_positions(robot, table.q[t_rows], smr_mm)
    d_nom = np.linalg.norm(np.diff(nominal, axis=0), axis=1)
    d_meas = np.linalg.norm(np.diff(export.xyz[e_rows], axis=0), axis=1)
    use = d_nom > 10.0
    if use.sum() < 3:
        raise MeasurementError("too few matched points to check the units", file=export.path)
    ratio = float(np.median(d_meas[use] / d_nom[use]))
    found = min(UNITS_MM, key=lambda u: abs(np.log(ratio * UNITS_MM[u])))
    if abs(np.log(ratio * UNITS_MM[found])) > UNIT_TOLERANCE:
        raise MeasurementError(
            f"distances between the points are {ratio:.4g}× those the plan's poses put "
            "between them: not mm, m or inch — a pose table from another plan, another "
            "ball offset, or the wrong robot?", file=export.path, row=int(export.rows[0]),
            column=export.columns.get("x"))
    if stated is not None and stated != found:
        raise MeasurementError(
            f"units are {found}, not {stated}: the distances between points match the plan in "
            f"{found} (ratio {ratio * UNITS_MM[found]:.4f})", file=export.path,
            row=int(export.rows[0]), column=export.columns.get("x"))
    how = "as stated" if stated else "detected"
    return found, (f"units {found} ({how}: distances match the plan's to "
                   f"{100 * abs(ratio * UNITS_MM[found] - 1):.2f} %)")


def match_export(export: TrackerExport, table: PoseTable, robot: RobotModel,
                 smr_mm: np.ndarray, *, mode: str = "auto", units: str | None = None,
                 time_tolerance_s: float = 0.3) -> Matching:
    """Match (see module doc); problems are collected, not raised."""
    problems: list[MeasurementError] = []
    assumptions = list(export.assumptions)
    if mode == "auto":
        ids_known = (export.ids is not None
                     and np.mean(np.isin(export.ids, table.point_id)) >= 0.5)
        mode = "id" if ids_known else "time" if export.time_s is not None else "order"
        assumptions.append(f"matched by {mode}")
    if mode == "id":
        if export.ids is None:
            raise MeasurementError("no id column to match by", file=export.path)
        t_rows, e_rows = _by_id(export, table, problems)
        if export.time_s is not None:
            keep = _moving_by_time(export, table, t_rows, e_rows, time_tolerance_s, problems)
            t_rows, e_rows = t_rows[keep], e_rows[keep]
    elif mode == "time":
        if export.time_s is None:
            raise MeasurementError("no time column to match by", file=export.path)
        back = np.flatnonzero(np.diff(export.time_s) < 0)
        if back.size:
            i = int(back[0]) + 1
            raise MeasurementError("points in the wrong order: the time goes back",
                                   file=export.path, row=int(export.rows[i]),
                                   column=export.columns.get("time"))
        t_rows, e_rows = _by_time(export, table, time_tolerance_s, problems)
    elif mode == "order":
        if len(export) != len(table):
            raise MeasurementError(f"{len(export)} points in the export, {len(table)} poses "
                                   "in the pose table: matching by order needs one each",
                                   file=export.path)
        t_rows = e_rows = np.arange(len(table))
    else:
        raise MeasurementError(f"unknown matching {mode!r}", file=export.path)
    unit_stated = units or export.unit
    unit, said = _unit(export, table, robot, smr_mm, t_rows, e_rows, unit_stated)
    assumptions.append(said)
    missing = [str(table.point_id[k]) for k in np.setdiff1d(np.arange(len(table)), t_rows)]
    return Matching(t_rows, e_rows, export.xyz[e_rows] * UNITS_MM[unit], mode, unit,
                    assumptions, problems, missing)
