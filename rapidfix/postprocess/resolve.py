"""Which motion targets can be compensated, and their poses, confdata and frames as arrays.

For every motion instruction of a program this decides whether its targets are
known before run time, finds its tool and work object (in the program, among
the controller's predefined data, or in declaration files the user passes for
data defined elsewhere) and gathers, per target, the TCP pose in its work
object, the confdata, the external axes, the frames and the payload — one row
per target, in program order, so that everything after this is vectorised.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import chain
from typing import Any

import numpy as np

from rapidfix.kinematics import pose
from rapidfix.postprocess.placement import Placement, shared
from rapidfix.rapid import Declaration, MotionInstruction, Operand, Program, ToolData, WobjData

#: instructions that become MoveAbsJ (instruction key -> path kind)
JOINT_FORM = {"movel": "L", "movej": "J", "movec": "C"}
#: optional arguments MoveAbsJ accepts as well
MOVEABSJ_OPTIONS = frozenset({"conc", "id", "noeoffs", "v", "t", "z", "inpos", "wobj", "tload"})
_UNDECLARED = "is not declared in this file"


@dataclass(slots=True)
class Site:
    """One motion instruction and what the post-processor does with it.

    `kind` 'L', 'J', 'C' (linear, joint, circular path) or 'X' (another instruction,
    kept, only its robtargets filtered); `rows` its target rows (CirPoint first);
    `reason` why it is left as it was (None when it is compensated); `index` the
    motion's place in `Program.motions`; `kept` why, when joint targets are emitted, it
    keeps its instruction with a filtered robtarget (no MoveAbsJ can stand for it).
    """

    motion: MotionInstruction
    kind: str
    targets: list[Operand] = field(default_factory=list)
    rows: list[int] = field(default_factory=list)
    reason: str | None = None
    index: int = -1
    kept: str | None = None
    #: a synchronized move of a MultiMove program (`\\ID`): its program's other tasks run
    #: the same moves, so it takes no intermediate nor approach points
    synchronized: bool = False

    @property
    def where(self) -> str:
        """`file:line` of the instruction."""
        span = self.motion.span
        return f"{span.file}:{span.line}"

    @property
    def label(self) -> str:
        """The instruction and its destination as written, for messages (a destination
        longer than a robtarget written inline cut short)."""
        target = self.targets[-1] if self.targets else None
        text = quoted(target.text) if target else ""
        if len(text) > LABEL_CHARS:
            text = text[:LABEL_CHARS - 4] + " ..."
        return f"{self.motion.name} {text}".strip()


#: the longest destination a message quotes whole
LABEL_CHARS = 200


def quoted(text: str) -> str:
    """An operand's text as a one-line message quotes it: its comments left out and its
    line breaks and runs of whitespace made one space (`Offs(p1, ! far⏎ 0,0,1)`)."""
    if "!" in text:  # the fast path's module, imported only where a comment may be
        from rapidfix.rapid import blank_comments

        text = blank_comments(text)
    return " ".join(text.split())


@dataclass
class Targets:
    """Per target row: TCP `pose` (N,4,4) in its work object, `conf` (N,4) int,
    `extax` (N,6), frames `placement`, the tool's load `payload_kg` (N,) and its centre of
    gravity `payload_cog_mm` (N,3) in the flange frame, `total_load` (N,) True where
    \\TLoad gives the move's whole load (a GripLoad is then not added), `site` (N,)
    owning site index, `operand` the Operand of each row."""

    pose: np.ndarray
    conf: np.ndarray
    extax: np.ndarray
    placement: Placement
    payload_kg: np.ndarray
    site: np.ndarray
    operand: list[Operand]
    payload_cog_mm: np.ndarray | None = None
    total_load: np.ndarray | None = None


class Declarations:
    """Data declared outside the program (Compensator.load(decl_files)), by lower-case name.

    The program sees another module's data as the controller does: module-level
    declarations that are not LOCAL. A name two of those modules declare is ambiguous
    (the controller refuses to load such a task) and is used from neither.
    """

    def __init__(self, programs: list[Program]) -> None:
        self._by_name: dict[str, Declaration] = {}
        self._hidden: dict[str, str] = {}  # name -> why a declaration of it is not used
        self._global: dict[str, Declaration] = {}  # the first global one, ambiguous or not
        ambiguous: dict[str, str] = {}
        for program in programs:
            for decl in program.declarations:
                if decl.routine is not None:
                    continue
                key = decl.key
                first = self._by_name.get(key)
                if decl.local:
                    self._hidden.setdefault(key, f"{decl.name} in module {decl.module} of "
                                                 f"{decl.source.filename} is LOCAL to that module")
                    continue
                self._global.setdefault(key, decl)
                if first is not None:
                    ambiguous[key] = (f"{decl.name} is declared in module {first.module} of "
                                      f"{first.source.filename} and in module {decl.module} "
                                      f"of {decl.source.filename}")
                else:
                    self._by_name[key] = decl
        for key, why in ambiguous.items():  # taken from neither
            del self._by_name[key]
            self._hidden[key] = why

    def declared_twice(self, program: Program) -> list[str]:
        """The program's own module-level global declarations that one of these modules
        declares too, each as 'name (module M of file)': a task holding both does not
        load on the controller."""
        found: list[str] = []
        if not self._global:  # no declaration file nor other module: nothing to compare
            return found
        for decl in program.declarations:
            if decl.routine is None and not decl.local:
                other = self._global.get(decl.key)
                if other is not None:
                    found.append(f"{decl.name} (module {other.module} of "
                                 f"{other.source.filename})")
        return found

    def get(self, name: str, type_name: str) -> Any:
        """Typed value of a declaration of this type, or None."""
        decl = self._by_name.get(name.lower())
        if decl is None or decl.type_key != type_name or not decl.static:
            return None
        return decl.data

    def why_not(self, name: str, type_name: str) -> str | None:
        """Why `get` gave nothing for a name the declaration files do mention, or None
        when they do not mention it."""
        key = name.lower()
        hidden = self._hidden.get(key)
        if hidden is not None and key not in self._by_name:
            return hidden
        decl = self._by_name.get(key)
        if decl is None:
            return None
        where = f"{decl.name} in {decl.source.filename}"
        if decl.type_key != type_name:
            return f"{where} is a {decl.type_name}, not a {type_name}"
        if not decl.static or decl.value is None:
            return f"{where}: {decl.reason or 'its value is not known before run time'}"
        return f"{where}: its value is not a {type_name}"


def operand_data(operand: Operand | None, type_name: str, outside: Declarations) -> tuple[Any, str]:
    """(typed value, '') of an operand, or (None, reason) when it is not known."""
    if operand is None:
        return None, f"no {type_name}"
    if operand.static and operand.value is not None:
        data = operand.data
        if data is not None:
            return data, ""
    if operand.form == "name" and operand.name and operand.declaration is None:
        data = outside.get(operand.name, type_name)
        if data is not None:
            return data, ""
        why = outside.why_not(operand.name, type_name)
        if why is not None:
            return None, why
    reason = operand.reason or "not known before run time"
    if _UNDECLARED in reason:
        reason += " (pass the file that declares it with Compensator.load(decl_files))"
    return None, reason


def _target_value(operand: Operand, outside: Declarations) -> tuple[Any, str]:
    """A robtarget operand's raw value ((x,y,z), (q1..q4), (cf..), (e..)), or (None, reason).

    The raw tuple (already checked against the robtarget shape by the RAPID layer)
    is used instead of the typed view: this runs once per move of the program.
    """
    if operand.static and operand.value is not None and operand.type_name == "robtarget":
        return operand.value, ""
    data, why = operand_data(operand, "robtarget", outside)
    if data is None:
        return None, why
    return (data.trans, data.rot, data.robconf, data.extax), ""


class _FrameCache:
    """Typed tool / work object / load data per distinct operand (a program uses a few)."""

    def __init__(self, outside: Declarations) -> None:
        self.outside = outside
        self.known: dict[tuple, tuple[Any, str]] = {}

    def get(self, operand: Operand, type_name: str) -> tuple[Any, str]:
        key = (type_name, *_operand_key(operand))
        found = self.known.get(key)
        if found is None:
            found = self.known[key] = operand_data(operand, type_name, self.outside)
        return found


def _operand_key(operand: Operand | None) -> tuple:
    """What decides an operand's data and reason: equal keys, equal outcomes."""
    if operand is None:
        return (None,)
    return (operand.text, operand.form, operand.static, id(operand.declaration), operand.reason)


