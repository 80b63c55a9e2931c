"""The pose table: every measured pose of a campaign, in execution order (CSV).

Columns: ``point_id,set,j1..j6,payload_kg`` then ``sweep_joint,repeat`` (sweeps),
``iso_pose,cycle`` (ISO 9283 cube), ``approach`` (+1 or −1 when an approach move
comes before the pose, 0 when none does), ``approach_joints`` (the joints that move
turns, bit j−1 for joint j: they arrive moving up (+1) or down (−1); the others as
the previous pose left them), ``pause_before`` (1 when the
program stops for the operator before this pose, e.g. to change the payload) and
the planned schedule ``t_arrive_s,t_trigger_s,t_leave_s`` (s from the start; the
robot is settled in [t_trigger_s, t_leave_s]). Joints in degrees, payload kg.
"""

from __future__ import annotations

import csv
import io
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.atomic import write_text_atomic
from rapidfix.exceptions import MeasurementError
from rapidfix.measure import read_measurement_text

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
INT_COLUMNS = ("sweep_joint", "repeat", "iso_pose", "cycle", "approach", "approach_joints",
               "pause_before")
TIME_COLUMNS = ("t_arrive_s", "t_trigger_s", "t_leave_s")
COLUMNS = ("point_id", "set", *JOINTS, "payload_kg", *INT_COLUMNS, *TIME_COLUMNS)
SETS = ("sweep", "calibration", "validation", "iso9283")


@dataclass
class PoseTable:
    """The pose table as arrays; `q` in radians, `rows` the file's line numbers."""

    point_id: np.ndarray
    set_name: np.ndarray
    q: np.ndarray
    payload_kg: np.ndarray
    ints: dict[str, np.ndarray]
    times: dict[str, np.ndarray]
    rows: np.ndarray
    path: Path | None = None

    def __len__(self) -> int:
        return len(self.point_id)

    def index(self) -> dict[str, int]:
        """Row index of each point id."""
        return {str(pid): i for i, pid in enumerate(self.point_id)}


def write_pose_table(path: str | Path, table: PoseTable) -> Path:
    """Write the table atomically (joints 1e-6°, times 1 ms)."""
    q = np.degrees(table.q)
    lines = [",".join(COLUMNS)]
    for i in range(len(table)):
        cells = [table.point_id[i], table.set_name[i], *(f"{v:.6f}" for v in q[i]),
                 f"{table.payload_kg[i]:.3f}", *(str(int(table.ints[c][i])) for c in INT_COLUMNS),
                 *(f"{table.times[c][i]:.3f}" for c in TIME_COLUMNS)]
        lines.append(",".join(cells))
    return write_text_atomic(path, "\n".join(lines) + "\n")


def read_pose_table(path: str | Path) -> PoseTable:
    """Read and check a pose table; any problem names the file, row and column."""
    path = Path(path)
    text = read_measurement_text(path, "pose table")
    reader = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    records: list[list[str]] = []
    rows: list[int] = []
    for record in reader:
        if not record or all(not c.strip() for c in record):
            continue
        if header is None:
            header = [c.strip().lower() for c in record]
            for name in ("point_id", "set", *JOINTS):
                if name not in header:
                    raise MeasurementError("missing column", file=path, row=reader.line_num,
                                           column=name)
            continue
        if len(record) != len(header):
            raise MeasurementError(f"expected {len(header)} fields like the header, found "
                                   f"{len(record)}", file=path, row=reader.line_num)
        records.append([c.strip() for c in record])
        rows.append(reader.line_num)
    if header is None or not records:
        raise MeasurementError("no poses in the pose table", file=path)
    col = {name: [r[header.index(name)] for r in records] for name in header}

    def numbers(name: str, default: float | None = None) -> np.ndarray:
        if name not in col:
            if default is None:
                raise MeasurementError("missing column", file=path, row=1, column=name)
            return np.full(len(records), default)
        out = np.empty(len(records))
        for i, cell in enumerate(col[name]):
            try:
                out[i] = float(cell)
            except ValueError:
                out[i] = np.nan
            if not np.isfinite(out[i]):
                raise MeasurementError(f"{cell!r} is not a number", file=path, row=rows[i],
                                       column=name)
        return out

    ids = np.array(col["point_id"], dtype=object)
    seen: dict[str, int] = {}
    for i, pid in enumerate(ids):
        if not pid:
            raise MeasurementError("empty point_id", file=path, row=rows[i], column="point_id")
        if pid in seen:
            raise MeasurementError(f"point_id {pid!r} already used in row {seen[pid]}",
                                   file=path, row=rows[i], column="point_id")
        seen[pid] = rows[i]
    sets = np.array(col["set"], dtype=object)
    for i, s in enumerate(sets):
        if s not in SETS:
            raise MeasurementError(f"unknown set {s!r} (one of {', '.join(SETS)})", file=path,
                                   row=rows[i], column="set")
    q = np.radians(np.column_stack([numbers(c) for c in JOINTS]))
    ints = {c: numbers(c, 0.0).astype(int) for c in INT_COLUMNS}
    times = {c: numbers(c, 0.0) for c in TIME_COLUMNS}
    for set_name, column, low, high in (("sweep", "sweep_joint", 1, 6),
                                        ("sweep", "repeat", 1, None),
                                        ("iso9283", "iso_pose", 1, 5),
                                        ("iso9283", "cycle", 1, None)):
        values = ints[column]
        bad = (sets == set_name) & ((values < low) | (values > (high or values.max())))
        if bad.any():
            i = int(np.argmax(bad))
            span = f"{low}..{high}" if high else f"at least {low}"
            raise MeasurementError(f"{set_name} rows need {column} {span}", file=path,
                                   row=rows[i], column=column)
    back = np.flatnonzero(np.diff(times["t_trigger_s"]) < 0)
    if back.size:
        raise MeasurementError("the schedule goes back in time: rows out of execution order",
                               file=path, row=rows[int(back[0]) + 1], column="t_trigger_s")
    return PoseTable(ids.astype(str), sets.astype(str), q, numbers("payload_kg", 0.0), ints,
                     times, np.asarray(rows), path)


def read_plan_meta(poses_path: str | Path) -> dict[str, Any]:
    """`plan.toml` beside a pose table (robot, ball offset, timing), or {} without one."""
    path = Path(poses_path).parent / "plan.toml"
    if not path.exists():
        return {}
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise MeasurementError(f"not valid TOML: {err}", file=path) from None
