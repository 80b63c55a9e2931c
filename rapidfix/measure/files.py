"""Measurement files (version 1): read, validate and write setup.toml and the CSV tables.

A measurement set is `setup.toml` plus CSV tables (header row, comma separated,
`.` as decimal mark, rows in execution order). Other tools' exports are read too: a
header separated by semicolons or tabs sets the delimiter (then `,` is also read as a
decimal mark), and lines starting with `#` are comments:

- sweeps:  ``sweep_joint,j1,j2,j3,j4,j5,j6,repeat,x,y,z``
- points:  ``point_id,j1,j2,j3,j4,j5,j6,x,y,z``, optional ``ball`` (the target-ball
  nest each row measured, an index into the setup's `smr_offsets_mm`, default 0)
- optional in either: ``payload_kg``, ``time_s``, ``temp_c``; further numeric
  columns are kept in ``extra`` (e.g. ``length_mm`` of a ballbar run); further text
  columns (notes, time stamps) are ignored with a warning.

The setup declares one ball (``smr_offset_mm = [x, y, z]``) or several nests on the
flange (``smr_offsets_mm = [[x, y, z], ...]``): one ball shows where the flange is,
not how it turns about that ball; two or more show its orientation too.

Joints are degrees in the files and radians in the tables; positions are mm.
Every problem a user can cause raises `MeasurementError` naming the file and,
for tables, the row (the line number in the file, the header being row 1) and
the column. Writers are the exact inverse and write atomically.
"""

from __future__ import annotations

import csv
import io
import math
import re
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix.atomic import write_text_atomic
from rapidfix.exceptions import KinematicsError, MeasurementError, RapidfixWarning
from rapidfix.kinematics import RobotModel, load_robot

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

JOINT_COLUMNS = ("j1", "j2", "j3", "j4", "j5", "j6")
XYZ_COLUMNS = ("x", "y", "z")
SWEEP_COLUMNS = ("sweep_joint", *JOINT_COLUMNS, "repeat", *XYZ_COLUMNS)
POINT_COLUMNS = ("point_id", *JOINT_COLUMNS, *XYZ_COLUMNS)
#: optional column of a points table: the nest (index into `Setup.ball_offsets_mm`)
BALL_COLUMN = "ball"
#: at most this many nests on one flange
MAX_BALLS = 16
CONDITION_COLUMNS = ("payload_kg", "time_s", "temp_c")

#: A measured position table whose every |x|, |y|, |z| stays below this (mm) was
#: written in metres: no target ball comes that close to the tracker or the base.
METRES_LIMIT_MM = 20.0
#: Five or more poses whose every joint stays within ±2π, though some joint moves by
#: more than 1 (57° if radians), look like radians.
RADIANS_LIMIT = 2.0 * math.pi + 1e-9
#: Physical bounds: a joint angle beyond ±10 turns, or a position farther than
#: REACH_FACTOR × the robot's reach from the origin, is not a measurement but a bad cell
#: (such numbers would overflow the fits instead of being told apart as outliers).
MAX_ABS_ANGLE_DEG = 3600.0
REACH_FACTOR = 10.0
#: reach assumed when the robot is not known yet (larger than any ABB arm's)
DEFAULT_REACH_MM = 5000.0
#: the farthest a target ball may sit from the flange (mm)
MAX_SMR_OFFSET_MM = 5000.0
#: two nests closer than this (mm) are one nest written twice (an SMR is 12.7–38 mm across)
MIN_NEST_GAP_MM = 5.0
#: physical ranges of the condition columns (kg, s, °C)
CONDITION_BOUNDS = {"payload_kg": (0.0, 1e4), "time_s": (-1e9, 1e9), "temp_c": (-273.15, 1e3)}