def operand_label(operands: list[Operand], operand: Operand) -> str:
    """'' for the destination (the site's label names it), else 'CirPoint p20: '."""
    if operand is operands[-1]:
        return ""
    return f"{operand.argument.name or 'CirPoint'} {quoted(operand.text)}: "


def _instruction_kind(motion: MotionInstruction, emit: str) -> tuple[bool, str, str | None]:
    """(moves to robtargets, site kind, why it keeps its instruction with a filtered
    robtarget when joint targets are emitted) for an instruction name, whatever its
    optional arguments."""
    if motion.target_kind != "robtarget":
        return False, "X", None
    kind = JOINT_FORM.get(motion.name.lower())
    if kind is None:
        kept = f"{motion.name} has no joint-target form" if emit == "jointtargets" else None
        return True, "X", kept
    return True, kind, None


def _optional_reason(motion: MotionInstruction) -> str | None:
    """Why MoveAbsJ cannot take one of the instruction's optional arguments, or None."""
    for name, op in motion.optional.items():
        if name not in MOVEABSJ_OPTIONS:
            return f"optional argument \\{op.argument.name} has no MoveAbsJ form"
    return None


@dataclass(frozen=True)
class _Frames:
    """The tool, work object and load (kg, centre of gravity in the flange frame, mm; `total`
    when \\TLoad names the whole load) a site's targets are compensated with."""

    tool: ToolData
    wobj: WobjData | None
    mass: float
    cog: tuple[float, float, float] = (0.0, 0.0, 0.0)
    total: bool = False


