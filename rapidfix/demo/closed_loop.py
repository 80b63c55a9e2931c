"""The loop on the robot: a program rewritten with a model, run on the virtual robot.

A pick-and-place cell program with two tools (each with its own load), a work
object, a gripped part picked up and put down (`GripLoad`), and MoveJ, MoveL
and MoveC to CONST robtargets is written from joint poses the virtual robot can
reach. The generator records, independently of the rewrite, the load every move
carries. The original and the rewritten program are then executed on the
virtual robot in the order their moves run: each move with its load, every joint
arriving from the direction it really moves in (the intermediate points
included), at the cell's temperature. Where each move really ends is compared
with where it should end.

Used by `rapidfix demo` and by the acceptance tests of the closed loop.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rapidfix.atomic import write_text_atomic
from rapidfix.error_model import OutsideRangeWarning
from rapidfix.kinematics import RobotModel, pose
from rapidfix.postprocess import align_axis1, commanded_motions, robtarget_literals
from rapidfix.rapid import parse_program
from rapidfix.sim import RunConditions, point_plan

#: the two tools: (name, TCP translation mm, TCP quaternion, load kg, load cog mm (flange))
TOOLS = (
    ("tGrip", (0.0, 0.0, 160.0), (1.0, 0.0, 0.0, 0.0), 3.0, (0.0, 0.0, 70.0)),
    ("tGlue", (40.0, 0.0, 120.0), (0.9659258, 0.0, 0.258819, 0.0), 1.2, (10.0, 0.0, 50.0)),
)
WOBJ = ("wTable", (700.0, -150.0, 250.0), (0.9238795, 0.0, 0.0, 0.3826834))
#: the gripped part: kg and centre of gravity in the gripper's TCP frame, mm
PART = ("lPart", 6.0, (0.0, 0.0, 40.0))


@dataclass(frozen=True)
class LoopProgram:
    """A generated program and, per move in execution order (K), its truth:
    `q` (K,6) rad the nominal joints of its destination, `tool` index into TOOLS,
    `payload_kg` (K,) and `payload_cog_mm` (K,3) (flange frame) of what it carries."""

    text: str
    q: np.ndarray
    tool: np.ndarray
    payload_kg: np.ndarray
    payload_cog_mm: np.ndarray


def _frame(trans: tuple, quat: tuple) -> np.ndarray:
    return pose(np.array([trans], dtype=float), np.array([quat], dtype=float))[0]


def _tuple(values: Any) -> str:
    return ",".join(f"{v:.9g}" for v in values)


def measured_range(model: Any) -> np.ndarray | None:
    """(6, 2) rad: the joint ranges the model's per-joint curves were measured over
    (NaN rows: not measured), or None when it has none."""
    ranges = [np.asarray(e.valid_range) for e in model.effects if hasattr(e, "valid_range")]
    return ranges[0] if ranges else None


#: a cell keeps its arm at least this far from stretched (the elbow singularity), deg
ELBOW_MARGIN_DEG = 5.0


def _elbow_bent(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """Poses (mask) whose elbow is bent by more than ELBOW_MARGIN_DEG: a stretched arm
    is at the edge of its reach, where a real arm a little shorter than the nominal
    one cannot reach a target at all."""
    _, points = robot.joint_frames(q)
    upper = points[:, 2] - points[:, 1]
    fore = points[:, 4] - points[:, 2]
    sine = np.linalg.norm(np.cross(upper, fore), axis=1) / (
        np.linalg.norm(upper, axis=1) * np.linalg.norm(fore, axis=1))
    return sine > np.sin(np.radians(ELBOW_MARGIN_DEG))


def pick_and_place(robot: RobotModel, seed: int, *, moves: int = 24,
                   smr_offset_mm: np.ndarray | None = None,
                   ranges: np.ndarray | None = None) -> LoopProgram:
    """A cell program of about `moves` moves (see the module doc), reproducible from
    `seed`, its joints within `ranges` (6, 2) rad where given (a cell works where its
    robot was measured)."""
    rng = np.random.default_rng([seed, 13])
    ball = np.zeros(3) if smr_offset_mm is None else np.asarray(smr_offset_mm, dtype=float)
    if ranges is not None:
        ranges = np.where(np.isnan(ranges), robot.limits, ranges)
    want = moves + moves // 4 + 2
    q = point_plan(robot, ball, 2 * want, seed=seed, ranges=ranges)
    q = q[_elbow_bent(robot, q)][:want]
    wobj = _frame(WOBJ[1], WOBJ[2])
    tools = [_frame(t[1], t[2]) for t in TOOLS]
    kinds, tool_of, grip = [], [], []
    gripping = False
    i = 0
    body: list[str] = []
    names: list[str] = []
    while i < len(q) and len(kinds) < moves:
        tool = 0 if len(kinds) < moves * 2 // 3 else 1  # glue the last third
        if tool == 0 and len(kinds) in (moves // 6, moves // 2):
            gripping = not gripping
            body.append(f"    GripLoad {PART[0] if gripping else 'load0'};")
        kind = rng.choice(["J", "L", "C"], p=[0.35, 0.45, 0.2]) if kinds else "J"
        if kind == "C" and i + 1 >= len(q):
            kind = "L"
        t_name, w_name = TOOLS[tool][0], WOBJ[0]
        if kind == "C":
            via, to = f"p{i + 1}", f"p{i + 2}"
            body.append(f"    MoveC {via}, {to}, v200, fine, {t_name}\\WObj:={w_name};")
            names += [via, to]
            tool_of += [tool, tool]
            i += 2
        else:
            to = f"p{i + 1}"
            instr = "MoveJ" if kind == "J" else "MoveL"
            speed = "v500" if kind == "J" else "v200"
            body.append(f"    {instr} {to}, {speed}, fine, {t_name}\\WObj:={w_name};")
            names.append(to)
            tool_of.append(tool)
            i += 1
        kinds.append(kind)
        grip.append(gripping and tool == 0)
    used = len(names)
    qs = q[:used]
    frames = np.array([tools[t] for t in tool_of])
    tcp = np.linalg.inv(wobj) @ robot.fk(qs) @ frames
    literals = robtarget_literals(tcp, robot.confdata(qs), np.full((used, 6), 9e9))
    decls = [f"  CONST robtarget {n}:={lit};" for n, lit in zip(names, literals)]
    tool_decls = [f"  PERS tooldata {t[0]}:=[TRUE,[[{_tuple(t[1])}],[{_tuple(t[2])}]],"
                  f"[{t[3]:g},[{_tuple(t[4])}],[1,0,0,0],0,0,0]];" for t in TOOLS]
    text = "\n".join([
        "MODULE LoopCell",
        *tool_decls,
        f"  PERS wobjdata {WOBJ[0]}:=[FALSE,TRUE,\"\",[[{_tuple(WOBJ[1])}],"
        f"[{_tuple(WOBJ[2])}]],[[0,0,0],[1,0,0,0]]];",
        f"  PERS loaddata {PART[0]}:=[{PART[1]:g},[{_tuple(PART[2])}],[1,0,0,0],0,0,0];",
        *decls,
        "  PROC main()",
        *body,
        "  ENDPROC",
        "ENDMODULE",
        "",
    ])
    # the truth per move (its destination): tool load plus the part while it is gripped
    dest = np.cumsum([2 if k == "C" else 1 for k in kinds]) - 1
    move_tool = np.array(tool_of)[dest]
    tool_mass = np.array([TOOLS[t][3] for t in move_tool])
    tool_cog = np.array([TOOLS[t][4] for t in move_tool], dtype=float)
    part_cog = np.einsum("nij,j->ni", frames[dest][:, :3, :3], PART[2]) + frames[dest][:, :3, 3]
    part = np.where(np.array(grip), PART[1], 0.0)
    mass = tool_mass + part
    cog = (tool_mass[:, None] * tool_cog + part[:, None] * part_cog) / mass[:, None]
    return LoopProgram(text, qs[dest], move_tool, mass, cog)


@dataclass(frozen=True)
class LoopRun:
    """Where the moves of a program really end on the virtual robot: TCP error (K,) mm
    of each move's destination, after the best joint-1 gauge (see `align_axis1`)."""

    error_mm: np.ndarray

    @property
    def mean_mm(self) -> float:
        """Mean over the moves."""
        return float(self.error_mm.mean()) if self.error_mm.size else 0.0


