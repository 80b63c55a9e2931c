"""Check a rewritten program the way the controller and the robot will see it.

The output is parsed again — its new statements and declarations, which is the
same check as parsing the whole of it (see `check_units`); a program that does
not parse is never written. For every compensated move the target is read back
from that text, turned into the joints the controller will command (a
jointtarget as written, rounded to the controller's single precision; a
filtered robtarget through the nominal inverse kinematics on its confdata) and
pushed through the error model: the distance between the TCP the model predicts
and the intended TCP is the predicted deviation.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from rapidfix.errors.context import Context
from rapidfix.errors.model import ErrorModel
from rapidfix.exceptions import RapidfixError, RapidSemanticError
from rapidfix.kinematics.frames import pose
from rapidfix.postprocess.check_units import CheckUnits
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import ik_on_conf
from rapidfix.rapid import MotionInstruction, motion_spec
from rapidfix.rapid.bulk import BulkProgram, read_bulk
from rapidfix.rapid.fastpath import NotFast, aggregate_value
from rapidfix.rapid.values import fits_type


@dataclass(frozen=True)
class Expected:
    """What the output must hold, per checked pose: the motion instruction it is read
    from (`motion` (K,), an index into the list `parse_units` returns), the target
    operand of that motion (`slot` (K,): 0 the CirPoint or the only target, 1 the
    ToPoint of a circular move), the intended TCP `tcp` (K,4,4) in its work object,
    its frames and the conditions it runs in (`context`: payload, directions,
    temperature)."""

    motion: np.ndarray
    slot: np.ndarray
    tcp: np.ndarray
    placement: Placement
    context: Context


def parse_units(units: CheckUnits, filename: str) -> list[MotionInstruction]:
    """Parse the rewritten parts with the full program model; their motion
    instructions by statement id.

    An error here is a bug of the rewrite: it is reported and nothing is written.
    """
    try:
        return units.parse(filename)[1]
    except (RapidfixError, ValueError) as err:
        raise RapidSemanticError(
            f"the rewritten program does not parse ({err}); nothing was written",
            file=filename,
            hint="please report this as a rapidfix bug",
        ) from None


@dataclass(frozen=True)
class ReadBack:
    """The targets the output commands, per checked pose (rows of `Expected`):
    `joint` (K,) True for a jointtarget, else a robtarget; `robax` (K,6) degrees of
    the jointtargets; `trans` (K,3), `rot` (K,4), `conf` (K,4) of the robtargets
    (rows of the other kind hold zeros)."""

    joint: np.ndarray
    robax: np.ndarray
    trans: np.ndarray
    rot: np.ndarray
    conf: np.ndarray

    @classmethod
    def empty(cls, k: int) -> ReadBack:
        return cls(np.zeros(k, bool), np.zeros((k, 6)), np.zeros((k, 3)), np.zeros((k, 4)),
                   np.zeros((k, 4)))


def read_back(units: CheckUnits, filename: str, expected: Expected) -> ReadBack:
    """Parse the rewritten parts and read the target of every expected pose from them.

    Rewritten parts made of simple statements only (a CAM program's) are read in
    bulk (`rapidfix.rapid.bulk`: Lark parses them with the same grammar, and the
    values are read once per run); anything else, and anything the bulk reader
    does not take, goes the full route through the program model, which also
    explains a syntax error. Both give the same values (tests compare them).
    """
    text, order = units.text()
    bulk = read_bulk(text)
    if bulk is not None:
        try:
            return _read_bulk_targets(bulk, order, expected)
        except _NotBulk:
            pass
    return read_back_full(units, filename, expected)


def read_back_full(units: CheckUnits, filename: str, expected: Expected) -> ReadBack:
    """`read_back` through the full program model (`parse_units`)."""
    motions = parse_units(units, filename)
    k = expected.motion.shape[0]
    out = ReadBack.empty(k)
    for i, (m, slot) in enumerate(zip(expected.motion.tolist(), expected.slot.tolist())):
        operand = motions[m].targets[slot]
        value = operand.value if operand.static else None
        if value is None or operand.type_name not in ("jointtarget", "robtarget"):
            raise RapidSemanticError(
                f"rewritten target {operand.text!r} cannot be read back: {operand.reason}",
                file=motions[m].span.file, line=motions[m].span.line,
                hint="please report this as a rapidfix bug")
        # raw values, already checked against their type by the RAPID layer
        if operand.type_name == "jointtarget":
            out.joint[i] = True
            out.robax[i] = value[0]
        else:
            out.trans[i], out.rot[i], out.conf[i] = value[:3]
    return out


class _NotBulk(Exception):
    """The bulk reader met a target it does not read (the full route decides)."""


_JOINT_LITERAL = re.compile(r"\[\[([-+0-9.eE,]*)\],\[([-+0-9.eE,]*)\]\]")


def _read_bulk_targets(bulk: BulkProgram, order: list[int], expected: Expected) -> ReadBack:
    calls = bulk.calls
    if len(calls) != len(order):
        raise _NotBulk
    index_of = [0] * len(order)  # statement id -> its call
    for i, ident in enumerate(order):
        index_of[ident] = i
    k = expected.motion.shape[0]
    out = ReadBack.empty(k)
    call_of_row = np.asarray(index_of)[expected.motion].tolist() if k else []
    run_of_row = (np.searchsorted([r[0] for r in bulk.runs], call_of_row, side="right") - 1
                  ).tolist() if k else []
    scopes = bulk.run_scopes()  # per run of calls: the routine's data, then the module's
    if k and len(set(map(id, (d for pair in scopes for d in pair)))) <= 2:
        quick = _jointtargets_named_first(bulk, call_of_row, expected, scopes[0])
        if quick is not None:
            return quick
    layouts: dict[str, tuple[tuple[int, ...], str]] = {}
    joint_rows: list[int] = []
    joint_texts: list[str] = []
    rob_values: dict[str, tuple] = {}
    for i, (c, run, slot) in enumerate(zip(call_of_row, run_of_row, expected.slot.tolist())):
        name, first, _rest = calls[c]
        layout = layouts.get(name)
        if layout is None:
            spec = motion_spec(name)
            if spec is None:
                raise _NotBulk
            layout = layouts[name] = (
                tuple(spec.parameters.index(p) for p in spec.target_parameters),
                spec.target_kind)
        where, inline_type = layout
        if slot >= len(where):
            raise _NotBulk
        position = where[slot]
        if position == 0 and first:
            text = first
        else:
            required = bulk.arguments(c)[0]
            if position >= len(required):
                raise _NotBulk
            text = required[position]
        if text[0] == "[":
            type_name = inline_type
        else:
            key = text.lower()
            local, module_data = scopes[run]
            found = local.get(key) or module_data.get(key)
            if found is None or not found[1]:
                raise _NotBulk
            type_name, text = found
        if type_name == "jointtarget":
            joint_rows.append(i)
            joint_texts.append(text)
        elif type_name == "robtarget":
            value = rob_values.get(text)
            if value is None:
                value = rob_values[text] = _robtarget_value(text)
            out.trans[i], out.rot[i], out.conf[i] = value
        else:
            raise _NotBulk
    if joint_rows:
        out.joint[joint_rows] = True
        out.robax[joint_rows] = _joint_values(joint_texts)
    return out


def _jointtargets_named_first(bulk: BulkProgram, call_of_row: list[int], expected: Expected,
                              scope: tuple[dict, dict]) -> ReadBack | None:
    """The usual case at list speed: every checked pose is a jointtarget data name written
    as the first argument of a call whose first parameter is its target, all calls in one
    scope. None when that is not so (the general loop decides)."""
    calls = bulk.calls
    rows = [calls[c] for c in call_of_row]
    if expected.slot.any() or not all(first for _, first, _ in rows):
        return None
    for name in {name for name, _, _ in rows}:
        spec = motion_spec(name)
        if spec is None or spec.target_kind != "jointtarget" or not spec.target_parameters \
                or spec.parameters.index(spec.target_parameters[0]) != 0:
            return None
    local, module_data = scope
    names = {**module_data, **local}  # routine data first, then the module's
    found = list(map(names.get, [first.lower() for _, first, _ in rows]))
    if None in found or any(type_name != "jointtarget" or not text
                            for type_name, text in found):
        return None
    out = ReadBack.empty(len(rows))
    out.joint[:] = True
    out.robax[:] = _joint_values([text for _, text in found])
    return out


def _robtarget_value(text: str) -> tuple:
    try:
        value = aggregate_value(text)
    except NotFast:
        raise _NotBulk from None
    if not fits_type("robtarget", value):  # the full route decides
        raise _NotBulk
    return value[:3]


def _joint_values(texts: list[str]) -> np.ndarray:
    """Robot axes (K,6) of jointtarget literals `[[j1..j6],[e1..e6]]`, read in one pass."""
    match = _JOINT_LITERAL.fullmatch
    groups = []
    extax_ok: dict[str, bool] = {}
    for text in texts:
        m = match(text)
        if m is None:
            raise _NotBulk
        robax, extax = m.groups()
        ok = extax_ok.get(extax)
        if ok is None:
            ok = extax_ok[extax] = extax.count(",") == 5 and _numbers(extax)
        if not ok or robax.count(",") != 5:
            raise _NotBulk
        groups.append(robax)
    try:
        values = np.array(",".join(groups).split(","), dtype=float).reshape(-1, 6)
    except ValueError:
        raise _NotBulk from None
    if not np.isfinite(values).all():  # the full route decides (and reports) those
        raise _NotBulk
    return values


def _numbers(group: str) -> bool:
    try:
        tuple(map(float, group.split(",")))
    except ValueError:
        return False
    return True


def commanded_joints(robot: Any, read: ReadBack, expected: Expected,
                     filename: str = "") -> np.ndarray:
    """Joints (K,6) rad the controller commands for the targets read back from the output."""
    k = expected.motion.shape[0]
    q = np.zeros((k, 6))
    if read.joint.any():
        q[read.joint] = np.radians(read.robax[read.joint].astype(np.float32).astype(float))
    rows = np.flatnonzero(~read.joint)
    if rows.size:
        trans = read.trans[rows].astype(np.float32).astype(float)
        rot = read.rot[rows].astype(np.float32).astype(float)
        conf = read.conf[rows].astype(int)
        flange = expected.placement.take(rows).flange(pose(trans, rot))
        q_rob, status = ik_on_conf(robot, flange, conf)
        if np.any(np.asarray(status) != 0):
            raise RapidSemanticError("a filtered robtarget has no solution on its confdata",
                                     file=filename or None,
                                     hint="please report this as a rapidfix bug")
        q[rows] = q_rob
    return q


def predicted_deviation(
    model: ErrorModel, robot: Any, read: ReadBack, expected: Expected, filename: str = ""
) -> np.ndarray:
    """Predicted TCP position error (K,) mm of every expected pose of the output."""
    if expected.motion.shape[0] == 0:
        return np.zeros(0)
    q = commanded_joints(robot, read, expected, filename)
    flange = model.actual_flange(robot, q, expected.context)
    tcp = expected.placement.tcp(flange)
    return np.linalg.norm(tcp[:, :3, 3] - expected.tcp[:, :3, 3], axis=1)