def _site_frames(motion: MotionInstruction, frames: _FrameCache) -> _Frames | str:
    """The frames of a motion instruction, or why they are not known."""
    tool_op = motion.tool
    if tool_op is None:
        return "no tool"
    tool, why = frames.get(tool_op, "tooldata")
    if tool is None:
        return f"tool {tool_op.text}: {why}"
    wobj = None
    wobj_op = motion.wobj
    if wobj_op is not None:
        wobj, why = frames.get(wobj_op, "wobjdata")
        if wobj is None:
            return f"work object {wobj_op.text}: {why}"
        if not wobj.ufprog:
            return (f"work object {wobj_op.text} moves with mechanical unit "
                    f"{wobj.ufmec!r}: known only at run time")
        if wobj.robhold and tool.robhold:
            return "tool and work object are both held by the robot"
    if not tool.robhold and (wobj is None or not wobj.robhold):
        return "stationary tool used without a robot-held work object"
    mass = tool.tload.mass if tool.robhold else 0.0
    cog = tuple(tool.tload.cog) if tool.robhold else (0.0, 0.0, 0.0)
    tload = motion.optional.get("tload")
    if tload is not None:
        load, why = frames.get(tload, "loaddata")
        if load is None:
            return f"\\TLoad {tload.text}: {why}"
        if load.mass > 0.001:  # \TLoad:=load0 (0.001 kg) means "the tool's load"
            return _Frames(tool, wobj, load.mass, tuple(load.cog), True)
    return _Frames(tool, wobj, mass, cog)