def run_on_robot(virtual: Any, program: LoopProgram, text: str, inserted: set[str],
                 temperature_c: float | None = None, *,
                 joint1_zero_rad: float | None = None) -> LoopRun:
    """Execute `text` (the program, or its rewrite with intermediate points `inserted`)
    on the virtual robot, every move in `program`'s conditions (module doc).

    The errors are taken after the best joint-1 gauge of this run (`align_axis1`), or,
    with `joint1_zero_rad`, after turning back a known constant joint-1 error: the
    gauge a model's base frame was registered in (a simulated set's truth states it),
    where a model's prediction can be compared with the run as it is."""
    robot = virtual.robot
    parsed = parse_program(text.encode(), "loop.mod")
    execution = commanded_motions(parsed, robot)
    q = execution.q_cmd
    # each executed motion belongs to the next move that is not an intermediate point
    dest = np.array([name not in inserted for name in execution.target], dtype=bool)
    owner = np.cumsum(dest) - dest
    if dest.sum() != len(program.q):
        raise AssertionError(f"{dest.sum()} destinations executed, {len(program.q)} moves")
    n = len(q)
    temp = None if temperature_c is None else np.full(n, float(temperature_c))
    ctx = RunConditions(payload_kg=program.payload_kg[owner], temp_c=temp,
                        payload_cog_mm=program.payload_cog_mm[owner])
    tools = np.array([_frame(t[1], t[2]) for t in TOOLS])[program.tool[owner]]
    actual = virtual.tcp_poses(q, tools, ctx)[dest][:, :3, 3]
    intended = (robot.fk(program.q) @ tools[dest])[:, :3, 3]
    if joint1_zero_rad is None:
        aligned = align_axis1(robot, actual, intended)
    else:
        axis = np.asarray(robot.axis_dirs[0], dtype=float)
        base = np.asarray(robot.axis_points[0], dtype=float)
        back = Rotation.from_rotvec(-float(joint1_zero_rad) * axis).as_matrix()
        aligned = (actual - base) @ back.T + base
    return LoopRun(np.linalg.norm(aligned - intended, axis=1))


