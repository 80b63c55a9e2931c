"""The state the robot is in when each move runs: payload, motion direction, temperature.

Some effects depend on more than the commanded joints. The rewrite takes that
state from the program where the program says it, and from the user where it
cannot:

- **Payload.** The tool's load (or the move's \\TLoad) plus the load a
  `GripLoad` statement set, followed through the routines in the order they
  execute: a loop or an IF joins the loads that can reach a move, a call of a
  routine of the program carries the load into and out of it, and `main`
  starts with none (the controller resets it to load0 when a program starts
  from the beginning). Where different loads can reach a move, or a routine is
  not called from this program, the load is not known before run time: no
  gripped load is assumed there, and the notes say where.
- **Motion direction** of each joint when it arrives (backlash): from the move
  executed just before (`chain.predecessors`); a joint that did not move keeps
  the direction it had. Where the move before is not known before run time (the
  first move of a routine, a loop body or an IF branch), the direction is
  unknown and effects take the value midway between the directions.
- **Temperature** of the cell, as the user states it (`RewriteOptions.temperature_c`).
- **Configuration monitoring** (`ConfL`/`ConfJ \\Off`), followed like the load: with
  it off, the controller reaches a target on the configuration nearest the one it
  is in, not necessarily the one its confdata names (`config_monitoring`).
- **Program displacement** (`PDispOn`, `PDispSet` ... `PDispOff`), followed like the
  load: a displaced move goes where its robtarget is displaced to at run time, which a
  MoveAbsJ would not be (`program_displacement`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rapidfix.error_model import STILL_RAD, Context
from rapidfix.postprocess.plan import FreeConfiguration
from rapidfix.postprocess.resolve import Declarations
from rapidfix.rapid import (
    SYSTEM_DATA,
    NameRef,
    ProcedureCall,
    Program,
    Routine,
    Statement,
    typed_value,
)

_UNKNOWN = "unknown"
#: calls deeper than this are taken as "load not known" (recursion guard)
_MAX_CALL_DEPTH = 32


@dataclass(frozen=True)
class Load:
    """A gripped load: its name as written, mass (kg) and centre of gravity (tool frame, mm)."""

    name: str
    mass: float
    cog: tuple[float, float, float]


NO_LOAD = Load("load0", 0.0, (0.0, 0.0, 0.0))
#: load0's mass in the controller's BASE module: a load this light is no load
LOAD0_KG = 0.001


@dataclass
class GripLoads:
    """Per motion of `program.motions`: the gripped load in effect, None where it is not
    known before run time; `statements` counts the GripLoad statements of the program."""

    load: list[Load | None]
    statements: int = 0
    uncalled: list[str] = field(default_factory=list)


def _join(a: Any, b: Any) -> Any:
    return a if a == b else _UNKNOWN


class _StateWalk:
    """Follows a state that statements set (a gripped load, configuration monitoring)
    through the statement lists in execution order: loops and IFs join what can reach a
    statement, calls of the program's routines carry it in and out (see the module doc).
    Subclasses say which calls change it (`step`) and how two states join (`join`)."""

    unknown: Any = _UNKNOWN

    def __init__(self, program: Program) -> None:
        self.program = program
        self.index_of = {id(m.syntax): k for k, m in enumerate(program.motions)}
        self.routines = {r.name.lower(): r for r in self._routine_nodes()}
        self.record: dict[int, Any] = {}
        self.entries: dict[str, Any] = {}
        self.exits: dict[tuple[str, Any], Any] = {}
        self.active: set[str] = set()
        self.seen: set[int] = set()  # the statements met that set the state

    def join(self, a: Any, b: Any) -> Any:
        """The state when either a or b can reach a statement."""
        return _join(a, b)

    def step(self, call: ProcedureCall, state: Any, routine: str) -> Any:
        """The state after a call that is not a routine of the program."""
        return state

    def _routine_nodes(self) -> list[Routine]:
        return [item for module in self.program.syntax.modules for item in module.items
                if isinstance(item, Routine)]

    def body(self, statements: list[Statement], state: Any, routine: str, depth: int) -> Any:
        """Walk one statement list from `state`; the state after it."""
        index_of, record = self.index_of, self.record
        for statement in statements:
            k = index_of.get(id(statement))
            if k is not None:
                # a move met again in the same state (or met first) keeps it: no join
                known = record.get(k, state)
                record[k] = known if known == state else self.join(known, state)
                continue
            nested = list(statement.bodies())
            if nested:
                after = state
                for inner in nested:
                    end = self.body(inner, state, routine, depth)
                    if end != state:  # a loop may run it again, an IF may skip it
                        self.body(inner, self.join(state, end), routine, depth)
                    after = self.join(after, end)
                state = after
            elif isinstance(statement, ProcedureCall):
                if statement.key in self.routines:
                    state = self.call(statement.key, state, depth + 1)
                else:
                    state = self.step(statement, state, routine)
        return state

    def call(self, key: str, state: Any, depth: int) -> Any:
        """Run routine `key` from `state`; its exit state (unknown on recursion)."""
        self.entries[key] = self.join(self.entries.get(key, state), state)
        memo = self.exits.get((key, state))
        if memo is not None:
            return memo
        if key in self.active or depth > _MAX_CALL_DEPTH:
            return self.unknown
        self.active.add(key)
        routine = self.routines[key]
        end = self.body(routine.body, state, routine.name, depth)
        for handler in routine.handlers:
            self.body(handler.body, self.unknown, routine.name, depth)
        self.active.discard(key)
        self.exits[(key, state)] = end
        return end

    def run(self, start: Any) -> list[str]:
        """Walk from `main` with `start`, then every routine main does not reach from an
        unknown state; the names of those routines."""
        if "main" in self.routines:
            self.call("main", start, 0)
        uncalled = [r.name for key, r in self.routines.items() if key not in self.entries]
        for name in uncalled:
            self.call(name.lower(), self.unknown, 0)
        return uncalled


class _LoadWalk(_StateWalk):
    """The gripped load: set by GripLoad."""

    def __init__(self, program: Program, outside: Declarations) -> None:
        super().__init__(program)
        self.outside = outside

    def load_named(self, expr: Any, routine: str) -> Any:
        """The Load an argument names, or unknown when it is not a static loaddata."""
        if not isinstance(expr, NameRef):
            return _UNKNOWN
        decl = self.program.declaration(expr.name, routine)
        data = None
        if decl is not None:
            if decl.static and decl.type_key == "loaddata":
                data = decl.data
        else:
            data = self.outside.get(expr.name, "loaddata")
            if data is None and expr.key in SYSTEM_DATA:
                value, type_name = SYSTEM_DATA[expr.key]
                data = typed_value(type_name, value) if type_name == "loaddata" else None
        if data is None:
            return _UNKNOWN
        if data.mass <= LOAD0_KG:  # load0 (0.001 kg): no gripped load
            return NO_LOAD
        return Load(expr.name, float(data.mass), tuple(float(c) for c in data.cog))

    def step(self, call: ProcedureCall, state: Any, routine: str) -> Any:
        if call.key != "gripload":
            return state
        self.seen.add(id(call))
        args = call.args
        return (self.load_named(args[0].value, routine)
                if args and args[0].value is not None else _UNKNOWN)


#: configuration monitoring of linear/circular (ConfL) and joint (ConfJ) moves:
#: True on, False off, None not known before run time
Monitoring = tuple["bool | None", "bool | None"]
_MONITOR_CALLS = {"confl": 0, "confj": 1}


class _ConfWalk(_StateWalk):
    """Configuration monitoring: set by `ConfL \\On|\\Off` and `ConfJ \\On|\\Off`."""

    unknown: Monitoring = (None, None)

    def join(self, a: Any, b: Any) -> Any:
        return a if a == b else tuple(x if x == y else None for x, y in zip(a, b))

    def step(self, call: ProcedureCall, state: Any, routine: str) -> Any:
        slot = _MONITOR_CALLS.get(call.key)
        if slot is None:
            return state
        self.seen.add(id(call))
        switches = {a.key for a in call.args if a.kind == "optional"}
        value = True if "on" in switches else False if "off" in switches else None
        return tuple(value if i == slot else v for i, v in enumerate(state))


#: moves the joint way (ConfJ); every other robtarget move is linear or circular (ConfL)
_JOINT_MOVES = ("movej", "triggj")
_MONITOR_WORDS = re.compile(r"\bconf[lj]\b", re.IGNORECASE)


def _mentions_monitoring(text: str) -> bool:
    """Whether the text has the word ConfL or ConfJ in any case. A plain search of the
    lowered text first (the case-blind pattern alone reads a large program at about
    0.1 µs a character): without either letter sequence the pattern cannot match."""
    lowered = text.lower()
    if "confl" not in lowered and "confj" not in lowered:
        return False
    return _MONITOR_WORDS.search(text) is not None


def config_monitoring(program: Program) -> tuple[np.ndarray, np.ndarray]:
    """Per motion of `program.motions`: (off, known) bool arrays — configuration
    monitoring for that move's kind (ConfJ for MoveJ/TriggJ…, ConfL for the linear and
    circular rest) is
    known to be off / is known before run time. `main` starts with both on, as the
    controller sets them when a program starts from the beginning."""
    m = len(program.motions)
    if not _mentions_monitoring(program.text):  # nothing switches it: on everywhere
        return np.zeros(m, dtype=bool), np.ones(m, dtype=bool)
    walk = _ConfWalk(program)
    walk.run((True, True))
    record, unknown, motions = walk.record, walk.unknown, program.motions
    # the state's slot of each motion name (a program has a few): 1 ConfJ, 0 ConfL
    slot = {name: int(name.lower().startswith(_JOINT_MOVES))
            for name in {motion.name for motion in motions}}
    values = [record.get(k, unknown)[slot[motion.name]] for k, motion in enumerate(motions)]
    off = np.fromiter((value is False for value in values), dtype=bool, count=m)
    known = np.fromiter((value is not None for value in values), dtype=bool, count=m)
    return off, known


class _DisplacementWalk(_StateWalk):
    """Program displacement: set by `PDispOn` and `PDispSet`, taken off by `PDispOff`."""

    def step(self, call: ProcedureCall, state: Any, routine: str) -> Any:
        key = call.key
        if key in ("pdispon", "pdispset"):
            self.seen.add(id(call))
            return True
        if key == "pdispoff":
            self.seen.add(id(call))
            return False
        return state


def program_displacement(program: Program) -> np.ndarray:
    """Per motion of `program.motions`: whether a program displacement may be active when
    it runs (on, or not known before run time). `main` starts without one, as the
    controller takes it off when a program starts from the beginning; where nothing in
    the program sets one, none is."""
    m = len(program.motions)
    if "pdisp" not in program.text.lower():
        return np.zeros(m, dtype=bool)
    walk = _DisplacementWalk(program)
    walk.run(False)
    if not walk.seen:
        return np.zeros(m, dtype=bool)
    record = walk.record
    return np.fromiter((record.get(k, _UNKNOWN) is not False for k in range(m)),
                       dtype=bool, count=m)


def grip_loads(program: Program, outside: Declarations | None = None) -> GripLoads:
    """The gripped load in effect at every motion of the program (see the module doc)."""
    walk = _LoadWalk(program, outside or Declarations([]))
    uncalled = walk.run(NO_LOAD)
    if len(walk.seen) == 0:  # nothing in this program sets a gripped load
        loads: list[Load | None] = [NO_LOAD] * len(program.motions)
        return GripLoads(loads, 0, uncalled)
    loads = [None if walk.record.get(k, _UNKNOWN) == _UNKNOWN else walk.record[k]
             for k in range(len(program.motions))]
    return GripLoads(loads, len(walk.seen), uncalled)


def total_load(tool_mass: np.ndarray, tool_cog: np.ndarray, tool_frame: np.ndarray,
               grip_mass: np.ndarray, grip_cog: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mass (N,) kg and centre of gravity (N,3) mm in the flange frame of a tool's load
    (cog in the flange frame) and a gripped load (cog in the tool frame (N,4,4))."""
    grip_flange = np.einsum("nij,nj->ni", tool_frame[:, :3, :3], grip_cog) + tool_frame[:, :3, 3]
    mass = tool_mass + grip_mass
    weighted = tool_mass[:, None] * tool_cog + grip_mass[:, None] * grip_flange
    cog = np.divide(weighted, mass[:, None], out=np.zeros_like(weighted),
                    where=mass[:, None] > 0.0)
    return mass, cog