def _site_values(operands: list[Operand], outside: Declarations) -> list[tuple] | str:
    """The raw robtarget values of a site's targets, or why one is not usable."""
    values = []
    for operand in operands:
        if operand.static and operand.value is not None and operand.type_name == "robtarget":
            data = operand.value  # the raw tuple, shape-checked by the RAPID layer
        else:
            data, why = _target_value(operand, outside)
            if data is None:
                return operand_label(operands, operand) + why
        q = data[1]
        if q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] < 1e-12:
            return operand_label(operands, operand) + "orientation quaternion is zero"
        values.append(data)
    return values


def _around_targets(motion: MotionInstruction) -> tuple[str | None, tuple, bool]:
    """(why MoveAbsJ cannot take an optional argument or None, what decides the frames,
    whether it is a synchronized move)."""
    optional = motion.optional
    key = (_operand_key(motion.arguments.get("tool")),
           _operand_key(optional.get("wobj") if optional else None),
           _operand_key(optional.get("tload") if optional else None))
    return (_optional_reason(motion) if optional else None), key, "id" in optional


def resolve(program: Program, outside: Declarations, emit: str, *,
            static_external_axes: bool = True) -> tuple[list[Site], Targets]:
    """Sites for every robtarget motion instruction, and the rows of the usable targets.

    `static_external_axes` False: a move to a target whose external axes stand anywhere
    but 0 or unused (9E9) gets a reason (`moving_axes_reason`), since a track may carry
    the robot or a positioner the work there, which nothing in the program describes.

    One cheap pass over the instructions: what depends only on an instruction's
    name, or only on its tool / work object / load operands (motions that share
    those operands share one answer), is worked out once per distinct name or
    operand set, and the numbers become arrays in one go. A site of one target
    written in the program (the usual move) costs a few attribute reads here; its
    orientation is checked with all the others on the arrays.
    """
    sites: list[Site] = []
    values: list[tuple] = []
    operands: list[Operand] = []
    row_site: list[int] = []  # per row: its site and its frame set
    row_set: list[int] = []
    frames = _FrameCache(outside)
    kinds: dict[str, tuple[bool, str, str | None]] = {}
    frame_sets: dict[tuple, tuple[_Frames | str, int]] = {}
    # per shared tail: [why MoveAbsJ cannot take an option, frame key, frame set or None,
    # synchronized]
    by_tail: dict[Any, list] = {}
    joint = emit == "jointtargets"
    deferred = False  # rows whose quaternion is checked on the arrays
    for index, motion in enumerate(program.motions):
        info = kinds.get(motion.name)
        if info is None:
            info = kinds[motion.name] = _instruction_kind(motion, emit)
        moves_to_robtargets, kind, kept = info
        if not moves_to_robtargets:
            continue
        site_ops = motion.targets
        if not site_ops:
            continue
        # what depends on the operands besides the targets: once per shared tail
        shared = motion.shared
        around = by_tail.get(shared) if shared is not None else None
        if around is None:
            reason, frame_key, synchronized = _around_targets(motion)
            around = [reason, frame_key, None, synchronized]
            if shared is not None:
                by_tail[shared] = around
        if kept is None and joint:
            kept = around[0]
        known = around[2]
        if known is None:
            known = frame_sets.get(around[1])
            if known is None:
                known = frame_sets[around[1]] = (_site_frames(motion, frames), len(frame_sets))
            around[2] = known
        used, set_index = known
        if len(site_ops) == 1 and not isinstance(used, str):
            operand = site_ops[0]
            if operand.static and operand.value is not None \
                    and operand.type_name == "robtarget":
                row = len(values)
                row_site.append(len(sites))
                sites.append(Site(motion, kind, site_ops, [row], None, index, kept,
                                  around[3]))
                values.append(operand.value)  # the raw tuple, shape-checked by the RAPID layer
                operands.append(operand)
                row_set.append(set_index)
                deferred = True
                continue
        site = Site(motion, kind, site_ops, [], None, index, kept, around[3])
        sites.append(site)
        found = _site_values(site_ops, outside)
        if isinstance(found, str):
            site.reason = found
            continue
        if isinstance(used, str):
            site.reason = used
            continue
        first = len(values)
        site.rows = [first] if len(found) == 1 else list(range(first, first + len(found)))
        values.extend(found)
        operands.extend(site_ops)
        row_site.extend([len(sites) - 1] * len(found))
        row_set.extend([set_index] * len(found))
    sets = [used for used, _ in frame_sets.values()]  # by index: insertion order
    flat = _flat_values(values)
    if (deferred or not static_external_axes) and flat is not None:
        drop = np.zeros(len(flat), dtype=bool)
        if deferred:
            drop = _zero_quaternions(flat)
            _drop_rows(sites, row_site, drop)
        if not static_external_axes:
            _drop_moving_axes(sites, row_site, flat, drop)
        if drop.any():
            keep = ~drop
            _renumber(sites, row_site, drop)
            rows = np.flatnonzero(keep).tolist()
            values = [values[r] for r in rows]
            operands = [operands[r] for r in rows]
            row_site = [row_site[r] for r in rows]
            row_set = [row_set[r] for r in rows]
            flat = flat[keep]
    return sites, _arrays(values, operands, (row_site, row_set), sets, flat)


