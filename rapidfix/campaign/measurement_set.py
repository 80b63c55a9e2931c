"""A matched tracker export as measurement files: sweeps, calibration, validation and
ISO 9283 tables in the project's format (`rapidfix.measure.files`), rows in the
pose table's (execution) order.

When the program approached poses from both sides (`rapidfix plan --approach
both`), every table gets the pose table's `approach` and `approach_joints`
columns: the rows' order alone would give the wrong direction of arrival for the
joints an approach move turned, and the sweep analysis reads them to fit each
joint's backlash. With one side only the play cannot be seen in the data and the
columns are left out: the analysis then runs exactly as on any sweep file (rows
in order), like the virtual cell's direct route."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rapidfix.campaign.matching import Matching
from rapidfix.campaign.pose_table import PoseTable
from rapidfix.campaign.tracker_export import TrackerExport
from rapidfix.measure import PointTable, Setup, SweepTable, write_points, write_setup, write_sweeps

FILES = {"sweep": "sweeps.csv", "calibration": "calibration.csv",
         "validation": "validation.csv", "iso9283": "iso9283.csv"}


def measurement_tables(match: Matching, table: PoseTable, export: TrackerExport
                       ) -> dict[str, SweepTable | PointTable]:
    """One table per set present, in execution order."""
    order = np.argsort(match.table_index, kind="stable")
    rows_t, rows_e = match.table_index[order], match.export_index[order]
    xyz = match.xyz_mm[order]
    payload_varies = bool(np.any(table.payload_kg != table.payload_kg[0])
                          or table.payload_kg[0] != 0)
    approached = bool(np.any(table.ints["approach"] > 0) and np.any(table.ints["approach"] < 0))
    out: dict[str, SweepTable | PointTable] = {}
    for name in FILES:
        sel = table.set_name[rows_t] == name
        if not sel.any():
            continue
        t, e = rows_t[sel], rows_e[sel]
        cond = {
            "payload_kg": table.payload_kg[t] if payload_varies else None,
            "time_s": None if export.time_s is None else export.time_s[e] - export.time_s[0],
            "temp_c": None if export.temp_c is None else export.temp_c[e],
        }
        file_rows = np.arange(len(t)) + 2
        extra = {}
        if approached:  # which joints an approach move turned (rapidfix.measure.sweeps)
            extra = {"approach": table.ints["approach"][t].astype(float),
                     "approach_joints": table.ints["approach_joints"][t].astype(float)}
        if name == "sweep":
            out[name] = SweepTable(sweep_joint=table.ints["sweep_joint"][t] - 1, q=table.q[t],
                                   repeat=table.ints["repeat"][t], xyz=xyz[sel], rows=file_rows,
                                   extra=extra, **cond)
        else:
            if name == "iso9283":
                extra.update({"cycle": table.ints["cycle"][t].astype(float),
                              "iso_pose": table.ints["iso_pose"][t].astype(float)})
            out[name] = PointTable(point_id=table.point_id[t], q=table.q[t], xyz=xyz[sel],
                                   rows=file_rows, extra=extra, **cond)
    return out


def write_measurement_set(out_dir: str | Path, tables: dict[str, SweepTable | PointTable],
                          setup: Setup | None) -> list[Path]:
    """Write the tables (and setup.toml when given) atomically; returns the paths."""
    out = Path(out_dir)
    written = []
    if setup is not None:
        written.append(write_setup(out / "setup.toml", setup))
    for name, tab in tables.items():
        path = out / FILES[name]
        if isinstance(tab, SweepTable):
            written.append(write_sweeps(path, tab))
        else:
            written.append(write_points(path, tab))
    return written