def arrival_directions(q: np.ndarray, prev: np.ndarray,
                       initial: np.ndarray | None = None) -> np.ndarray:
    """Sign (N,6) of each joint's motion into point i from point prev[i] (−1: not known).

    A joint that did not move keeps the direction it had at prev[i], along the chain
    (pointer jumping: a few vectorised passes, however long the chain); at a point
    without prev the direction is `initial` (N,6) (default 0: not known).
    """
    q = np.asarray(q, dtype=float)
    n = q.shape[0]
    prev = np.asarray(prev, dtype=np.int64)
    if n == 0:
        return np.zeros((0, 6))
    has_prev = prev >= 0
    step = np.where(has_prev[:, None], q - q[np.maximum(prev, 0)], 0.0)
    sign = np.where(np.abs(step) > STILL_RAD, np.sign(step), 0.0)
    if initial is not None:
        sign = np.where(has_prev[:, None], sign, initial)
    rows = np.arange(n)
    # source[i, j]: the point whose sign decides joint j at point i
    source = np.where((sign != 0) | ~has_prev[:, None], rows[:, None], prev[:, None])
    while True:
        nxt = np.take_along_axis(source, source, axis=0)
        if np.array_equal(nxt, source):
            break
        source = nxt
    return np.take_along_axis(sign, source, axis=0)