#: numbers of a robtarget value: position 3, quaternion 4, confdata 4, external axes 6
_WIDTHS = (3, 4, 4, 6)
_ROW = sum(_WIDTHS)


def _flat_values(values: list[tuple]) -> np.ndarray | None:
    """The raw robtarget values (shape-checked by the RAPID layer) as one (N, 17) array
    in one pass, or None when their numbers do not add up (then `_arrays` takes them
    column by column and fails)."""
    numbers = chain.from_iterable(chain.from_iterable(values))
    try:
        flat = np.fromiter(numbers, dtype=float, count=_ROW * len(values))
    except ValueError:  # fewer numbers
        return None
    if next(numbers, None) is not None:  # more numbers
        return None
    return flat.reshape(len(values), _ROW)


def _zero_quaternions(flat: np.ndarray) -> np.ndarray:
    """(N,) rows whose orientation quaternion is zero (the test `_site_values` makes)."""
    q = flat[:, 3:7]
    return q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3] < 1e-12


def _drop_rows(sites: list[Site], row_site: list[int], zero: np.ndarray) -> None:
    """The sites of one target whose quaternion is zero (rare) get that reason and no
    rows (`_renumber` moves the rows of the others up)."""
    for site_index in sorted({row_site[r] for r in np.flatnonzero(zero).tolist()}):
        site = sites[site_index]  # only one-target sites are checked on the arrays
        site.reason = operand_label(site.targets, site.targets[0]) \
            + "orientation quaternion is zero"
        site.rows = []


#: an external axis value at least this large is RAPID's 9E9: the axis is not used
UNUSED_AXIS = 1e9


def moving_axes_reason(values: np.ndarray) -> str:
    """Why a target whose external axes (6,) stand at `values` is left as it was."""
    standing = [f"eax_{'abcdef'[k]} at {values[k]:g}" for k in range(6)
                if 0 < abs(values[k]) < UNUSED_AXIS]
    axes = "axes " if len(standing) > 1 else "axis "
    return (f"external {axes}{', '.join(standing)}: a track carrying the robot or a positioner "
            "carrying the work stands elsewhere there, and rapidfix does not model it "
            "(RewriteOptions(static_external_axes=True) where they carry neither)")


def _drop_moving_axes(sites: list[Site], row_site: list[int], flat: np.ndarray,
                      drop: np.ndarray) -> None:
    """Every site with a target whose external axes stand anywhere but 0 or unused gets
    `moving_axes_reason` and no rows; its rows are marked in `drop`."""
    extax = np.abs(flat[:, 11:17])
    moving = ((extax > 0) & (extax < UNUSED_AXIS)).any(axis=1) & ~drop
    reasons: dict[tuple[float, ...], str] = {}  # a track's few stations: each worded once
    for row in np.flatnonzero(moving).tolist():
        site = sites[row_site[row]]
        if site.rows:
            values = tuple(flat[row, 11:17].tolist())
            reason = reasons.get(values)
            if reason is None:
                reason = reasons[values] = moving_axes_reason(flat[row, 11:17])
            site.reason = operand_label(site.targets, site.targets[site.rows.index(row)]) \
                + reason
            drop[site.rows] = True
            site.rows = []