@dataclass(frozen=True)
class Setup:
    """The cell as `setup.toml` declares it.

    `smr_offset_mm` is the target-ball centre in the flange (tool0) frame (nest 0,
    the one the sweeps use); `smr_offsets_mm` (K, 3), when the flange carries K ≥ 2
    nests, every nest's centre (row 0 = `smr_offset_mm`), None for one ball;
    `tracker_sigma_mm` the tracker's stated noise (None when not stated);
    `payload_kg` the default payload of rows without a payload column.
    """

    robot: str
    smr_offset_mm: np.ndarray
    tracker_sigma_mm: float | None = None
    payload_kg: float = 0.0
    path: Path | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    smr_offsets_mm: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.smr_offsets_mm is None:
            return
        nests = np.asarray(self.smr_offsets_mm, dtype=float).reshape(-1, 3)
        if not np.allclose(nests[0], self.smr_offset_mm, rtol=0.0, atol=1e-9):
            raise ValueError("smr_offsets_mm[0] must be smr_offset_mm (nest 0)")
        object.__setattr__(self, "smr_offsets_mm", nests)

    @property
    def ball_offsets_mm(self) -> np.ndarray:
        """Every nest's ball centre (K, 3) mm in the flange frame (K = 1 for one ball)."""
        if self.smr_offsets_mm is None:
            return np.asarray(self.smr_offset_mm, dtype=float).reshape(1, 3)
        return self.smr_offsets_mm


@dataclass(frozen=True)
class SweepTable:
    """A sweeps CSV as arrays; row i of each array is file row `rows[i]`.

    `sweep_joint` is the 0-based index of the moved joint (the file's 1..6 minus one),
    `q` the full commanded pose in radians (N, 6), `xyz` the measured ball centre in
    the tracker frame in mm (N, 3). Condition columns are None when absent.
    """

    sweep_joint: np.ndarray
    q: np.ndarray
    repeat: np.ndarray
    xyz: np.ndarray
    rows: np.ndarray
    payload_kg: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temp_c: np.ndarray | None = None
    extra: Mapping[str, np.ndarray] = field(default_factory=dict)
    path: Path | None = None

    def __len__(self) -> int:
        return len(self.rows)


@dataclass(frozen=True)
class PointTable:
    """A points CSV (calibration, validation, ballbar) as arrays; see `SweepTable`.

    `ball` (N,) int is the nest each row measured (None: the file has no `ball`
    column, every row is nest 0); `ball_offsets` turns it into offsets.
    """

    point_id: np.ndarray
    q: np.ndarray
    xyz: np.ndarray
    rows: np.ndarray
    payload_kg: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temp_c: np.ndarray | None = None
    extra: Mapping[str, np.ndarray] = field(default_factory=dict)
    path: Path | None = None
    ball: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.rows)


# --------------------------------------------------------------------------- setup


#: the keys setup.toml may hold; any other is reported and ignored
SETUP_KEYS = ("robot", "smr_offset_mm", "smr_offsets_mm", "tracker_sigma_mm", "payload_kg")


class MeasurementWarning(RapidfixWarning):
    """Something in a measurement file that is ignored (e.g. an unknown setup key)."""


def read_measurement_text(path: str | Path, what: str = "measurement file") -> str:
    """A measurement file's text (UTF-8, BOM allowed); a missing file or other bytes
    are a MeasurementError naming the file."""
    path = Path(path)
    try:
        return path.read_bytes().decode("utf-8-sig")
    except FileNotFoundError:
        raise MeasurementError(f"{what} not found", file=path) from None
    except UnicodeDecodeError as err:
        raise MeasurementError(f"not UTF-8 text ({err.reason})", file=path) from None


def _toml_line(text: str, key: str) -> int | None:
    """The line on which `key = ...` is written, for error messages."""
    match = re.search(rf"^\s*{re.escape(key)}\s*=", text, flags=re.MULTILINE)
    return text.count("\n", 0, match.start()) + 1 if match else None


