"""Laser-tracker exports: plain text tables of measured points, read and written.

What tracker analysis software exports: one point per line, `id, X, Y, Z`,
optionally a timestamp and a temperature; comma, semicolon, tab or spaces between
fields (decimal comma with `;` or tab); a header line or none; comment lines
starting with `#` or `//`; coordinates in mm, m or inch. The reader finds the
delimiter, the header and the columns, and says what it assumed. Units are
decided later, against the pose table (`rapidfix.campaign.matching`), unless the
header names them (`X [mm]`, `X(m)`, `x_in`, …).

Timestamps: seconds (any origin) or a clock time `hh:mm:ss(.fff)` or an ISO date
and time; all become seconds.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

import numpy as np

from rapidfix.atomic import write_text_atomic
from rapidfix.exceptions import MeasurementError

UNITS_MM = {"mm": 1.0, "m": 1000.0, "in": 25.4}
_ALIASES = {
    "id": ("id", "point", "point_id", "pointid", "name", "label", "pt", "point name"),
    "x": ("x",), "y": ("y",), "z": ("z",),
    "time": ("time", "t", "timestamp", "time_s", "date/time", "datetime", "date_time"),
    "temp": ("temp", "temperature", "temp_c", "air temp", "air_temperature", "t_air"),
}
_UNIT_WORDS = {"mm": "mm", "millimeter": "mm", "millimetre": "mm", "m": "m", "meter": "m",
               "metre": "m", "in": "in", "inch": "in", "inches": "in", '"': "in"}


@dataclass
class TrackerExport:
    """Measured points in file order: ids (N,) or None, xyz (N, 3) in the file's unit,
    time_s (N,) or None, temp_c (N,) or None, line numbers, column names and the
    assumptions the reader made (printed by `rapidfix import`)."""

    path: Path
    ids: np.ndarray | None
    xyz: np.ndarray
    time_s: np.ndarray | None
    temp_c: np.ndarray | None
    rows: np.ndarray
    columns: dict[str, str]
    unit: str | None
    assumptions: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.rows)


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    return next(csv.reader([line], delimiter=delimiter))


def _delimiter(lines: list[str]) -> str | None:
    """The delimiter all data lines agree on: , ; tab or whitespace (None)."""
    for delim in ("\t", ";", ","):
        counts = {line.count(delim) for line in lines[:50]}
        if len(counts) == 1 and counts.pop() >= 2:
            return delim
    return None


def _parse_time(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        pass
    match = re.fullmatch(r"(\d{1,2}):(\d{2}):(\d{2}(?:\.\d*)?)", text)
    if match:
        return int(match[1]) * 3600.0 + int(match[2]) * 60.0 + float(match[3])
    return datetime.fromisoformat(text.replace(" ", "T", 1)).timestamp()


def _column_role(name: str) -> tuple[str | None, str | None]:
    """(role, unit) of a header cell such as 'X [mm]', 'Point ID', 'Time (s)'."""
    clean = name.strip().lower()
    unit = None
    found = re.search(r"[\[(]\s*([a-z\"]+)\s*[\])]\s*$", clean) or re.search(
        r"[_ ](mm|m|in|inch)$", clean)
    if found:
        unit = _UNIT_WORDS.get(found[1])
        clean = clean[:found.start()].strip(" _")
    for role, names in _ALIASES.items():
        if clean in names:
            return role, unit
    return None, unit


def read_export(path: str | Path, *, columns: list[str] | None = None) -> TrackerExport:
    """Read a tracker export (see module doc). `columns` names the columns in order
    (roles id, x, y, z, time, temp, or '-' to skip) when the file has no header."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise MeasurementError("tracker export not found", file=path) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    numbered = [(i + 1, line.strip()) for i, line in enumerate(text.splitlines())]
    numbered = [(n, line) for n, line in numbered
                if line and not line.startswith(("#", "//", ";"))]
    if not numbered:
        raise MeasurementError("no measured points in the file", file=path)
    assumptions: list[str] = []
    delimiter = _delimiter([line for _, line in numbered[1:]] or [numbered[0][1]])
    first = _split(numbered[0][1], delimiter)
    has_header = not _is_number(first[-1].replace(",", "."))
    roles: list[str | None]
    unit = None
    if has_header and columns is None:
        roles, units = zip(*(_column_role(c) for c in first))
        roles = list(roles)
        xyz_units = {u for r, u in zip(roles, units) if r in ("x", "y", "z") and u}
        if len(xyz_units) > 1:
            raise MeasurementError(f"X, Y and Z are in different units ({', '.join(xyz_units)})",
                                   file=path, row=numbered[0][0])
        unit = xyz_units.pop() if xyz_units else None
        for role in ("x", "y", "z"):
            if role not in roles:
                raise MeasurementError(f"no {role.upper()} column in the header (found "
                                       f"{', '.join(first)})", file=path, row=numbered[0][0])
        header_names = {r: c.strip() for r, c in zip(roles, first) if r}
        data = numbered[1:]
    else:
        if columns is not None:
            roles = [None if c == "-" else c for c in columns]
        elif len(first) == 4:
            roles = ["id", "x", "y", "z"]
            assumptions.append("no header: columns taken as id, X, Y, Z")
        elif len(first) == 3:
            roles = ["x", "y", "z"]
            assumptions.append("no header: columns taken as X, Y, Z (no ids)")
        else:
            raise MeasurementError(f"no header and {len(first)} columns: name them with "
                                   "--columns (e.g. id,time,x,y,z)", file=path,
                                   row=numbered[0][0])
        header_names = {r: r for r in roles if r}
        data = numbered[1:] if has_header else numbered
    if not data:
        raise MeasurementError("no measured points after the header", file=path)
    name = {" ": "spaces", None: "spaces", ",": "commas", ";": "semicolons", "\t": "tabs"}
    assumptions.insert(0, f"fields separated by {name[delimiter]}")
    decimal_comma = delimiter in (";", "\t", None) and any(
        re.fullmatch(r"-?\d+,\d+", c) for c in _split(data[0][1], delimiter))
    if decimal_comma:
        assumptions.append("decimal comma")
    width = len(roles)
    cells: list[list[str]] = []
    for n, line in data:
        record = [c.strip() for c in _split(line, delimiter)]
        if len(record) != width:
            raise MeasurementError(f"expected {width} fields, found {len(record)}", file=path,
                                   row=n)
        cells.append(record)
    rows = np.array([n for n, _ in data])

    def column(role: str) -> list[str] | None:
        return [r[roles.index(role)] for r in cells] if role in roles else None

    def numbers(role: str, parse=float) -> np.ndarray | None:  # noqa: ANN001
        values = column(role)
        if values is None:
            return None
        out = np.empty(len(values))
        for i, v in enumerate(values):
            v = v.replace(",", ".") if decimal_comma else v
            try:
                out[i] = parse(v)
            except ValueError:
                out[i] = np.nan
            if not np.isfinite(out[i]):
                what = "empty cell" if not v else f"{v!r} is not a number"
                if role == "time" and v:
                    what = f"{v!r} is not a time (seconds, hh:mm:ss or an ISO date and time)"
                raise MeasurementError(what, file=path, row=int(rows[i]),
                                       column=header_names[role])
        return out

    xyz = np.column_stack([numbers(r) for r in ("x", "y", "z")])
    ids = column("id")
    if ids is not None:
        for i, v in enumerate(ids):
            if not v:
                raise MeasurementError("empty point id", file=path, row=int(rows[i]),
                                       column=header_names["id"])
    return TrackerExport(path, None if ids is None else np.array(ids, dtype=str), xyz,
                         numbers("time", _parse_time), numbers("temp"), rows, header_names,
                         unit, assumptions)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def write_export(path: str | Path, xyz_mm: np.ndarray, *, ids: list[str] | None = None,
                 time_s: np.ndarray | None = None, temp_c: np.ndarray | None = None,
                 unit: str = "mm", delimiter: str = ",", header: bool = True) -> Path:
    """Write points as tracker software exports them (atomically)."""
    scale = 1.0 / UNITS_MM[unit]
    decimals = {"mm": 4, "m": 7, "in": 6}[unit]
    cols: list[tuple[str, list[str]]] = []
    if ids is not None:
        cols.append(("Point", list(ids)))
    if time_s is not None:
        cols.append(("Time", [f"{t:.3f}" for t in time_s]))
    for k, axis in enumerate("XYZ"):
        cols.append((f"{axis} [{unit}]", [f"{v * scale:.{decimals}f}" for v in xyz_mm[:, k]]))
    if temp_c is not None:
        cols.append(("Temperature", [f"{t:.3f}" for t in temp_c]))
    lines = [delimiter.join(name for name, _ in cols)] if header else []
    lines += [delimiter.join(row) for row in zip(*(v for _, v in cols))]
    return write_text_atomic(path, "\n".join(lines) + "\n")