def _renumber(sites: list[Site], row_site: list[int], drop: np.ndarray) -> None:
    """The rows of the sites that keep theirs, moved up past the `drop`ped ones."""
    new_row = np.cumsum(~drop) - 1
    first = int(np.argmax(drop))
    for site_index in sorted(set(row_site[first:])):
        site = sites[site_index]
        site.rows = [int(new_row[r]) for r in site.rows]


def _arrays(values: list[tuple], operands: list[Operand],
            rows: tuple[list[int], list[int]], sets: list[_Frames | str],
            flat: np.ndarray | None = None) -> Targets:
    """The rows as arrays: raw robtarget values (`flat`, (N, 17), when made already), and
    per row its site and frame set (`rows`)."""
    if not values:
        return Targets(np.zeros((0, 4, 4)), np.zeros((0, 4), int), np.zeros((0, 6)),
                       Placement.identity(0), np.zeros(0), np.zeros(0, int), [],
                       np.zeros((0, 3)), np.zeros(0, bool))
    n = len(values)

    def column(k: int, width: int) -> np.ndarray:
        """Item k of every value (all of length `width`, shape-checked), as (n, width)."""
        flat = np.fromiter(chain.from_iterable(r[k] for r in values), dtype=float)
        return flat.reshape(n, width)  # a value of another length fails here

    if flat is None:
        trans, rot, conf, extax = (column(k, w) for k, w in enumerate(_WIDTHS))
    else:
        trans, rot, conf, extax = (np.ascontiguousarray(flat[:, a:b])
                                   for a, b in ((0, 3), (3, 7), (7, 11), (11, 17)))
    conf = conf.astype(int)
    owner, row_set = (np.array(column, dtype=int) for column in rows)
    # a stand-in for the frame sets that are reasons (no row uses them)
    usable = [f for f in sets if not isinstance(f, str)]
    chosen = [f if not isinstance(f, str) else usable[0] for f in sets]
    identity = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    tool = _poses([f.tool.tframe for f in chosen])
    wobj_u = _poses([f.wobj.uframe if f.wobj is not None else identity for f in chosen])
    wobj_o = _poses([f.wobj.oframe if f.wobj is not None else identity for f in chosen])
    stationary = np.array([not f.tool.robhold for f in chosen], dtype=bool)
    mass = np.array([f.mass for f in chosen], dtype=float)
    cog = np.array([f.cog for f in chosen], dtype=float).reshape(-1, 3)
    total = np.array([f.total for f in chosen], dtype=bool)
    wobj = wobj_u @ wobj_o
    if (row_set == row_set[0]).all():  # one tool and work object throughout: no copies
        first = row_set[0]
        placement = Placement(shared(tool[first], n), shared(wobj[first], n), stationary[row_set])
    else:
        placement = Placement(tool[row_set], wobj[row_set], stationary[row_set])
    return Targets(pose(trans, rot), conf, extax, placement, mass[row_set],
                   owner, operands, cog[row_set], total[row_set])


def _poses(frames: list[Any]) -> np.ndarray:
    """(N,4,4) from rapid Pose values or (trans, rot) tuples; each distinct frame built once."""
    keys: dict[tuple, int] = {}
    index = np.empty(len(frames), dtype=int)
    unique: list[tuple] = []
    for i, frame in enumerate(frames):
        key = (tuple(frame.trans), tuple(frame.rot)) if hasattr(frame, "trans") else frame
        j = keys.get(key)
        if j is None:
            j = keys[key] = len(unique)
            unique.append(key)
        index[i] = j
    trans = np.array([u[0] for u in unique], dtype=float)
    rot = np.array([u[1] for u in unique], dtype=float)
    return pose(trans, rot)[index]
