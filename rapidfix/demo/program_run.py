"""Run a measurement program on the virtual robot and write what the tracker saw.

The program is executed the way the controller would run a straight-line RAPID
program: from `main`, through calls of the module's own parameterless routines,
statement by statement. Moves command the joints the nominal controller would
(`rapidfix.postprocess.execute.commanded_motions`: jointtargets as stored,
robtargets through the nominal inverse kinematics on their confdata) and take the
time `rapidfix.campaign.timing` gives them; `WaitTime` waits; `Stop` pauses (for
`pause_s`); `PulseDO`/`SetDO`/`TPWrite` trigger a measurement. Without any
trigger in the program, the tracker takes a point when the robot has stood still
at a fine point for the first `WaitTime` after it arrived.

Every measurement is taken with the robot's true errors, the pose it came from
(backlash), the payload the pose table gives the point (the operator mounts it),
the time since the start (thermal drift) and the tracker's noise, in the tracker's
own frame and clock.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.campaign import MotionSettings, move_durations
from rapidfix.exceptions import RapidSemanticError
from rapidfix.postprocess import commanded_motions
from rapidfix.rapid import NameRef, Node, Number, ProcedureCall, Program, Routine, Statement, String
from rapidfix.sim import RunConditions, VirtualRobot

IGNORED_CALLS = frozenset({"gripload", "confj", "confl", "accset", "velset", "singarea",
                           "tperase", "pathacclim", "motionsup", "setdo", "reset", "set",
                           "tpwrite"})


@dataclass(frozen=True)
class Run:
    """What a program run measured: per measurement (M) the commanded joints `q` (M, 6)
    rad, the joints commanded just before (`q_prev`), the time since the start (s),
    the id the program wrote (TPWrite) or None, and the total run time."""

    q: np.ndarray
    q_prev: np.ndarray
    time_s: np.ndarray
    ids: list[str | None]
    total_s: float


def _fail(program: Program, node: Node, message: str) -> RapidSemanticError:
    line, col = program.source.line_column(node.start)
    return RapidSemanticError(message, file=program.filename, line=line, column=col)


def _statements(program: Program) -> list[Statement]:
    """main's statements in execution order, calls of the module's routines inlined."""
    routines = {item.name.lower(): item for module in program.syntax.modules
                for item in module.items if isinstance(item, Routine)}
    if "main" not in routines:
        raise RapidSemanticError("no PROC main() to run", file=program.filename)
    out: list[Statement] = []

    def walk(routine: Routine, depth: int) -> None:
        if depth > 20:
            raise _fail(program, routine, "routine calls nest more than 20 deep")
        for stmt in routine.body:
            if isinstance(stmt, ProcedureCall) and stmt.key in routines:
                called = routines[stmt.key]
                if called.parameters or called.kind != "PROC":
                    raise _fail(program, stmt, f"the simulator runs only calls of "
                                f"parameterless PROCs, not {stmt.name}")
                walk(called, depth + 1)
            else:
                out.append(stmt)

    walk(routines["main"], 0)
    return out


def _trigger_id(st: Statement) -> str | bool | None:
    """False: not a trigger; None: a PulseDO; else the point id a TPWrite writes
    (messages starting with 'rapidfix:' are for the operator, not triggers)."""
    if not isinstance(st, ProcedureCall):
        return False
    if st.key == "pulsedo":
        return None
    if st.key == "tpwrite" and st.args and isinstance(st.args[0].value, String):
        text = st.args[0].value.value
        return False if text.startswith("rapidfix:") else text
    return False


def _number(program: Program, expr: Node | None) -> float:
    if isinstance(expr, Number):
        return float(expr.value)
    if isinstance(expr, NameRef):
        decl = program.declaration(expr.name)
        if decl is not None and isinstance(decl.value, (int, float)):
            return float(decl.value)
    raise _fail(program, expr, "the simulator needs a number or a num constant here")


def run_program(program: Program, robot_model: object, *, motion: MotionSettings,
                tool_mm: np.ndarray, pause_s: float = 60.0) -> Run:
    """Walk the program (see module doc) and time it; nothing is measured yet."""
    execution = commanded_motions(program, robot_model)
    q_of = {int(m): execution.q_cmd[k] for k, m in enumerate(execution.motion)}
    motion_of = {id(m.syntax): k for k, m in enumerate(program.motions)}
    stmts = _statements(program)
    has_trigger = any(_trigger_id(st) is not False for st in stmts)
    # one pass for the moves' joints, then their durations in one vectorised call
    moves: list[np.ndarray] = []
    for st in stmts:
        if isinstance(st, ProcedureCall) and id(st) in motion_of:
            k = motion_of[id(st)]
            if k not in q_of:
                raise _fail(program, st, f"{st.name}: its target is not known before run "
                            "time or not reachable on its confdata")
            moves.append(q_of[k])
    q_moves = np.array(moves).reshape(-1, 6)
    start = np.vstack([np.zeros((1, 6)), q_moves[:-1]])
    durations = move_durations(robot_model, start, q_moves, motion, tool_mm=tool_mm)

    clock = 0.0
    n_move = 0
    here = np.zeros(6)
    before = np.zeros(6)
    arrived_fine = False
    q_out, prev_out, t_out, id_out = [], [], [], []

    def measure(label: str | None) -> None:
        q_out.append(here)
        prev_out.append(before)
        t_out.append(clock)
        id_out.append(label)

    for st in stmts:
        if not isinstance(st, ProcedureCall):
            raise _fail(program, st, "the simulator runs straight-line programs: no "
                        "IF, FOR, WHILE, TEST or assignments")
        key = st.key
        if id(st) in motion_of:
            before, here = here, q_moves[n_move]
            clock += float(durations[n_move])
            n_move += 1
            zone = program.motions[motion_of[id(st)]].zone
            arrived_fine = zone is not None and zone.text.lower() == "fine"
        elif key == "waittime":
            args = [a for a in st.args if a.kind == "required"]
            clock += _number(program, args[0].value if args else None)
            if not has_trigger and arrived_fine:
                measure(None)
            arrived_fine = False
        elif key == "stop":
            clock += pause_s
        elif _trigger_id(st) is not False:
            measure(_trigger_id(st))  # type: ignore[arg-type]
        elif key in IGNORED_CALLS:
            continue
        else:
            raise _fail(program, st, f"{st.name}: not an instruction the simulator runs")
    q = np.array(q_out).reshape(-1, 6)
    return Run(q, np.array(prev_out).reshape(-1, 6), np.array(t_out), id_out, clock)


def measure_run(vr: VirtualRobot, run: Run, payload_kg: np.ndarray, *, seed: int,
                clock_offset_s: float = 0.0) -> tuple[np.ndarray, np.ndarray,
                                                      np.ndarray | None]:
    """Tracker-frame positions (M, 3) mm, tracker clock times (M,) and arm temperatures
    (M,) (None without thermal drift) of a run's measurements on the virtual robot."""
    temp = vr.errors.temperature(run.time_s) if vr.errors.needs_temperature else None
    ctx = RunConditions(payload_kg=np.asarray(payload_kg, dtype=float), time_s=run.time_s,
                        temp_c=temp, q_prev=run.q_prev)
    xyz = vr.measure(run.q, ctx, frame="tracker", seed=seed)
    return xyz, run.time_s + clock_offset_s, temp
