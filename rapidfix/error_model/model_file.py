"""The model file: JSON, versioned, written atomically.

Layout (version 1):

    {
      "format": "rapidfix-model",
      "version": 1,
      "robot": "IRB1600-10/1.45",
      "rapidfix_version": "0.1.0",
      "effects": [ {"type": "joint_rbf", "name": ..., "params": {...}, "state": {...}}, ...],
      "data": [ {"name": "sweeps.csv", "sha256": "…", "role": "sweeps"}, ...],
      "statistics": { ... per-joint CV RMS, residuals ... },
      "robot_definition": { "name", "joint": [...], "tool0": {...} }   (optional)
    }

`robot_definition` holds the robot file's content (screws, limits, tool0) when the
model was fitted for a robot rapidfix does not ship, so the model reloads alone.

Angles are stored in radians (names end in _rad) so a round trip is exact.
Loading checks the format tag, the version and, when asked, the robot.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rapidfix import __version__
from rapidfix.atomic import write_text_atomic
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.registry import effect_from_dict
from rapidfix.exceptions import ModelError

FORMAT = "rapidfix-model"
VERSION = 1


def model_to_dict(model: ErrorModel) -> dict[str, Any]:
    """The JSON document of a model."""
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "robot": model.robot,
        "rapidfix_version": __version__,
        "effects": [e.to_dict() for e in model.effects],
        "data": list(model.data_files),
        "statistics": model.statistics,
    }
    if model.robot_definition is not None:
        doc["robot_definition"] = model.robot_definition
    return doc


def save_model(model: ErrorModel, path: str | Path) -> Path:
    """Write the model file atomically; returns its path."""
    text = json.dumps(model_to_dict(model), indent=1, allow_nan=False) + "\n"
    return write_text_atomic(path, text)


def _require(doc: dict[str, Any], key: str, kind: type, path: Path) -> Any:
    if key not in doc:
        raise ModelError(f"missing key {key!r}", file=path, column=key)
    value = doc[key]
    if not isinstance(value, kind):
        raise ModelError(
            f"key {key!r} should be a {kind.__name__}, not {type(value).__name__}",
            file=path,
            column=key,
        )
    return value


def model_from_dict(doc: Any, path: str | Path = "<model>") -> ErrorModel:
    """Build a model from its JSON document; ModelError names the file and the key."""
    path = Path(path)
    if not isinstance(doc, dict):
        raise ModelError("not a rapidfix model (a JSON object was expected)", file=path)
    if doc.get("format") != FORMAT:
        raise ModelError(
            f"not a rapidfix model file (key 'format' is {doc.get('format')!r}, "
            f"expected {FORMAT!r})",
            file=path,
            column="format",
        )
    version = _require(doc, "version", int, path)
    if version != VERSION:
        raise ModelError(
            f"model file version {version} is not supported (this rapidfix reads {VERSION})",
            file=path,
            column="version",
        )
    robot = _require(doc, "robot", str, path)
    effects_data = _require(doc, "effects", list, path)
    data_files = doc.get("data", [])
    statistics = doc.get("statistics", {})
    if not isinstance(data_files, list) or not isinstance(statistics, dict):
        raise ModelError("keys 'data' / 'statistics' are malformed", file=path, column="data")
    effects = []
    for i, item in enumerate(effects_data):
        where = f"effects[{i}]"
        if not isinstance(item, dict):
            raise ModelError(f"{where} is not an object", file=path, column=where)
        try:
            effects.append(effect_from_dict(item, where))
        except ModelError as err:
            raise ModelError(err.message, file=path, column=err.column or where,
                             hint=err.hint) from None
    definition = doc.get("robot_definition")
    if definition is not None and not isinstance(definition, dict):
        raise ModelError("key 'robot_definition' should be an object (a robot file's content)",
                         file=path, column="robot_definition")
    return ErrorModel(robot, effects, statistics, data_files, definition)


def load_model(path: str | Path, robot_name: str | None = None) -> ErrorModel:
    """Read a model file; with `robot_name`, refuse a model made for another robot."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ModelError("not a rapidfix model file (not UTF-8 text)", file=path) from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise ModelError(f"not valid JSON: {err.msg}", file=path, line=err.lineno,
                         column=err.colno) from None
    model = model_from_dict(doc, path)
    if robot_name is not None and robot_name != model.robot:
        raise ModelError(
            f"the model was made for robot {model.robot!r}, not {robot_name!r}",
            file=path,
            hint="fit a model on measurements of this robot",
        )
    return model