def read_setup(path: str | Path, *, check_robot: bool = True) -> Setup:
    """Read and validate `setup.toml`; with `check_robot` the robot name must be known."""
    path = Path(path)
    text = read_measurement_text(path, "setup file")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        where = re.search(r"line (\d+), column (\d+)", str(err))
        line, col = (int(where[1]), int(where[2])) if where else (None, None)
        message = re.sub(r"\s*\(at line.*\)$", "", str(err))
        raise MeasurementError(f"not valid TOML: {message}", file=path, line=line,
                               column=col) from None

    def fail(key: str, message: str) -> MeasurementError:
        return MeasurementError(message, file=path, line=_toml_line(text, key))

    robot = data.get("robot")
    if not isinstance(robot, str) or not robot.strip():
        raise fail("robot", "'robot' must name a robot model, e.g. robot = \"IRB1600-10/1.45\"")
    robot = robot.strip()
    if check_robot:
        try:
            load_robot(robot)
        except KinematicsError as err:
            raise fail("robot", err.message if repr(robot) in err.message
                       else f"unknown robot {robot!r}: {err.message}") from None

    if "smr_offset_mm" in data and "smr_offsets_mm" in data:
        raise fail("smr_offsets_mm", "give either 'smr_offset_mm' (one ball) or "
                   "'smr_offsets_mm' (several nests), not both")
    nests = None
    if "smr_offsets_mm" in data:
        value = data["smr_offsets_mm"]
        if (not isinstance(value, list) or not 1 <= len(value) <= MAX_BALLS
                or not all(isinstance(v, list) for v in value)):
            raise fail("smr_offsets_mm", "'smr_offsets_mm' must be a list of 1 to "
                       f"{MAX_BALLS} offsets [[x, y, z], ...] in mm")
        nests = np.vstack([_ball_offset(v, f"smr_offsets_mm[{k}]", "smr_offsets_mm", fail)
                           for k, v in enumerate(value)])
        gap = np.linalg.norm(nests[:, None] - nests[None], axis=-1) + 1e9 * np.eye(len(nests))
        if np.any(gap < MIN_NEST_GAP_MM):
            a, b = np.argwhere(gap < MIN_NEST_GAP_MM)[0]
            raise fail("smr_offsets_mm", f"nests {a} and {b} of 'smr_offsets_mm' are "
                       f"{gap[a, b]:.3g} mm apart: two nests must be at least "
                       f"{MIN_NEST_GAP_MM:g} mm apart")
        smr_arr = nests[0]
    else:
        smr_arr = _ball_offset(data.get("smr_offset_mm"), "smr_offset_mm", "smr_offset_mm",
                               fail)

    sigma = _positive_number(data, "tracker_sigma_mm", fail, optional=True)
    if sigma is not None and sigma >= 1.0:
        raise fail("tracker_sigma_mm", f"'tracker_sigma_mm' = {sigma} mm is implausible "
                   "for a laser tracker (give mm, e.g. 0.005)")
    payload = _positive_number(data, "payload_kg", fail, optional=True, allow_zero=True)
    if payload is not None and payload > CONDITION_BOUNDS["payload_kg"][1]:
        raise fail("payload_kg", f"'payload_kg' = {payload:g} kg is beyond any robot's payload")
    extra = {k: v for k, v in data.items() if k not in SETUP_KEYS}
    for key in extra:
        where = _toml_line(text, key)
        warnings.warn(f"{path}{f':{where}' if where else ''}: unknown key {key!r} ignored "
                      f"(known: {', '.join(SETUP_KEYS)})", MeasurementWarning, stacklevel=2)
    return Setup(robot=robot, smr_offset_mm=smr_arr, tracker_sigma_mm=sigma,
                 payload_kg=0.0 if payload is None else payload, path=path, extra=extra,
                 smr_offsets_mm=nests if nests is not None and len(nests) > 1 else None)


def _ball_offset(value: Any, name: str, key: str, fail: Any) -> np.ndarray:
    """One ball offset [x, y, z] mm from the setup, checked (`name` for the message)."""
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        raise fail(key, f"'{name}' must be three numbers [x, y, z] in mm")
    try:
        arr = np.asarray(value, dtype=float)
    except OverflowError:
        raise fail(key, f"'{name}' must be finite") from None
    if not np.all(np.isfinite(arr)):
        raise fail(key, f"'{name}' must be finite")
    norm = float(np.linalg.norm(arr))
    if norm > MAX_SMR_OFFSET_MM:
        raise fail(key, f"'{name}' is {norm:.4g} mm long: no target ball "
                   f"sits more than {MAX_SMR_OFFSET_MM:g} mm from the flange")
    if 0.0 < norm < 1.0:
        raise fail(key, f"'{name}' is {norm:.4g} long: "
                   "this looks like metres, the file needs mm")
    return arr


