"""Robot model files (TOML): read, check and list the models shipped in the package.

A file holds `name`, six `[[joint]]` tables (`axis`, `point` mm, `limits_deg`)
and a `[tool0]` table (`position` mm, `quaternion` [w, x, y, z]) — see
`robots/irb1600-10_1.45.toml` for a commented example. Every malformed value
raises KinematicsError naming the file and the key.
"""

from __future__ import annotations

import re
import sys
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np

from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics.frames import pose
from rapidfix.kinematics.ik_analytic import check_structure
from rapidfix.kinematics.robot_model import RobotModel

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

_ROBOTS_PACKAGE = "rapidfix.kinematics.robots"


def _key_error(path: str, key: str, message: str) -> KinematicsError:
    return KinematicsError(f"key '{key}': {message}", file=path)


def _numbers(table: dict, key: str, where: str, path: str, count: int) -> np.ndarray:
    full = f"{where}.{key}" if where else key
    if key not in table:
        raise _key_error(path, full, "missing")
    value = table[key]
    ok = (
        isinstance(value, list)
        and len(value) == count
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    )
    if not ok:
        raise _key_error(path, full, f"expected a list of {count} numbers, got {value!r}")
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise _key_error(path, full, "numbers must be finite")
    return arr


def parse_robot(data: dict, path: str) -> RobotModel:
    """Build a nominal RobotModel from the parsed TOML `data` of file `path`."""
    name = data.get("name")
    if not isinstance(name, str) or not name.strip():
        raise _key_error(path, "name", "missing or not a non-empty string")
    joints = data.get("joint")
    if not isinstance(joints, list) or len(joints) != 6:
        count = len(joints) if isinstance(joints, list) else 0
        raise _key_error(path, "joint", f"expected six [[joint]] tables, found {count}")
    dirs, points, limits = [], [], []
    for i, joint in enumerate(joints):
        where = f"joint[{i + 1}]"
        axis = _numbers(joint, "axis", where, path, 3)
        if np.linalg.norm(axis) < 1e-9:
            raise _key_error(path, f"{where}.axis", "axis direction is zero")
        dirs.append(axis / np.linalg.norm(axis))
        points.append(_numbers(joint, "point", where, path, 3))
        lim = _numbers(joint, "limits_deg", where, path, 2)
        if not lim[0] < lim[1]:
            raise _key_error(path, f"{where}.limits_deg", "lower limit must be below upper")
        limits.append(np.radians(lim))
    tool0 = data.get("tool0")
    if not isinstance(tool0, dict):
        raise _key_error(path, "tool0", "missing table [tool0]")
    position = _numbers(tool0, "position", "tool0", path, 3)
    quat = _numbers(tool0, "quaternion", "tool0", path, 4)
    if abs(np.linalg.norm(quat) - 1.0) > 1e-6:
        raise _key_error(path, "tool0.quaternion", "not a unit quaternion (|q| must be 1 ± 1e-6)")
    definition = {
        "name": name,
        "joint": [{key: [float(v) for v in joint[key]] for key in ("axis", "point", "limits_deg")}
                  for joint in joints],
        "tool0": {"position": position.tolist(), "quaternion": quat.tolist()},
    }
    model = RobotModel(
        name.strip(),
        np.array(dirs),
        np.array(points),
        pose(position, quat),
        np.array(limits),
        source=path,
        definition=definition,
    )
    problem = check_structure(model)
    if problem is not None:
        raise _key_error(path, problem[0], problem[1])
    return model


def read_robot_file(path: str | Path) -> RobotModel:
    """Load a user's robot model file; KinematicsError with file and key if malformed."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as err:
        raise KinematicsError(f"cannot read robot file: {err.strerror or err}", file=p) from None
    return _parse_bytes(raw, str(p))


def _parse_bytes(raw: bytes, path: str) -> RobotModel:
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError:
        raise KinematicsError("robot file is not UTF-8 text", file=path) from None
    except tomllib.TOMLDecodeError as err:
        text = str(err)
        m = re.search(r"\(at line (\d+), column (\d+)\)", text)
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", text)
        if m:
            raise KinematicsError(
                f"not valid TOML: {message}", file=path, line=int(m[1]), column=int(m[2])
            ) from None
        raise KinematicsError(f"not valid TOML: {message}", file=path) from None
    return parse_robot(data, path)


def _normalise(name: str) -> str:
    return re.sub(r"[\s_]", "", name).upper()


@cache
def _shipped() -> dict[str, RobotModel]:
    models = {}
    for entry in sorted(resources.files(_ROBOTS_PACKAGE).iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            model = _parse_bytes(entry.read_bytes(), f"{_ROBOTS_PACKAGE}/{entry.name}")
            models[model.name] = model
    return models


def is_shipped(model: RobotModel) -> bool:
    """True for a robot model shipped with rapidfix (read from the package, not a user's file)."""
    shipped = _shipped().get(model.name)
    return shipped is not None and shipped.source == model.source


def available_robots() -> list[str]:
    """Names of the robot models shipped with rapidfix, e.g. 'IRB1600-10/1.45'."""
    return list(_shipped())


def load_robot(name_or_path: str | Path) -> RobotModel:
    """A shipped model by name ('IRB1600-10/1.45', spaces ignored) or a robot file path."""
    if isinstance(name_or_path, str):
        wanted = _normalise(name_or_path)
        for name, model in _shipped().items():
            if _normalise(name) == wanted:
                return model
    p = Path(name_or_path)
    if p.suffix.lower() == ".toml" or p.is_file():
        return read_robot_file(p)
    known = ", ".join(available_robots())
    raise KinematicsError(f"unknown robot {str(name_or_path)!r}; known robots: {known}")
