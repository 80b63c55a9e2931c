"""Check a rewritten program the way the controller and the robot will see it.

The output is parsed again — its new statements and declarations, which is the
same check as parsing the whole of it (see `reparse_changes`); a program that does
not parse is never written. For every compensated move the target is read back
from that text, turned into the joints the controller will command (a
jointtarget as written, rounded to the controller's single precision; a
filtered robtarget through the nominal inverse kinematics on its confdata) and
pushed through the error model: the distance between the TCP the model predicts
and the intended TCP is the predicted deviation.
"""

from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass
from itertools import repeat
from operator import is_not, itemgetter

import numpy as np

from rapidfix.error_model import Context, ErrorModel
from rapidfix.exceptions import RapidfixError, RapidSemanticError
from rapidfix.kinematics import RobotModel, pose
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import ik_on_conf
from rapidfix.postprocess.reparse_changes import CheckUnits
from rapidfix.rapid import (
    MotionInstruction,
    ReadBack,
    one_per_shape,
    parse_program,
    read_jointtarget_declarations,
    read_robtarget_declarations,
    read_robtarget_literals,
    read_targets_full,
    read_targets_in_bulk,
)


@dataclass(frozen=True)
class Expected:
    """What the output must hold, per checked pose: the motion instruction it is read
    from (`motion` (K,), an index into the list `parse_units` returns), the target
    operand of that motion (`slot` (K,): 0 the CirPoint or the only target, 1 the
    ToPoint of a circular move), the intended TCP position `position` (K,3) mm in its
    work object (what the predicted deviation is measured from: the pose's 16 numbers
    would be held at the rewrite's peak), its frames and the conditions it runs in
    (`context`: payload, directions, temperature)."""

    motion: np.ndarray
    slot: np.ndarray
    position: np.ndarray
    placement: Placement
    context: Context
    #: (K,6) rad: the joints the rewrite wrote for a pose it wrote as a jointtarget (what
    #: the read-back must find there); None: not checked
    joints: np.ndarray | None = None


def parse_units(units: CheckUnits, filename: str) -> list[MotionInstruction]:
    """Parse the rewritten parts with the full program model; their motion
    instructions by statement id.

    An error here is a bug of the rewrite: it is reported and nothing is written.
    """
    try:
        return units.parse(filename)[1]
    except (RapidfixError, ValueError) as err:
        raise _not_parsed(err, filename) from None


def _not_parsed(err: Exception, filename: str) -> RapidSemanticError:
    """What stops a rewrite whose rewritten parts do not parse: a bug of the rewrite."""
    return RapidSemanticError(
        f"the rewritten program does not parse ({err}); nothing was written",
        file=filename,
        hint="please report this as a rapidfix bug",
    )


def read_back(units: CheckUnits, filename: str, expected: Expected) -> ReadBack:
    """Parse the rewritten parts and read the target of every expected pose from them.

    The MoveAbsJ statements and jointtarget declarations, and the instructions kept with
    filtered robtargets and their robtarget declarations, that the emission made as
    columns are read as columns (`_read_columns`); rewritten parts made of simple statements
    only are read in bulk (`rapidfix.rapid.readback`: Lark parses them with the same
    grammar, and the values are read once per run); anything else, and anything those
    readers do not take, goes the full route through the program model, which also
    explains a syntax error. All give the same values (tests compare them). A
    jointtarget that does not hold the joints the rewrite meant to write stops it.
    """
    try:  # the approach points' statements, one of each shape
        units.parse_shapes(filename)
    except (RapidfixError, ValueError) as err:
        raise _not_parsed(err, filename) from None
    found = _read_columns(units, expected, filename)
    if found is None:
        text, order = units.text()
        found = read_targets_in_bulk(text, order, expected.motion, expected.slot)
    if found is None:
        found = read_back_full(units, filename, expected)
    _check_joints(found, expected, filename)
    return found


def _check_joints(read: ReadBack, expected: Expected, filename: str) -> None:
    """Every jointtarget read back holds the joints meant, as written to six decimals."""
    if expected.joints is None or not read.joint.any():
        return
    meant = np.degrees(expected.joints[read.joint])
    got = read.robax[read.joint]
    bad = ~(np.abs(got - meant) <= 5e-7 + np.abs(meant) * 1e-12)
    if bad.any():
        first = int(np.flatnonzero(bad.any(axis=1))[0])
        row = int(np.flatnonzero(read.joint)[first])
        raise RapidSemanticError(
            f"the rewritten program commands other joints than planned (statement "
            f"{int(expected.motion[row])} of the rewritten parts: {got[first].tolist()} "
            f"degrees, planned {meant[first].round(6).tolist()}); nothing was written",
            file=filename or None, hint="please report this as a rapidfix bug")