def _positive_number(data: Mapping[str, Any], key: str, fail: Any, *, optional: bool,
                     allow_zero: bool = False) -> float | None:
    value = data.get(key)
    if value is None and optional:
        return None
    if (not isinstance(value, (int, float)) or isinstance(value, bool)
            or not math.isfinite(float(value) if abs(value) < 1e300 else math.inf)):
        raise fail(key, f"'{key}' must be a finite number")
    if value < 0 or (value == 0 and not allow_zero):
        raise fail(key, f"'{key}' must be {'non-negative' if allow_zero else 'positive'}")
    return float(value)


def write_setup(path: str | Path, setup: Setup) -> Path:
    """Write `setup` as `setup.toml` (atomically); extra keys must be plain scalars/lists."""
    lines = [f'robot = "{setup.robot}"']
    nests = setup.ball_offsets_mm
    if len(nests) == 1:
        lines.append("smr_offset_mm = [" + ", ".join(f"{v:.6f}" for v in nests[0]) + "]")
    else:
        lines.append("smr_offsets_mm = [" + ", ".join(
            "[" + ", ".join(f"{v:.6f}" for v in row) + "]" for row in nests) + "]")
    if setup.tracker_sigma_mm is not None:
        lines.append(f"tracker_sigma_mm = {setup.tracker_sigma_mm:.6g}")
    lines.append(f"payload_kg = {float(setup.payload_kg):.6g}")
    for key, value in setup.extra.items():
        lines.append(f"{key} = {toml_value(value)}")
    return write_text_atomic(path, "\n".join(lines) + "\n")


def toml_value(value: Any) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float, np.floating, np.integer)):
        return repr(float(value)) if isinstance(value, (float, np.floating)) else str(int(value))
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


# --------------------------------------------------------------------------- CSV core


@dataclass(frozen=True)
class _RawTable:
    path: Path
    header: tuple[str, ...]
    cells: list[list[str]]
    rows: np.ndarray
    decimal_comma: bool = False

    def column(self, name: str) -> list[str]:
        idx = self.header.index(name)
        return [r[idx] for r in self.cells]

    def numeric_texts(self, name: str) -> list[str]:
        """A column's cells as Python reads numbers (decimal commas made points)."""
        texts = self.column(name)
        return [t.replace(",", ".") for t in texts] if self.decimal_comma else texts


#: delimiters a header may use, in the order they are looked for
_DELIMITERS = (",", ";", "\t")


def _delimiter(text: str) -> str:
    """The delimiter of the first line that is neither blank nor a comment."""
    for line in text.splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            return next((d for d in _DELIMITERS if d in line), ",")
    return ","


def _read_raw(path: Path, required: Sequence[str]) -> _RawTable:
    text = read_measurement_text(path)
    delimiter = _delimiter(text)
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    header: tuple[str, ...] | None = None
    cells: list[list[str]] = []
    rows: list[int] = []
    try:
        for record in reader:
            if not record or all(not c.strip() for c in record):
                continue
            if record[0].lstrip().startswith("#"):
                continue
            if header is None:
                header = tuple(c.strip().lower() for c in record)
                seen = set()
                for name in header:
                    if name in seen:
                        raise MeasurementError("column appears twice in the header",
                                               file=path, row=reader.line_num, column=name)
                    seen.add(name)
                continue
            if len(record) != len(header):
                raise MeasurementError(
                    f"expected {len(header)} fields like the header, found {len(record)}",
                    file=path, row=reader.line_num)
            cells.append([c.strip() for c in record])
            rows.append(reader.line_num)
    except csv.Error as err:
        raise MeasurementError(f"not valid CSV: {err}", file=path, row=reader.line_num) from None
    if header is None:
        raise MeasurementError("empty file: expected a header row "
                               f"({','.join(required)})", file=path)
    for name in required:
        if name not in header:
            raise MeasurementError(f"missing column (the header needs {','.join(required)})",
                                   file=path, row=1, column=name)
    if not cells:
        raise MeasurementError("no data rows after the header", file=path)
    return _RawTable(path, header, cells, np.asarray(rows, dtype=int),
                     decimal_comma=delimiter != ",")


