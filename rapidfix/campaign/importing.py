"""`rapidfix import` as a function: a tracker export and a pose table to measurement files.

Reads both, matches them (`rapidfix.campaign.matching`), and writes the measurement
set only when nothing is wrong: otherwise the result carries every problem, the
command prints them and nothing is written (missing poses are a problem unless
allowed, then a warning).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rapidfix.campaign.matching import Matching, match_export
from rapidfix.campaign.measurement_set import FILES, measurement_tables, write_measurement_set
from rapidfix.campaign.pose_table import read_plan_meta, read_pose_table
from rapidfix.campaign.tracker_export import read_export
from rapidfix.exceptions import MeasurementError, OutputExistsError, RapidfixError
from rapidfix.kinematics import load_robot
from rapidfix.measure import PointTable, Setup, SweepTable


@dataclass
class ImportResult:
    """What was matched and written (`paths` empty when there were problems)."""

    match: Matching
    tables: dict[str, SweepTable | PointTable] = field(default_factory=dict)
    paths: list[Path] = field(default_factory=list)
    problems: list[MeasurementError] = field(default_factory=list)
    poses: int = 0


def import_export(export_path: str | Path, poses_path: str | Path, out_dir: str | Path, *,
                  mode: str = "auto", units: str | None = None,
                  columns: list[str] | None = None, time_tolerance_s: float = 0.3,
                  robot: str | None = None, smr_offset_mm: list[float] | None = None,
                  allow_missing: bool = False, write_setup: bool = True,
                  overwrite: bool = False) -> ImportResult:
    """Match and, when nothing is wrong, write (see module doc)."""
    poses_path = Path(poses_path)
    table = read_pose_table(poses_path)
    meta = read_plan_meta(poses_path)
    robot_name = robot or meta.get("robot")
    smr = smr_offset_mm if smr_offset_mm is not None else meta.get("smr_offset_mm")
    if robot_name is None or smr is None:
        raise RapidfixError("no plan.toml beside the pose table: give --robot and --smr-offset")
    out = Path(out_dir)
    existing = [n for n in (*FILES.values(), "setup.toml") if (out / n).exists()]
    if existing and not overwrite:
        raise OutputExistsError(f"the folder already holds {', '.join(existing)}", file=out,
                                hint="choose another folder or pass --force")
    export = read_export(export_path, columns=columns)
    model = load_robot(robot_name)
    smr_a = np.asarray(smr, dtype=float)
    match = match_export(export, table, model, smr_a, mode=mode, units=units,
                         time_tolerance_s=time_tolerance_s)
    result = ImportResult(match, problems=list(match.problems), poses=len(table))
    missing = match.missing
    if missing and not allow_missing:
        shown = ", ".join(missing[:10]) + (f" and {len(missing) - 10} more"
                                           if len(missing) > 10 else "")
        result.problems.append(MeasurementError(
            f"{len(missing)} poses of the pose table were not measured: {shown}",
            file=export.path, hint="--allow-missing writes the rest"))
    if result.problems:
        return result
    result.tables = measurement_tables(match, table, export)
    setup = Setup(robot=model.name, smr_offset_mm=smr_a) if write_setup else None
    result.paths = write_measurement_set(out, result.tables, setup)
    return result