# the jointtarget a template statement moves to, and the axes it holds
_TEMPLATE_NAME = "rapidfix_template_target"
_TEMPLATE_AXES = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
# the robtargets a template statement of kept instructions moves to: name + its slot
_TEMPLATE_ROBTARGET = "rapidfix_template_robtarget"
# the name a declaration declares (after LOCAL / TASK, the storage and the type)
# (a name may hold letters of ISO 8859-1: `\w` takes every letter the grammar's NAME does)
_DECLARED = re.compile(r"\s*(?:LOCAL\s+)?(?:TASK\s+)?(?:VAR|PERS|CONST)\s+\w+\s+(\w+)",
                       re.IGNORECASE)


def _read_columns(units: CheckUnits, expected: Expected, filename: str) -> ReadBack | None:
    """The targets, with the statements the emission made as columns read as columns: the
    MoveAbsJ statements (a JointSlot: text before the name, the name, text after) and
    the instructions kept with filtered robtargets (a TargetSlot: the texts around the
    targets, and the targets, named or inline). The same check as parsing them, at list
    speed. None when there are none or anything does not fit (`read_back` then parses
    the whole).

    - The jointtarget declarations: one regular-expression pass over all of them and one
      conversion of their numbers (`read_jointtarget_declarations`); a name declared
      twice in a scope, or also by another new declaration of the module (the names
      are allocated to be new, so that is a bug), is a clash and stops the rewrite.
    - The robtarget declarations (new ones, and those whose value the emission
      replaced): the same (`read_robtarget_declarations`); the first of a name in a
      scope counts, as in the model.
    - The statements: each distinct text around the names (a CAM program has a few
      dozen) is parsed once, with names of the same kind in their places, and must be a
      call whose targets read those names' values; each name is found as RAPID finds it
      (the routine's data, then the module's) among the new declarations; a robtarget
      written inline is read where it stands.
    - Everything else (the header comments, anything the emission wrote move by move)
      is parsed and read as before, on its own.
    """
    slots, target_slots = units.joint_slots(), units.target_slots()
    k = expected.motion.shape[0]
    if not k or not (any(slots) or any(target_slots)):
        return None
    is_joint = np.fromiter(map(is_not, slots, repeat(None)), bool, len(slots))
    is_target = np.fromiter(map(is_not, target_slots, repeat(None)), bool, len(slots))
    joint_rows, target_rows = is_joint[expected.motion], is_target[expected.motion]
    if expected.slot[joint_rows].any():
        return None
    # the declarations
    declared = units.joint_declarations()
    read = read_jointtarget_declarations([t for texts in declared.values() for t in texts])
    if read is None:
        return None
    names, axes = read
    tables: dict[tuple[str, str | None], dict[str, int]] = {}
    pos = 0
    for key, texts in declared.items():
        table = dict(zip(names[pos:pos + len(texts)], range(pos, pos + len(texts))))
        if len(table) < len(texts):
            _clash(next(n for n in names[pos:pos + len(texts)]
                        if names[pos:pos + len(texts)].count(n) > 1), key, filename)
        tables[key] = table
        pos += len(texts)
    # the names of the other new declarations (the robtargets' too): a clash where a new
    # jointtarget of their module has it; those not robtargets' (`others`, and the new
    # jointtargets) are in the way of a robtarget's name in their scope
    others: dict[tuple[str, str | None], set[str]] = {}
    for robtargets, by_scope in ((False, units.other_declarations()),
                                 (True, units.robtarget_declarations() if tables else {})):
        for scope, texts in by_scope.items():
            for text in texts:
                match = _DECLARED.match(text)
                if match is None:
                    return None
                name = match.group(1).lower()
                for (joint_module, joint_routine), table in tables.items():
                    if joint_module == scope[0] and name in table:
                        _clash(name, (joint_module, joint_routine), filename)
                if not robtargets:
                    others.setdefault(scope, set()).add(name)
    # the statements' names, found in their scopes
    where = np.full(len(slots), -1, dtype=np.int64)
    for (module, routine), idents in units.statement_scopes():
        joint_idents = [i for i in idents if slots[i] is not None]
        if not joint_idents:
            continue
        written = "\n".join([slots[i][1] for i in joint_idents])
        lowered = written.lower().split("\n")
        if not written.isascii() or len(lowered) != len(joint_idents):
            return None
        local = tables.get((module, routine))
        found = list(map(tables.get((module, None), {}).get, lowered))
        if local:
            found = [local.get(name, at) for name, at in zip(lowered, found)]
        if None in found:
            return None
        where[joint_idents] = found
    if slots and is_joint.any() and not _templates_move_to_their_name(one_per_shape(
            map(itemgetter(0, 2), filter(None, slots)))):
        return None
    targets = None
    if target_rows.any():
        at = np.flatnonzero(target_rows)
        targets = _robtarget_targets(units, expected.motion[at], expected.slot[at],
                                     (tables, others))
    if targets is None:  # the kept instructions and their robtargets with everything else
        if not is_joint.any():
            return None
        target_rows = np.zeros(k, dtype=bool)
    # everything else, on its own
    text, order = units.text(without=("joint",) if targets is None else ("joint", "robtarget"))
    local_id = np.full(len(slots), -1, dtype=np.int64)
    local_id[order] = np.arange(len(order))
    rows = np.flatnonzero(~(joint_rows | target_rows))
    motion, slot = local_id[expected.motion[rows]], expected.slot[rows]
    other = read_targets_in_bulk(text, list(range(len(order))), motion, slot)
    if other is None:
        try:
            program = parse_program(text, f"{filename} (rewritten parts)")
            if len(program.motions) != len(order):
                return None
            other = read_targets_full(program.motions, motion, slot)
        except RapidfixError:
            return None
    out = ReadBack.empty(k)
    for field in ("joint", "robax", "trans", "rot", "conf"):
        getattr(out, field)[rows] = getattr(other, field)
    joint = np.flatnonzero(joint_rows)
    out.joint[joint] = True
    out.robax[joint] = axes[where[expected.motion[joint]]]
    if targets is not None:
        at = np.flatnonzero(target_rows)
        out.trans[at], out.rot[at], out.conf[at] = targets
    return out