def _numbers(raw: _RawTable, name: str) -> np.ndarray:
    """A column as float64; the first non-numeric, NaN or infinite cell is an error."""
    texts = raw.numeric_texts(name)
    try:
        values = np.asarray(texts, dtype=float)
    except ValueError:
        for i, t in enumerate(texts):
            try:
                float(t)
            except ValueError:
                what = "empty cell" if not t else f"{t!r} is not a number"
                raise MeasurementError(what, file=raw.path, row=int(raw.rows[i]),
                                       column=name) from None
        raise AssertionError("unreachable") from None
    bad = ~np.isfinite(values)
    if bad.any():
        i = int(np.argmax(bad))
        raise MeasurementError(f"{texts[i]!r} is not a finite number", file=raw.path,
                               row=int(raw.rows[i]), column=name)
    return values


def _integers(raw: _RawTable, name: str, low: int, high: int | None) -> np.ndarray:
    values = _numbers(raw, name)
    bad = (values != np.round(values)) | (values < low)
    if high is not None:
        bad |= values > high
    if bad.any():
        i = int(np.argmax(bad))
        span = f"{low}..{high}" if high is not None else f"≥ {low}"
        raise MeasurementError(f"{raw.column(name)[i]!r} is not an integer {span}",
                               file=raw.path, row=int(raw.rows[i]), column=name)
    return values.astype(int)


def _check_units(raw: _RawTable, joints_deg: np.ndarray, xyz: np.ndarray) -> None:
    """Refuse tables that were evidently written in metres or radians."""
    if np.max(np.abs(xyz)) < METRES_LIMIT_MM:
        raise MeasurementError(
            f"every x, y, z is within ±{METRES_LIMIT_MM:g}: these look like metres, "
            "the file needs mm", file=raw.path, row=int(raw.rows[0]), column="x")
    if (len(joints_deg) >= 5 and np.max(np.abs(joints_deg)) <= RADIANS_LIMIT
            and np.max(np.ptp(joints_deg, axis=0)) > 1.0):
        raise MeasurementError(
            "every joint angle is within ±2π: these look like radians, the file needs degrees",
            file=raw.path, row=int(raw.rows[0]), column="j1")


def robot_reach_mm(robot: RobotModel) -> float:
    """An upper bound of the flange's distance from the base origin (mm): the chain of
    axis points and the tool0 home position, link by link."""
    points = np.vstack([np.zeros(3), np.asarray(robot.axis_points, dtype=float),
                        np.asarray(robot.home, dtype=float)[:3, 3]])
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))


def _check_bounds(raw: _RawTable, joints_deg: np.ndarray, xyz: np.ndarray,
                  reach_mm: float | None) -> None:
    """Refuse finite but absurd cells: angles beyond ±10 turns, positions beyond 10× reach."""
    limit_mm = REACH_FACTOR * (reach_mm if reach_mm else DEFAULT_REACH_MM)
    for values, names, limit, unit in ((joints_deg, JOINT_COLUMNS, MAX_ABS_ANGLE_DEG, "°"),
                                       (xyz, XYZ_COLUMNS, limit_mm, " mm")):
        bad = np.abs(values) > limit
        if bad.any():
            i, k = np.argwhere(bad)[0]
            raise MeasurementError(
                f"{raw.column(names[k])[i]!r} is beyond the physical bound ±{limit:.6g}{unit}",
                file=raw.path, row=int(raw.rows[i]), column=names[k])