@dataclass(frozen=True)
class RunState:
    """What the rewrite assumes about how the program runs, for the header and the notes."""

    temperature_c: float | None
    notes: list[str]
    warnings: list[str]
    recorded: dict[str, str]


def context_for(payload_kg: np.ndarray, payload_cog_mm: np.ndarray, direction: np.ndarray | None,
                temperature_c: float | None) -> Context:
    """The error model's context for rows with these conditions."""
    n = payload_kg.shape[0]
    temp = None if temperature_c is None else np.full(n, float(temperature_c))
    return Context(payload_kg=payload_kg, temp_c=temp, last_direction=direction,
                   payload_cog_mm=payload_cog_mm)


def _absj_joints(motion: Any) -> np.ndarray | None:
    """The joints (rad) of a MoveAbsJ whose jointtarget is known before run time."""
    if motion.name.lower() != "moveabsj" or motion.target_kind != "jointtarget":
        return None
    target = motion.target
    data = target.data if target is not None and target.static else None
    if data is None:
        return None
    return np.radians(np.asarray(data.robax, dtype=float))


class ProgramConditions:
    """Payload, arrival direction and temperature of every target row of a program.

    Built once per rewrite from the program, its resolved sites and target rows;
    calling it with the joints of every row gives the error model's Context.
    `joint_moves`: linear and circular moves become MoveAbsJ (their CirPoint is then
    no stop on the way).
    """

    def __init__(self, program: Program, sites: list[Any], targets: Any,
                 outside: Declarations, temperature_c: float | None,
                 needs: frozenset[str], *, joint_moves: bool = True) -> None:
        n = len(targets.site)
        self.temperature_c = temperature_c
        self.needs = needs
        # the payload of every target row and what is known of the grips (set by _payload)
        self.payload_kg: np.ndarray | float = 0.0
        self.payload_cog_mm: np.ndarray | None = None
        self.grip_notes: list[str] = []
        self.grip_unknown = 0
        self.grip_statements = 0
        grips = grip_loads(program, outside) if "payload_kg" in needs else None
        motions = program.motions
        self._program = program
        self._pred: np.ndarray | None = None
        # the rows in blocks, one per site with rows (contiguous, in site order)
        owner = np.asarray(targets.site, dtype=np.int64)
        site_motion = np.fromiter((site.index for site in sites), dtype=np.int64,
                                  count=len(sites))
        #: per site: its instruction's place in `program.motions`, and its kind ('L', 'J',
        #: 'C' or 'X', `Site.kind`)
        self.site_motion = site_motion
        self.site_kind = np.array([site.kind for site in sites], dtype="U1").reshape(len(sites))
        motion_of_row = site_motion[owner] if n else np.zeros(0, dtype=np.int64)
        self._payload(targets, grips, motion_of_row)
        #: per site: a synchronized move (`\\ID`, Site.synchronized); a program
        #: displacement may be active when it runs
        self.synchronized = np.fromiter((site.synchronized for site in sites), dtype=bool,
                                        count=len(sites))
        self.displaced = program_displacement(program)[site_motion]
        off, _ = config_monitoring(program)
        #: rows that run with configuration monitoring off (ConfL/ConfJ \Off)
        self.config_free = off[motion_of_row] if n else np.zeros(0, dtype=bool)
        chain = "last_direction" in needs or bool(self.config_free.any())
        # the points the chain runs through: target rows, then known MoveAbsJ joints
        first = np.flatnonzero(np.diff(owner, prepend=-1)) if n else np.zeros(0, np.int64)
        last = np.append(first[1:], n) - 1
        block_motion = site_motion[owner[first]]
        last_point = np.full(len(motions), -1, dtype=np.int64)
        last_point[block_motion] = last
        prev_row = np.full(n, -1, dtype=np.int64)
        extra: list[np.ndarray] = []
        absj: list[int] = []
        if chain:  # known MoveAbsJ joints: among the instructions that are no site
            is_site = np.zeros(len(motions), dtype=bool)
            is_site[site_motion] = True
            for k in np.flatnonzero(~is_site).tolist():
                joints = _absj_joints(motions[k])
                if joints is not None:
                    last_point[k] = n + len(extra)
                    extra.append(joints)
                    absj.append(k)
        extra_prev = np.full(len(extra), -1, dtype=np.int64)
        if chain and n:
            pred = self.predecessors()
            before = pred[block_motion]
            known = before >= 0
            prev_row[first[known]] = last_point[before[known]]
            several = known & (last > first)
            circular = (self.site_kind == "C")[owner[first]]
            # MoveAbsJ: the CirPoint is not a stop; else the controller's arc passes the
            # CirPoint, then the ToPoint (rows of one site follow each other)
            to_end = several & circular if joint_moves else np.zeros_like(several)
            prev_row[last[to_end]] = last_point[before[to_end]]
            follow = several & ~to_end
            if follow.any():
                block = np.repeat(np.arange(first.size), last - first + 1)  # of each row
                rows = np.arange(n)
                inner = np.flatnonzero(follow[block] & (rows != first[block]))
                prev_row[inner] = inner - 1
        if chain and absj:
            pred = self.predecessors()
            for i, k in enumerate(absj):
                if pred[k] >= 0:
                    extra_prev[i] = last_point[pred[k]]
        self.prev = np.concatenate([prev_row, extra_prev])
        self.extra = np.array(extra, dtype=float).reshape(-1, 6)
        self.n = n
        self.unknown_start = int(np.count_nonzero(prev_row < 0)) if n else 0
        self.forced: np.ndarray | None = None

    def predecessors(self) -> np.ndarray:
        """Per motion of the program: the motion executed just before it (-1: not known
        before run time), `chain.predecessors`, worked out once per rewrite."""
        if self._pred is None:
            from rapidfix.postprocess.chain import predecessors

            self._pred = np.asarray(predecessors(self._program), dtype=np.int64)
        return self._pred

    def _payload(self, targets: Any, grips: GripLoads | None, motion_of_row: np.ndarray) -> None:
        """Mass and centre of gravity per row: the tool's load plus the gripped load."""
        n = motion_of_row.shape[0]
        tool_mass = np.asarray(targets.payload_kg, dtype=float)
        tool_cog = (np.zeros((n, 3)) if targets.payload_cog_mm is None
                    else np.asarray(targets.payload_cog_mm, dtype=float))
        self.grip_notes = []
        self.grip_unknown = 0
        self.grip_statements = 0 if grips is None else grips.statements
        if grips is None or grips.statements == 0 or n == 0:
            self.payload_kg, self.payload_cog_mm = tool_mass, tool_cog
            return
        loads = [grips.load[k] for k in motion_of_row.tolist()]
        known = np.array([load is not None for load in loads], dtype=bool)
        total = (np.zeros(n, bool) if targets.total_load is None
                 else np.asarray(targets.total_load, bool))
        mass = np.array([0.0 if ld is None else ld.mass for ld in loads])
        cog = np.array([(0.0, 0.0, 0.0) if ld is None else ld.cog for ld in loads]).reshape(n, 3)
        mass = np.where(total, 0.0, mass)  # \TLoad is the whole load of its move
        frame = np.broadcast_to(targets.placement.tool, (n, 4, 4))
        self.payload_kg, self.payload_cog_mm = total_load(tool_mass, tool_cog, frame, mass, cog)
        self.grip_unknown = int(np.count_nonzero(~known & ~total))

    def free_configuration(self) -> FreeConfiguration | None:
        """The rows whose configuration the controller chooses (monitoring off), with the
        chain of moves it chooses it from; None when every row keeps its confdata."""
        if not self.config_free.any():
            return None
        return FreeConfiguration(self.config_free, self.prev, self.extra)

    def force_arrival(self, rows: np.ndarray, direction: np.ndarray) -> None:
        """Rows reached from a known side (an approach point just before them): their
        arrival direction (len(rows), 6), 0 on joints still taken from the move order."""
        if self.forced is None:
            self.forced = np.zeros((self.n, 6))
        self.forced[np.asarray(rows, dtype=np.int64)] = direction

    def __call__(self, q_rows: np.ndarray, known: np.ndarray) -> Context:
        """The Context of every row for joints q_rows (N,6) rad; rows not `known` (not
        solved) break the direction chain."""
        direction = None
        if "last_direction" in self.needs and self.n:
            q = np.concatenate([np.asarray(q_rows, dtype=float), self.extra])
            ok = np.concatenate([np.asarray(known, dtype=bool), np.ones(len(self.extra), bool)])
            prev = np.where(ok[np.maximum(self.prev, 0)] & (self.prev >= 0), self.prev, -1)
            direction = arrival_directions(q, prev)[: self.n]
            direction[~np.asarray(known, dtype=bool)] = 0.0
            if self.forced is not None:
                direction = np.where(self.forced != 0.0, self.forced, direction)
        return context_for(self.payload_kg, self.payload_cog_mm, direction, self.temperature_c)