#: (trans (K,3), rot (K,4), conf (K,4)) of robtargets
_Robtargets = tuple[np.ndarray, np.ndarray, np.ndarray]


def _robtarget_tables(units: CheckUnits
                      ) -> tuple[dict[tuple[str, str | None], dict[str, int]], _Robtargets] | None:
    """The robtarget declarations of the check units: per scope, name -> row (the first of
    a name counts, as in the model), and the rows' values; None when one is not read
    (`read_robtarget_declarations`)."""
    declared = units.robtarget_declarations()
    read = read_robtarget_declarations([t for texts in declared.values() for t in texts])
    if read is None:
        return None
    names, *values = read
    tables: dict[tuple[str, str | None], dict[str, int]] = {}
    pos = 0
    for key, texts in declared.items():
        table = tables.setdefault(key, {})
        deque(map(table.setdefault, names[pos:pos + len(texts)],
                  range(pos, pos + len(texts))), maxlen=0)
        pos += len(texts)
    return tables, (values[0], values[1], values[2])


def _robtarget_targets(units: CheckUnits, motion: np.ndarray, slot: np.ndarray,
                       in_the_way: tuple[dict[tuple[str, str | None], dict[str, int]],
                                         dict[tuple[str, str | None], set[str]]]
                       ) -> _Robtargets | None:
    """The robtargets of checked rows (target `slot[i]` of statement `motion[i]`, each with
    a TargetSlot): a name as RAPID finds it (the routine's data, then the module's) among
    the robtarget declarations of the check units, a literal as written; None where a
    declaration or a literal is not read (`read_robtarget_declarations`), a name is not
    among them or is declared otherwise in its scope (`in_the_way`: the new jointtargets
    and the other new declarations, by scope), or a statement's
    text around its targets does not read them."""
    robtargets = _robtarget_tables(units)
    if robtargets is None:
        return None
    tables, values = robtargets
    target_slots = units.target_slots()
    first = np.full(len(target_slots), -1, dtype=np.int64)  # per statement: its first target
    count = np.zeros(len(target_slots), dtype=np.int64)
    found: list[np.ndarray] = []  # per scope, per target: its row in the values (-1: inline)
    literals: list[str] = []
    total = 0  # targets so far
    for (module, routine), idents in units.statement_scopes():
        idents = [i for i in idents if target_slots[i] is not None]
        if not idents:
            continue
        texts = [target_slots[i][1::2] for i in idents]
        sizes = np.fromiter(map(len, texts), np.int64, len(texts))
        first[idents] = total + np.cumsum(sizes) - sizes
        count[idents] = sizes
        flat = [text for group in texts for text in group]
        inline = np.fromiter((text[:1] == "[" for text in flat), bool, len(flat))
        named = [text for text in flat if text[:1] != "["] if inline.any() else flat
        literals += [text for text in flat if text[:1] == "["] if inline.any() else []
        written = "\n".join(named)
        lowered = written.lower().split("\n") if named else []
        if not written.isascii() or len(lowered) != len(named):
            return None
        for scope in ((module, routine), (module, None)):  # names declared otherwise there
            joint, other = in_the_way[0].get(scope, {}), in_the_way[1].get(scope, set())
            if not (joint.keys().isdisjoint(lowered) and other.isdisjoint(lowered)):
                return None
        local = tables.get((module, routine), {})
        rows = list(map(tables.get((module, None), {}).get, lowered))
        if local:
            rows = [local.get(name, at) for name, at in zip(lowered, rows)]
        if None in rows:
            return None
        scope_rows = np.full(len(flat), -1, dtype=np.int64)
        scope_rows[~inline] = rows
        found.append(scope_rows)
        total += len(flat)
    if not _templates_read_their_robtargets(one_per_shape(
            texts[0::2] for texts in target_slots if texts is not None)):
        return None
    trans, rot, conf = values
    rows_of = np.concatenate(found) if found else np.zeros(0, dtype=np.int64)
    if literals:
        read = read_robtarget_literals(literals)
        if read is None:
            return None
        rows_of[rows_of < 0] = trans.shape[0] + np.arange(len(literals))
        trans, rot, conf = (np.concatenate([a, b]) for a, b in zip(values, read))
    if ((slot >= count[motion]) | (first[motion] < 0)).any():
        return None
    at = rows_of[first[motion] + slot]
    return trans[at], rot[at], conf[at]