def demo_on_robot(cell: str | Path, models: dict[str, str | Path], out: str | Path,
                  seed: int) -> dict[str, Any]:
    """The demo's last step: a cell program rewritten with each model (label → file) and
    run on the virtual robot of the measurement set `cell` (its truth.json), before and
    after. Writes OUT/cell_loop.mod and OUT/cell_loop.LABEL.mod."""
    from rapidfix.postprocess import Compensator, RewriteOptions, rewrite_file
    from rapidfix.sim import VirtualRobot

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    virtual = VirtualRobot.from_truth(json.loads((Path(cell) / "truth.json").read_text()))
    comps = {label: Compensator.load(path) for label, path in models.items()}
    ranges = next((measured_range(c.model) for c in comps.values()), None)
    program = pick_and_place(virtual.robot, seed, smr_offset_mm=virtual.smr_offset_mm,
                             ranges=ranges)
    source = out / "cell_loop.mod"
    write_text_atomic(source, program.text)
    floor = virtual.noise_floor(program.q)["mean_tcp_error_mm"]
    rows = {"as programmed": (run_on_robot(virtual, program, program.text, set()).mean_mm,
                              None)}
    for label, comp in comps.items():
        with warnings.catch_warnings():  # the demo's moves stay within the sweeps
            warnings.simplefilter("ignore", OutsideRangeWarning)
            result = rewrite_file(source, out / f"cell_loop.{label}.mod", comp,
                                  RewriteOptions(force=True, approach=True))
        run = run_on_robot(virtual, program, result.data.decode(), result.inserted)
        rows[label] = (run.mean_mm, result.predicted_before_mm)
    return {"program": str(source), "moves": len(program.q), "noise_floor_mm": floor,
            "mean_tcp_error_mm": rows}


def format_on_robot(summary: dict[str, Any]) -> str:
    """The demo's lines for the loop on the robot."""
    lines = [f"on the robot: {summary['program']} ({summary['moves']} moves, two tools, a part "
             "picked and placed), mean TCP error on the virtual robot:"]
    for label, (mean, predicted) in summary["mean_tcp_error_mm"].items():
        said = "" if predicted is None else f" (the rewrite predicted {predicted[0]:.4f} mm " \
            "before compensation)"
        lines.append(f"  {label:<24} {mean:.4f} mm{said}")
    lines.append(f"  noise floor              {summary['noise_floor_mm']:.4f} mm")
    return "\n".join(lines)