def _check_duplicates(raw: _RawTable, values: np.ndarray) -> None:
    """Two rows identical in every numeric column are a copy, not a measurement."""
    _, first, inverse = np.unique(values, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    dup = first[inverse] != np.arange(len(values))
    if dup.any():
        i = int(np.argmax(dup))
        j = int(first[inverse[i]])
        raise MeasurementError(f"duplicate of row {int(raw.rows[j])}", file=raw.path,
                               row=int(raw.rows[i]))


def _optional_columns(raw: _RawTable, skip: Sequence[str]) -> tuple[dict, dict]:
    conditions: dict[str, np.ndarray | None] = {}
    for name in CONDITION_COLUMNS:
        conditions[name] = _numbers(raw, name) if name in raw.header else None
    payload = conditions["payload_kg"]
    if payload is not None and (payload < 0).any():
        i = int(np.argmax(payload < 0))
        raise MeasurementError("payload must not be negative", file=raw.path,
                               row=int(raw.rows[i]), column="payload_kg")
    for name, (low, high) in CONDITION_BOUNDS.items():
        values = conditions[name]
        bad = None if values is None else (values < low) | (values > high)
        if bad is not None and bad.any():
            i = int(np.argmax(bad))
            raise MeasurementError(f"{raw.column(name)[i]!r} is outside the physical range "
                                   f"[{low:g}, {high:g}]", file=raw.path,
                                   row=int(raw.rows[i]), column=name)
    known = set(skip) | set(CONDITION_COLUMNS)
    extra = {}
    for name in raw.header:
        if name in known:
            continue
        try:
            extra[name] = _numbers(raw, name)
        except MeasurementError:
            warnings.warn(f"{raw.path}: column {name!r} is not numeric; it is ignored",
                          MeasurementWarning, stacklevel=3)
    return conditions, extra


# --------------------------------------------------------------------------- tables


def read_sweeps(path: str | Path, *, reach_mm: float | None = None) -> SweepTable:
    """Read and validate a sweeps CSV (see module docstring).

    `reach_mm` (the robot's reach, `robot_reach_mm`) bounds the positions; without it
    a reach larger than any ABB arm's is assumed.
    """
    raw = _read_raw(Path(path), SWEEP_COLUMNS)
    joint = _integers(raw, "sweep_joint", 1, 6) - 1
    if BALL_COLUMN in raw.header:
        nest = _numbers(raw, BALL_COLUMN)
        if np.any(nest != 0):
            i = int(np.argmax(nest != 0))
            raise MeasurementError(
                f"{raw.column(BALL_COLUMN)[i]!r}: sweeps are analysed on ball 0 only "
                "(smr_offset_mm or the first of smr_offsets_mm)", file=raw.path,
                row=int(raw.rows[i]), column=BALL_COLUMN)
    q_deg = np.column_stack([_numbers(raw, c) for c in JOINT_COLUMNS])
    repeat = _integers(raw, "repeat", 0, None)
    xyz = np.column_stack([_numbers(raw, c) for c in XYZ_COLUMNS])
    conditions, extra = _optional_columns(raw, SWEEP_COLUMNS)
    _check_bounds(raw, q_deg, xyz, reach_mm)
    _check_units(raw, q_deg, xyz)
    stacked = [joint[:, None], q_deg, repeat[:, None], xyz]
    stacked += [v[:, None] for v in conditions.values() if v is not None]
    _check_duplicates(raw, np.hstack(stacked))
    return SweepTable(sweep_joint=joint, q=np.radians(q_deg), repeat=repeat, xyz=xyz,
                      rows=raw.rows, extra=extra, path=raw.path, **conditions)


def read_points(path: str | Path, *, reach_mm: float | None = None) -> PointTable:
    """Read and validate a points CSV (calibration, validation or ballbar run);
    `reach_mm` as in `read_sweeps`."""
    raw = _read_raw(Path(path), POINT_COLUMNS)
    ids = np.asarray(raw.column("point_id"), dtype=object)
    empty = ids == ""
    if empty.any():
        i = int(np.argmax(empty))
        raise MeasurementError("empty point_id", file=raw.path, row=int(raw.rows[i]),
                               column="point_id")
    _, first, inverse = np.unique(ids.astype(str), return_index=True, return_inverse=True)
    dup = first[inverse] != np.arange(len(ids))
    if dup.any():
        i = int(np.argmax(dup))
        raise MeasurementError(f"point_id {ids[i]!r} already used in row "
                               f"{int(raw.rows[first[inverse[i]]])}", file=raw.path,
                               row=int(raw.rows[i]), column="point_id")
    q_deg = np.column_stack([_numbers(raw, c) for c in JOINT_COLUMNS])
    xyz = np.column_stack([_numbers(raw, c) for c in XYZ_COLUMNS])
    nest = (_integers(raw, BALL_COLUMN, 0, MAX_BALLS - 1) if BALL_COLUMN in raw.header
            else None)
    conditions, extra = _optional_columns(raw, (*POINT_COLUMNS, BALL_COLUMN))
    _check_bounds(raw, q_deg, xyz, reach_mm)
    _check_units(raw, q_deg, xyz)
    stacked = [q_deg, xyz] + [v[:, None] for v in conditions.values() if v is not None]
    if nest is not None:
        stacked.append(nest[:, None])
    _check_duplicates(raw, np.hstack(stacked))
    return PointTable(point_id=ids.astype(str), q=np.radians(q_deg), xyz=xyz, rows=raw.rows,
                      extra=extra, path=raw.path, ball=nest, **conditions)


def ball_offsets(table: PointTable, setup: Setup) -> np.ndarray:
    """Each row's ball centre (N, 3) mm in the flange frame: the nest its `ball` column
    names (nest 0 without the column). A nest the setup does not declare is a
    MeasurementError naming the table's file, row and column."""
    nests = setup.ball_offsets_mm
    if table.ball is None:
        return np.broadcast_to(nests[0], (len(table), 3)).copy()
    index = np.asarray(table.ball, dtype=int)
    bad = (index < 0) | (index >= len(nests))
    if bad.any():
        i = int(np.argmax(bad))
        where = f" ({setup.path.name})" if setup.path is not None else ""
        declared = ("only one ball (smr_offset_mm), nest 0" if len(nests) == 1
                    else f"nests 0..{len(nests) - 1} (smr_offsets_mm)")
        raise MeasurementError(f"ball {int(index[i])} has no offset: the setup{where} "
                               f"declares {declared}", file=table.path,
                               row=int(table.rows[i]), column=BALL_COLUMN)
    return nests[index]


_FORMATS = {"q": "%.6f", "xyz": "%.4f", "payload_kg": "%.3f", "time_s": "%.3f",
            "temp_c": "%.4f", "extra": "%.6f"}


def _render(columns: list[tuple[str, np.ndarray, str]]) -> str:
    names = [c[0] for c in columns]
    texts = [np.char.mod(fmt, values) if fmt != "%s" else np.asarray(values, dtype=str)
             for _, values, fmt in columns]
    body = "\n".join(",".join(cells) for cells in zip(*texts))
    return ",".join(names) + "\n" + body + "\n"


def _condition_columns(table: SweepTable | PointTable) -> list[tuple[str, np.ndarray, str]]:
    out = []
    for name in CONDITION_COLUMNS:
        values = getattr(table, name)
        if values is not None:
            out.append((name, np.asarray(values, dtype=float), _FORMATS[name]))
    out += [(name, np.asarray(v, dtype=float), _FORMATS["extra"])
            for name, v in table.extra.items()]
    return out


def write_sweeps(path: str | Path, table: SweepTable) -> Path:
    """Write a sweeps CSV atomically (joints in degrees, 1e-6° resolution)."""
    q_deg = np.degrees(table.q)
    columns = [("sweep_joint", np.asarray(table.sweep_joint) + 1, "%d")]
    columns += [(c, q_deg[:, i], _FORMATS["q"]) for i, c in enumerate(JOINT_COLUMNS)]
    columns.append(("repeat", np.asarray(table.repeat), "%d"))
    columns += [(c, table.xyz[:, i], _FORMATS["xyz"]) for i, c in enumerate(XYZ_COLUMNS)]
    return write_text_atomic(path, _render(columns + _condition_columns(table)))


def write_points(path: str | Path, table: PointTable) -> Path:
    """Write a points CSV atomically (joints in degrees, 1e-6° resolution)."""
    q_deg = np.degrees(table.q)
    columns = [("point_id", np.asarray(table.point_id, dtype=str), "%s")]
    columns += [(c, q_deg[:, i], _FORMATS["q"]) for i, c in enumerate(JOINT_COLUMNS)]
    columns += [(c, table.xyz[:, i], _FORMATS["xyz"]) for i, c in enumerate(XYZ_COLUMNS)]
    if table.ball is not None:
        columns.append((BALL_COLUMN, np.asarray(table.ball, dtype=int), "%d"))
    return write_text_atomic(path, _render(columns + _condition_columns(table)))


def round_joints_deg(q: np.ndarray) -> np.ndarray:
    """Commanded joints (rad) rounded to the 1e-6° the files carry, so data and files agree."""
    return np.radians(np.round(np.degrees(np.asarray(q, dtype=float)), 6))