def _clash(name: str, scope: tuple[str, str | None], filename: str) -> None:
    module, routine = scope
    raise RapidSemanticError(
        f"the rewritten program declares {name} twice in "
        f"{module if routine is None else module + '.' + routine}; nothing was written",
        file=filename or None, hint="please report this as a rapidfix bug")


def _templates_move_to_their_name(templates: dict[tuple[str, str], None]) -> bool:
    """Each (text before, text after) around a name, with a name in between, is one
    call whose target reads that name's jointtarget."""
    axes = ",".join(f"{v:g}" for v in _TEMPLATE_AXES)
    lines = ["MODULE RapidfixTemplates",
             f"CONST jointtarget {_TEMPLATE_NAME}:=[[{axes}],[0,0,0,0,0,0]];", "PROC t()"]
    lines += [f"{head}{_TEMPLATE_NAME}{tail}" for head, tail in templates]
    lines += ["ENDPROC", "ENDMODULE", ""]
    count = len(templates)
    read = _read_templates("\n".join(lines), count, np.arange(count),
                           np.zeros(count, dtype=np.int64))
    return read is not None and bool(read.joint.all() and (read.robax == _TEMPLATE_AXES).all())


def _templates_read_their_robtargets(templates: dict[tuple[str, ...], None]) -> bool:
    """Each tuple of texts around a statement's targets, with a robtarget name in each
    place between them, is one call whose targets read those names' robtargets, in
    that order."""
    if not templates:
        return True
    most = max(map(len, templates)) - 1
    lines = ["MODULE RapidfixTemplates"]
    lines += [f"CONST robtarget {_TEMPLATE_ROBTARGET}{j}:=[[{j + 1},0,0],[1,0,0,0],[0,0,0,0],"
              "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];" for j in range(most)]
    lines.append("PROC t()")
    motion: list[int] = []
    slot: list[int] = []
    for n, texts in enumerate(templates):
        names = [f"{_TEMPLATE_ROBTARGET}{j}" for j in range(len(texts) - 1)]
        lines.append("".join(part for pair in zip(texts, [*names, ""]) for part in pair))
        motion += [n] * len(names)
        slot += range(len(names))
    lines += ["ENDPROC", "ENDMODULE", ""]
    which = np.asarray(slot, dtype=np.int64)
    read = _read_templates("\n".join(lines), len(templates),
                           np.asarray(motion, dtype=np.int64), which)
    return read is not None and bool(not read.joint.any() and (read.trans[:, 0] == which + 1).all()
                                     and (read.trans[:, 1:] == 0).all())


def _read_templates(text: str, count: int, motion: np.ndarray, slot: np.ndarray
                    ) -> ReadBack | None:
    """Target `slot[i]` of statement `motion[i]` of a template program of `count`
    statements (in bulk, else through the full model); None when it does not parse or
    its statements are not `count` motions."""
    read = read_targets_in_bulk(text, list(range(count)), motion, slot)
    if read is None:
        try:
            program = parse_program(text, "templates")
            if len(program.motions) != count:
                return None
            read = read_targets_full(program.motions, motion, slot)
        except RapidfixError:
            return None
    return read

def read_back_full(units: CheckUnits, filename: str, expected: Expected) -> ReadBack:
    """`read_back` through the full program model (`parse_units`)."""
    return read_targets_full(parse_units(units, filename), expected.motion, expected.slot)


def commanded_joints(robot: RobotModel, read: ReadBack, expected: Expected,
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
    model: ErrorModel, robot: RobotModel, read: ReadBack, expected: Expected, filename: str = ""
) -> np.ndarray:
    """Predicted TCP position error (K,) mm of every expected pose of the output."""
    if expected.motion.shape[0] == 0:
        return np.zeros(0)
    q = commanded_joints(robot, read, expected, filename)
    flange = model.actual_flange(robot, q, expected.context)
    tcp = expected.placement.tcp_positions(flange)
    return np.linalg.norm(tcp - expected.position, axis=1)
