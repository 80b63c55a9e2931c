"""Rewrite one RAPID program with compensated targets: the post-processor's main job.

Steps, each vectorised over all targets of the file:
1. parse; refuse a program rapidfix already compensated (unless forced);
2. resolve every motion target with its tool and work object (`resolve`);
3. inverse kinematics on the confdata branch and compensation (`plan`);
4. for linear and circular moves that become MoveAbsJ, intermediate points
   until the joint-interpolated path stays within the tolerance (`path`);
5. span edits: CONST jointtargets and MoveAbsJ (or filtered robtargets), a
   header comment; every other byte stays as it was. Each edit replaces or
   inserts whole statements and declarations, which are also collected as
   `CheckUnits`;
6. parse the output again — its new units, which is the same check as
   parsing all of it (`reparse_changes`) — and push what it commands through the
   model (`verify`): the predicted worst-case TCP deviation.

A MoveL or MoveC whose start is not known before run time (the first move of
a routine, a loop body or an IF branch) keeps its instruction and gets a
filtered robtarget instead, so its path stays the controller's line or arc.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from rapidfix import __version__
from rapidfix.atomic import write_bytes_atomic
from rapidfix.digest import sha256_bytes
from rapidfix.error_model.context import Context
from rapidfix.exceptions import (
    InvalidOption,
    OutputExistsError,
    RapidSemanticError,
)
from rapidfix.gc_pause import cyclic_gc_paused
from rapidfix.postprocess.chain import predecessors
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.conditions import ProgramConditions
from rapidfix.postprocess.emission_forms import (
    joint_edits,
    joint_statement,
    jointtarget_declaration,
    jointtarget_literals,
    robtarget_literals,
    statement_variant,
)
from rapidfix.postprocess.header import MARK, Header, read_header
from rapidfix.postprocess.naming import NameAllocator, identifier_counts
from rapidfix.postprocess.path import (
    MIN_PATH_TOLERANCE_MM,
    Curves,
    Refinement,
    chain_span,
    line_deviation_bound,
    refine,
    wrist_levers,
)
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.plan import Plan, compensate_joints, plan_nearest, plan_targets
from rapidfix.postprocess.reparse_changes import CheckUnits
from rapidfix.postprocess.resolve import Declarations, Site, Targets, operand_label, resolve
from rapidfix.postprocess.verify import Expected, predicted_deviation, read_back
from rapidfix.rapid import MotionInstruction, Program, parse_program
from rapidfix.rapid.edit import Editor
from rapidfix.rapid.format import format_declaration

EMIT_CHOICES = ("jointtargets", "robtargets")
#: an approach point stands this far beyond twice a joint's play (rad)
APPROACH_EXTRA_RAD = np.radians(0.01)


def _is_fine(program: Program, motion: MotionInstruction) -> bool:
    zone = motion.zone
    value = zone.argument.value if zone is not None else None
    return value is not None and program.text[value.start:value.end].strip().lower() == "fine"


#: optional arguments left off the intermediate points of a subdivided move
INTERMEDIATE_DROPS = frozenset({"inpos", "z", "t", "id"})
INTERMEDIATE_ZONE = "z0"
#: why a MoveL/MoveC kept its instruction when its start is not known
START_UNKNOWN = "start not known before run time"


@dataclass(frozen=True)
class RewriteOptions:
    """How to rewrite: what to emit, the path tolerance (mm), strict and force."""

    emit: str = "jointtargets"
    path_tolerance_mm: float = 0.1
    strict: bool = False
    force: bool = False
    #: the cell temperature the program will run at (°C); None: not known
    temperature_c: float | None = None
    #: put an approach point before every compensated fine point, so that each joint
    #: with play arrives from one known side (unidirectional positioning)
    approach: bool = False

    def __post_init__(self) -> None:
        """Refuse values the rewrite cannot honour (InvalidOption names the field)."""
        if self.emit not in EMIT_CHOICES:
            raise InvalidOption("emit", f"must be one of {', '.join(EMIT_CHOICES)}")
        if not (math.isfinite(self.path_tolerance_mm) and self.path_tolerance_mm > 0):
            raise InvalidOption("path_tolerance_mm", "must be a positive number of mm")
        if self.path_tolerance_mm < MIN_PATH_TOLERANCE_MM:
            raise InvalidOption(
                "path_tolerance_mm", f"{self.path_tolerance_mm:g} mm is below what the model "
                f"can resolve; give at least {MIN_PATH_TOLERANCE_MM:g} mm")
        if self.temperature_c is not None and not -50.0 <= self.temperature_c <= 150.0:
            raise InvalidOption("temperature_c", f"{self.temperature_c:g} °C is not a cell "
                                "temperature (give degrees Celsius, -50 to 150)")
        if self.approach and self.emit != "jointtargets":
            # an approach point fixes the side each joint arrives from; a robtarget leaves
            # the joints to the controller's inverse kinematics, so it cannot
            raise InvalidOption("approach", f"needs emit 'jointtargets' (not {self.emit!r}): "
                                "approach points are joint positions, and a robtarget "
                                "leaves the joints to the controller")



def header_options(options: RewriteOptions, comp: Compensator) -> dict[str, str]:
    """What changes the output besides the input and the model, as the header records it."""
    recorded = {
        "emit": options.emit,
        "path_tolerance_mm": f"{options.path_tolerance_mm:g}",
        "robot": comp.robot.name,
    }
    if comp.decl_paths:
        recorded["decls_sha256"] = comp.decls_sha256
    if options.temperature_c is not None:
        recorded["temperature_c"] = f"{options.temperature_c:g}"
    if options.approach:
        recorded["approach"] = "fine_points"
    return recorded


@dataclass(frozen=True)
class Skipped:
    """A motion instruction left as it was, and why."""

    where: str
    label: str
    reason: str

    def __str__(self) -> str:
        return f"{self.where}: {self.label}: {self.reason}"


@dataclass
class RewriteResult:
    """What a rewrite did; `data` is the output file's bytes."""

    filename: str
    data: bytes
    moves_total: int
    moves_compensated: int
    moves_filtered: int
    points_added: int
    skipped: list[Skipped]
    worst_predicted_mm: float | None
    worst_path_mm: float | None
    header: Header
    written: bool = False
    output: str | None = None
    backup: str | None = None
    inserted: set[str] = field(default_factory=set)
    #: how the program's run was taken (payload, directions, temperature): printed
    notes: list[str] = field(default_factory=list)
    #: what had to be assumed and may make the result wrong: printed as warnings, exit 3
    warnings: list[str] = field(default_factory=list)
    #: the model's predicted TCP error of the original program's moves (mean, max), mm
    predicted_before_mm: tuple[float, float] | None = None
    #: why moves kept their instruction with a filtered robtarget: reason -> count
    filtered_reasons: dict[str, int] = field(default_factory=dict)

    def report_lines(self) -> list[str]:
        """What the command prints."""
        lines = []
        if self.written:
            backup = f" (backup {self.backup})" if self.backup else ""
            lines.append(f"wrote {self.output}{backup}")
        lines.append(
            f"{self.filename}: {self.moves_compensated} of {self.moves_total} moves compensated"
            f", {self.points_added} intermediate points added"
            f", {len(self.skipped)} left as they were"
        )
        for reason, count in self.filtered_reasons.items():
            lines.append(f"  {count} linear/circular moves kept their instruction "
                         f"with a filtered robtarget ({reason})")
        lines.extend(f"  {note}" for note in self.notes)
        if self.predicted_before_mm is not None:
            mean, worst = self.predicted_before_mm
            lines.append(f"predicted TCP error of the original moves on this robot: mean "
                         f"{mean:.4f} mm, max {worst:.4f} mm")
        if self.worst_predicted_mm is not None:
            lines.append(
                f"predicted worst-case TCP deviation from the intended poses: "
                f"{self.worst_predicted_mm:.6f} mm"
            )
        if self.worst_path_mm is not None:
            lines.append(f"largest predicted deviation from a line or arc between points: "
                         f"{self.worst_path_mm:.4f} mm")
        return lines


# ---------------------------------------------------------------------------- helpers
def _stem(site: Site, slot: int) -> str:
    motion = site.motion
    operand = site.targets[slot]
    if operand.form == "name" and operand.name:
        return operand.name
    if operand.form in ("offs", "reltool") and operand.name:
        return f"{operand.name}_{operand.form}"
    return f"{motion.name}_L{motion.span.line}"


def _indent_before(program: Program, offset: int) -> str | None:
    """Whitespace between the line start and offset, or None if text precedes it."""
    source = program.source
    before = source.text[source.line_start(offset):offset]
    return before if before.strip() == "" else None


class _TakeUp:
    """The direction of each joint along a path whose joints reverse at its start.

    A reversing joint with play stands still until its motor has taken the play up;
    between the two directions its direction is the fraction taken up, so the path
    check sees the joint stand (not jump) at the start of the move.
    """

    def __init__(self, play: np.ndarray, context: Context, from_row: np.ndarray,
                 q_start: np.ndarray, absj: dict[int, np.ndarray]) -> None:
        self.play = play
        self.active = context.last_direction is not None and bool(np.any(play > 0))
        self.start_dir = np.zeros((len(from_row), 6))
        if context.last_direction is not None:
            self.start_dir = np.asarray(context.last_direction, dtype=float)[from_row].copy()
            if absj:  # a MoveAbsJ start: its direction is not followed here
                self.start_dir[np.fromiter(absj, dtype=int, count=len(absj))] = 0.0
        self.q_start = q_start

    def __call__(self, ctx: Context, seg: np.ndarray, q: np.ndarray) -> Context:
        if not self.active or ctx.last_direction is None:
            return ctx
        travel = np.abs(q - self.q_start[seg])
        frac = np.clip(travel / np.where(self.play > 0, self.play, 1.0), 0.0, 1.0)
        frac = np.where(self.play > 0, frac, 1.0)
        start = self.start_dir[seg]
        return replace(ctx, last_direction=start + (ctx.last_direction - start) * frac)


class _Rewriter:
    """State of one rewrite (kept together so the steps read as methods)."""

    def __init__(self, program: Program, comp: Compensator, options: RewriteOptions) -> None:
        self.program = program
        self.comp = comp
        self.options = options
        self.robot = comp.robot
        self.model = comp.model
        self.editor = Editor(program)
        self.names = NameAllocator(
            texts=[program.text, *(decl_program.text for decl_program in comp.decls)])
        self.skipped: list[Skipped] = []
        self.decl_blocks: dict[Any, list[str]] = {}
        self.decl_anchor_order: list[Any] = []
        self.inserted: set[str] = set()
        #: site index -> arrival direction (6,) of the moves given an approach point, and
        #: how far (rad, per joint) each approach point stands from its target
        self.approach: dict[int, np.ndarray] = {}
        self.approach_margin = np.zeros(6)
        self.refinement: Refinement | None = None
        self.refined_sites: list[int] = []
        #: the arrival direction of every intermediate point (refinement order), if followed
        self.inter_direction: np.ndarray | None = None
        self.units = CheckUnits()
        # what verification reads back: (statement id, target slot, target row) ...
        self.checks: list[tuple[int, int, int]] = []
        # ... and intermediate points: (statement id, refined segment, its index there)
        self.inter_checks: list[tuple[int, int, int]] = []
        # set by plan(): the resolved sites and target rows, the program's run conditions,
        # the solved plan, each compensated site's emission mode ('joint' or 'filtered')
        # and why a site is 'filtered' although jointtargets were asked for
        self.sites: list[Site] = []
        self.targets: Targets | None = None
        self.conditions: ProgramConditions | None = None
        self.plan_: Plan | None = None
        self.mode: dict[int, str] = {}
        self.filtered_reason: dict[int, str] = {}
        # set by paths(): the frames and run conditions of the refined segments
        self.seg_frames: Placement | None = None
        self.seg_context: Context | None = None

    # ------------------------------------------------------------------ plan
    def plan(self) -> None:
        """Resolve, solve and compensate every target; decide each move's emission mode."""
        outside = Declarations(self.comp.decls)
        self.sites, self.targets = resolve(self.program, outside, self.options.emit)
        t = self.targets
        self.conditions = ProgramConditions(
            self.program, self.sites, t, outside, self.options.temperature_c,
            self.model.context_fields(), joint_moves=self.options.emit == "jointtargets")
        self.plan_ = None
        if self.options.approach:
            self._plan_approach()
        if self.plan_ is None:
            self.plan_ = plan_targets(self.model, self.robot, t.pose, t.conf, t.placement,
                                      self.conditions, self.conditions.free_configuration())
        # rows are in site order: the first failed row of each site names its reason
        for row in np.flatnonzero(~self.plan_.ok).tolist():
            site = self.sites[int(t.site[row])]
            if site.reason is None:
                label = operand_label(site.targets, t.operand[row])
                site.reason = label + self.plan_.reason[row]
        # emission mode of each compensated site: 'joint' (MoveAbsJ) or 'filtered'
        self.mode = {}
        self.filtered_reason = {}
        for i, site in enumerate(self.sites):
            if site.reason is None:
                joint = self.options.emit == "jointtargets" and site.kind in "LJC"
                self.mode[i] = "joint" if joint else "filtered"

    def _plan_approach(self) -> None:
        """Every joint with play reaches a compensated MoveJ fine point moving up (down
        where its lower limit is too close): compensate those rows in that direction.
        A MoveL or MoveC keeps its path: its joints arrive the way the path takes them."""
        play = self.model.play()
        if self.options.emit != "jointtargets" or not np.any(play > 0):
            return
        self.approach_margin = np.where(play > 0, 2.0 * play + APPROACH_EXTRA_RAD, 0.0)
        sites = [i for i, site in enumerate(self.sites)
                 if site.rows and site.kind == "J" and _is_fine(self.program, site.motion)]
        if not sites:
            return
        rows = np.array([self.sites[i].rows[-1] for i in sites], dtype=np.int64)
        up = np.broadcast_to((play > 0).astype(float), (len(rows), 6))
        direction = up.copy()
        for _ in range(2):  # once with all up, once more if a limit turned some down
            self.conditions.force_arrival(rows, direction)
            t = self.targets
            self.plan_ = plan_targets(self.model, self.robot, t.pose, t.conf, t.placement,
                                      self.conditions, self.conditions.free_configuration())
            start = self.plan_.q_cmd[rows] - direction * self.approach_margin
            low = np.asarray(self.robot.limits, dtype=float)[:, 0]
            down = (start < low) & (direction > 0)
            if not down.any():
                break
            direction = np.where(down, -up, direction)
        self.approach = dict(zip(sites, direction))

    # ------------------------------------------------------------------ paths
    def _start_state(self, motion: MotionInstruction | None) -> tuple | None:
        """(q_ideal, q_cmd) where the robot is after `motion` (not a site), if known before
        run time."""
        if motion is None:
            return None
        if motion.target_kind == "jointtarget" and motion.name.lower() == "moveabsj":
            data = motion.target.data if motion.target is not None else None
            if data is not None and motion.target.static:
                q = np.radians(np.asarray(data.robax, dtype=float))
                return q, q
        return None

    def paths(self) -> None:
        """Start of every linear/circular move, and intermediate points within the tolerance."""
        if self.options.emit != "jointtargets":
            return
        mode, sites, motions = self.mode, self.sites, self.program.motions
        n = len(sites)
        site_motion = np.fromiter((site.index for site in sites), dtype=np.int64, count=n)
        site_of_motion = np.full(len(motions) + 1, -1, dtype=np.int64)  # [-1]: no motion
        site_of_motion[site_motion] = np.arange(n)
        compensated = np.zeros(n, dtype=bool)
        compensated[list(mode)] = True
        last_row = np.fromiter((site.rows[-1] if site.rows else -1 for site in sites),
                               dtype=np.int64, count=n)
        moves = np.array(sorted(i for i, m in mode.items()
                                if m == "joint" and sites[i].kind in "LC"), dtype=np.int64)
        previous = np.asarray(predecessors(self.program), dtype=np.int64)[site_motion[moves]]
        after = site_of_motion[previous]  # the site of the motion before, or -1
        # a move after another compensated site starts where that one ends; one after an
        # instruction that is not a site (a MoveAbsJ) may start at its joints
        keep = (after >= 0) & compensated[np.maximum(after, 0)]
        start_rows = np.where(keep, last_row[np.maximum(after, 0)], -1)
        starts: dict[int, np.ndarray] = {}  # site -> the joints of the MoveAbsJ it follows
        for k in np.flatnonzero(after < 0).tolist():
            start = self._start_state(motions[previous[k]] if previous[k] >= 0 else None)
            if start is not None:
                keep[k] = True
                starts[int(moves[k])] = start[0]
        for i in moves[~keep].tolist():
            mode[i] = "filtered"
            self.filtered_reason[i] = START_UNKNOWN
        segs = moves[keep].tolist()
        from_row = start_rows[keep]
        absj = {k: starts[i] for k, i in enumerate(segs) if i in starts}
        to_rows = [sites[i].rows[-1] for i in segs]
        via_rows = [sites[i].rows[0] for i in segs]
        circular_sites = [sites[i].kind == "C" for i in segs]
        self.refined_sites = segs
        if not segs:
            return
        t, p = self.targets, self.plan_
        to_row, via_row = np.array(to_rows), np.array(via_rows)
        circular = np.array(circular_sites, dtype=bool)
        q0i, q0c = p.q_ideal[from_row], p.q_cmd[from_row]
        start_flange = p.flange[from_row]  # the previous target's intended tool0 pose
        if absj:
            at = np.fromiter(absj, dtype=int, count=len(absj))
            q0i[at] = q0c[at] = np.array(list(absj.values()))
            start_flange[at] = self.robot.fk(q0i[at])
        frames = t.placement.take(to_row)
        start_tcp = frames.tcp(start_flange)
        curves = Curves(start_tcp, t.pose[to_row], t.pose[via_row, :3, 3], circular)
        # points between two targets run in the destination's conditions: its payload,
        # and each joint moving the way it moves into the destination
        seg_ctx = p.context.take(to_row)
        take_up = _TakeUp(self.model.play(), p.context, from_row, q0c, absj)

        def predict(seg: np.ndarray, q: np.ndarray) -> np.ndarray:
            flange = self.model.actual_flange(self.robot, q, take_up(seg_ctx.take(seg), seg, q))
            return frames.take(seg).tcp(flange)[:, :3, 3]

        def solve(seg: np.ndarray, poses: np.ndarray, seed: np.ndarray) -> tuple:
            sub: Plan = plan_nearest(self.model, self.robot, poses, seed, frames.take(seg),
                                     seg_ctx.take(seg))
            return sub.q_ideal, sub.q_cmd, sub.ok

        bound = self._line_bounds(start_flange, to_row, q0c, frames)
        bound[circular] = np.inf
        self.refinement = refine(
            curves, (q0i, p.q_ideal[to_row]), (q0c, p.q_cmd[to_row]),
            self.options.path_tolerance_mm, predict, solve, bound,
        )
        for k in np.flatnonzero(self.refinement.failed):
            self.mode[segs[k]] = "filtered"
            self.filtered_reason[segs[k]] = (
                "its arc is degenerate" if curves.degenerate[k] else
                "no intermediate points keep its path within the path tolerance "
                f"{self.options.path_tolerance_mm:g} mm")
        self.seg_frames, self.seg_context = frames, seg_ctx
        if seg_ctx.last_direction is not None and self.refinement.seg.size:
            self._redirect(q0c, to_row, take_up.start_dir)

    def _redirect(self, q0c: np.ndarray, to_row: np.ndarray, start_dir: np.ndarray) -> None:
        """Directions along refined paths, and the points whose direction changed solved again.

        A joint need not move monotonically along a line: between intermediate points
        it moves the way the points say, and it arrives at the destination from the
        last of them. The points were solved with the destination's direction; those
        (and destinations) whose joints arrive the other way are compensated again.
        """
        r, p = self.refinement, self.plan_
        order = np.lexsort((r.s, r.seg))
        seg, q_inter = r.seg[order], r.q_cmd[order]
        m = to_row.shape[0]
        # one chain per segment: start, intermediate points, destination
        first = np.searchsorted(seg, np.arange(m))
        count = np.bincount(seg, minlength=m)
        pts = np.concatenate([q0c, q_inter, p.q_cmd[to_row]])
        start_id, inter_id = np.arange(m), m + np.arange(seg.shape[0])
        dest_id = m + seg.shape[0] + np.arange(m)
        prev = np.full(pts.shape[0], -1, dtype=np.int64)
        prev[inter_id] = np.where(np.arange(seg.shape[0]) == first[seg], start_id[seg],
                                  inter_id - 1)
        prev[dest_id] = np.where(count > 0, m + first + count - 1, start_id)
        from rapidfix.postprocess.conditions import arrival_directions

        initial = np.zeros((pts.shape[0], 6))
        initial[:m] = start_dir  # where each path starts, joints point as they arrived there
        direction = arrival_directions(pts, prev, initial)
        dest_dir = np.asarray(p.context.last_direction, dtype=float)
        inter_dir, new_dest = direction[inter_id], direction[dest_id]
        forced = self.conditions.forced
        if forced is not None:  # destinations behind an approach point arrive as planned
            new_dest = np.where(forced[to_row] != 0.0, forced[to_row], new_dest)
        used = self.seg_context.last_direction[seg]
        redo = np.flatnonzero((inter_dir != used).any(axis=1))
        if redo.size:
            ctx = replace(self.seg_context.take(seg[redo]), last_direction=inter_dir[redo])
            qc, good, _ = compensate_joints(self.model, self.robot, r.q_ideal[order][redo], ctx)
            rows = order[redo]
            r.q_cmd[rows] = np.where(good[:, None], qc, r.q_cmd[rows])
        self.inter_direction = np.empty_like(inter_dir)
        self.inter_direction[order] = inter_dir
        changed = np.flatnonzero((new_dest != dest_dir[to_row]).any(axis=1)
                                 & (count > 0) & p.ok[to_row])
        if changed.size:
            rows = to_row[changed]
            all_dir = dest_dir.copy()
            all_dir[rows] = new_dest[changed]
            context = replace(p.context, last_direction=all_dir)
            qc, good, _ = compensate_joints(self.model, self.robot, p.q_ideal[rows],
                                            context.take(rows))
            p.q_cmd[rows] = np.where(good[:, None], qc, p.q_cmd[rows])
            self.plan_ = replace(p, context=context)

    def _line_bounds(self, start_flange: np.ndarray, to_row: np.ndarray, q0c: np.ndarray,
                     frames: Placement) -> np.ndarray:
        """An upper bound of each segment's bow as a line (`path.line_deviation_bound`),
        inf where the robot does not carry the tool: a CAM program's short moves are
        settled by it without sampling."""
        robot, p = self.robot, self.plan_
        bound = line_deviation_bound(
            chain_span(robot.axis_points),
            wrist_levers(robot.axis_dirs, robot.axis_points, robot.home),
            start_flange, p.flange[to_row], frames.tool[:, :3, 3], p.q_cmd[to_row] - q0c)
        bound[frames.stationary] = np.inf
        return bound

    # ------------------------------------------------------------------ emission
    def _add_declaration(self, site: Site, slot: int, text: str) -> None:
        """Queue a declaration beside the robtarget it replaces, else in the motion's module."""
        motion = site.motion
        operand = site.targets[slot]
        decl = operand.declaration
        if (decl is not None and operand.form == "name" and decl.module == motion.module
                and (decl.routine is None or decl.routine.lower() == motion.routine.lower())):
            anchor: Any = id(decl)  # after the declaration
            local = decl.syntax.local
            target: Any = decl
            where = (decl.module, decl.routine)
        else:
            anchor = motion.module.lower()  # among the module's declarations
            local = False
            target = next(m for m in self.program.modules if m.name == motion.module)
            where = (motion.module, None)
        block = self.decl_blocks.get(anchor)
        if block is None:
            block = self.decl_blocks[anchor] = []
            self.decl_anchor_order.append((anchor, target))
        if local and not text.startswith("LOCAL"):
            text = "LOCAL " + text
        block.append(text)
        self.units.add_declaration(*where, text)

    def _replace_statement(self, site: Site, edits: list[tuple]) -> int:
        """Apply local edits to a motion instruction as one whole-statement edit; returns
        the id of its new text among the check units."""
        motion = site.motion
        text = statement_variant(self.program, motion, edits)
        if edits:
            self.editor.replace((motion.syntax.start, motion.syntax.end), text)
        return self.units.add_statement(motion.module, motion.routine, text)

    def _intermediates(self) -> dict[int, tuple[int, int]]:
        """Refined site -> (first, end) index of its intermediate points in the refinement."""
        inter: dict[int, tuple[int, int]] = {}
        if self.refinement is not None and self.refinement.seg.size:
            bounds = np.searchsorted(self.refinement.seg,
                                     np.arange(len(self.refined_sites) + 1))
            for k, site_index in enumerate(self.refined_sites):
                lo, hi = int(bounds[k]), int(bounds[k + 1])
                if hi > lo and self.mode.get(site_index) == "joint":
                    inter[site_index] = (lo, hi)
        return inter

    def emit(self) -> Expected:
        """All edits (whole statements and declarations); returns what verification must find."""
        t, p = self.targets, self.plan_
        joint_sites = [i for i in sorted(self.mode) if self.mode[i] == "joint"]
        filtered_sites = [i for i in sorted(self.mode) if self.mode[i] == "filtered"]
        inter = self._intermediates()
        segment_of = {site: k for k, site in enumerate(self.refined_sites)}
        # joint literals for all destinations and intermediate points at once
        dest_rows = np.array([self.sites[i].rows[-1] for i in joint_sites], dtype=int)
        inter_sites = [i for i in joint_sites if i in inter]
        r = self.refinement
        q_parts = [p.q_cmd[dest_rows]] + [r.q_cmd[slice(*inter[i])] for i in inter_sites]
        ext_parts = [t.extax[dest_rows]] + [
            np.repeat(t.extax[self.sites[i].rows[-1]][None], inter[i][1] - inter[i][0], 0)
            for i in inter_sites]
        literals = jointtarget_literals(np.degrees(np.concatenate(q_parts)),
                                        np.concatenate(ext_parts))
        dest_literal = literals[: len(joint_sites)]
        inter_start = len(joint_sites)
        self._filtered(filtered_sites)

        jt_names: dict[tuple[str, str], str] = {}
        allocate, add_declaration = self.names.allocate, self._add_declaration

        def jointtarget_name(stem: str, literal: str, site: Site) -> str:
            key = (stem.lower(), literal)
            name = jt_names.get(key)
            if name is None:
                name = jt_names[key] = allocate(stem, "jt_")
                add_declaration(site, len(site.targets) - 1,
                                jointtarget_declaration(name, literal))
            return name

        approach = {i: d for i, d in self.approach.items() if self.mode.get(i) == "joint"}
        approach_literal = {}
        if approach:
            keys = list(approach)
            rows = np.array([self.sites[i].rows[-1] for i in keys], dtype=int)
            start = p.q_cmd[rows] - np.array(list(approach.values())) * self.approach_margin
            approach_literal = dict(zip(keys, jointtarget_literals(np.degrees(start),
                                                                   t.extax[rows])))
        if not inter and not approach:
            self._emit_joints(joint_sites, dest_literal)
            self._flush_declarations()
            return self._expected()
        program_text = self.program.text
        starts: list[int] = []
        ends: list[int] = []
        statements: list[str] = []
        add_statement = self.units.add_statement
        for i, literal in zip(joint_sites, dest_literal):
            site = self.sites[i]
            motion = site.motion
            stem = _stem(site, len(site.targets) - 1)
            name = jointtarget_name(stem, literal, site)
            indent = _indent_before(self.program, motion.syntax.start)
            sep = "\n" + indent if indent is not None else " "
            drops = [(op.argument.start, op.argument.end, "")
                     for key, op in motion.optional.items() if key in INTERMEDIATE_DROPS]
            lines = []
            if i in inter:
                lo, hi = inter[i]
                zone = motion.zone
                zone_value = zone.argument.value if zone is not None else None
                zone_edit = ([(zone_value.start, zone_value.end, INTERMEDIATE_ZONE)]
                             if zone_value is not None else [])
                for j in range(hi - lo):
                    sub = jointtarget_name(f"{stem}_{j + 1}", literals[inter_start + j], site)
                    self.inserted.add(sub)
                    variant = statement_variant(
                        self.program, motion, joint_edits(site, sub) + drops + zone_edit)
                    lines.append(variant + sep)
                    ident = add_statement(motion.module, motion.routine, variant)
                    self.inter_checks.append((ident, segment_of[i], lo + j))
                inter_start += hi - lo
            if i in approach:  # stands still there (fine), then arrives from one side
                sub = jointtarget_name(f"{stem}_app", approach_literal[i], site)
                self.inserted.add(sub)
                lines.append(statement_variant(self.program, motion,
                                                joint_edits(site, sub) + drops) + sep)
            if lines:
                self.editor.insert(motion.syntax.start, "".join(lines))
            statement = joint_statement(program_text, site, name)
            starts.append(motion.syntax.start)
            ends.append(motion.syntax.end)
            statements.append(statement)
            ident = add_statement(motion.module, motion.routine, statement)
            self.checks.append((ident, 0, site.rows[-1]))
        self.editor.replace_many(starts, ends, statements)
        self._flush_declarations()
        return self._expected()

    def _emit_joints(self, joint_sites: list[int], literals: list[str]) -> None:
        """`emit`'s loop for moves without intermediate points (a CAM program), in phases
        over all moves: the same names, declarations and statements."""
        sites = [self.sites[i] for i in joint_sites]
        stems = [_stem(site, len(site.targets) - 1) for site in sites]
        keys = list(zip(map(str.lower, stems), literals))
        first: dict[tuple[str, str], int] = {}
        for n, key in enumerate(keys):
            first.setdefault(key, n)
        order = list(first.values())
        names = self.names.allocate_many([stems[n] for n in order], "jt_")
        name_of = dict(zip(first, names))
        add_declaration = self._add_declaration
        for n, name in zip(order, names):
            site = sites[n]
            add_declaration(site, len(site.targets) - 1,
                            jointtarget_declaration(name, literals[n]))
        text = self.program.text
        statements = [joint_statement(text, site, name_of[key])
                      for site, key in zip(sites, keys)]
        self.editor.replace_many([site.motion.syntax.start for site in sites],
                                 [site.motion.syntax.end for site in sites], statements)
        add_statement, checks = self.units.add_statement, self.checks
        for site, statement in zip(sites, statements):
            motion = site.motion
            checks.append((add_statement(motion.module, motion.routine, statement), 0,
                           site.rows[-1]))

    def _filtered(self, filtered_sites: list[int]) -> None:
        """Filtered robtargets: in the declaration when only compensated moves use it,
        inline in place of an aggregate, else as a new CONST robtarget."""
        if not filtered_sites:
            return
        t, p = self.targets, self.plan_
        rows_all = [r for i in filtered_sites for r in self.sites[i].rows]
        rows_a = np.array(rows_all, dtype=int)
        tcp = t.placement.take(rows_a).tcp(self.robot.fk(p.q_cmd[rows_a]))
        conf = self.robot.confdata(p.q_cmd[rows_a])
        f_literal = dict(zip(rows_all, robtarget_literals(tcp, conf, t.extax[rows_a])))
        by_decl: dict[int, list[int]] = {}
        for row in rows_all:
            op = t.operand[row]
            if op.form == "name" and op.declaration is not None:
                by_decl.setdefault(id(op.declaration), []).append(row)
        uses = identifier_counts(self.program.text)
        replaced: set[int] = set()
        for rows in by_decl.values():
            decl = t.operand[rows[0]].declaration
            literals = {f_literal[r] for r in rows}
            only_here = uses.get(decl.key, 0) == 1 + len(rows)
            if len(literals) == 1 and only_here and decl.value_span is not None:
                replaced.add(id(decl))
                text = self.program.text
                new = (text[decl.span.start:decl.value_span.start] + literals.pop()
                       + text[decl.value_span.end:decl.span.end])
                self.editor.replace(decl.span, new)
                self.units.add_declaration(decl.module, decl.routine, new)
        names: dict[tuple[str, str], str] = {}
        for i in filtered_sites:
            site = self.sites[i]
            edits: list[tuple] = []
            for slot, row in enumerate(site.rows):
                op = t.operand[row]
                literal = f_literal[row]
                if op.form == "name" and op.declaration is not None \
                        and id(op.declaration) in replaced:
                    continue
                if op.form == "inline":
                    edits.append((op.value_span.start, op.value_span.end, literal))
                    continue
                key = (_stem(site, slot).lower(), literal)
                name = names.get(key)
                if name is None:
                    name = names[key] = self.names.allocate(_stem(site, slot), "ft_")
                    self._add_declaration(site, slot, format_declaration(
                        "CONST", "robtarget", name, literal))
                edits.append((op.value_span.start, op.value_span.end, name))
            ident = self._replace_statement(site, edits)
            self.checks.extend((ident, slot, row) for slot, row in enumerate(site.rows))

    def _flush_declarations(self) -> None:
        """Insert the queued declarations, in the order their anchors were first used
        (runs of declarations after declarations go in as one batch)."""
        after: list[tuple[int, int]] = []
        after_texts: list[str] = []
        for anchor, target in self.decl_anchor_order:
            text = "\n".join(self.decl_blocks[anchor])
            if type(anchor) is int:
                after.append((target.syntax.start, target.syntax.end))
                after_texts.append(text)
            else:
                self.editor.insert_lines_after(after, after_texts)
                after, after_texts = [], []
                self.editor.insert_declaration(target, text)
        self.editor.insert_lines_after(after, after_texts)

    def _expected(self) -> Expected:
        """Each compensated pose: the check statement and slot it is read from, its
        intended TCP, frames and the conditions it runs in."""
        t = self.targets
        ids, slots, rows = np.array(self.checks, dtype=int).reshape(-1, 3).T
        placement = t.placement.take(rows)
        tcp, context = t.pose[rows], self.plan_.context.take(rows)
        if self.inter_checks:
            inter_ids, seg, index = np.array(self.inter_checks, dtype=int).T
            frames = self.seg_frames.take(seg)
            placement = Placement(*(np.concatenate([a, b]) for a, b in (
                (placement.tool, frames.tool), (placement.wobj, frames.wobj),
                (placement.stationary, frames.stationary))))
            ids = np.concatenate([ids, inter_ids])
            slots = np.concatenate([slots, np.zeros(len(seg), int)])
            tcp = np.concatenate([tcp, self.refinement.pose[index]])
            inter = self.seg_context.take(seg)
            if self.inter_direction is not None:
                inter = replace(inter, last_direction=self.inter_direction[index])
            context = Context.concatenate(context, inter)
        return Expected(ids, slots, tcp, placement, context)


def _run_statement(job: _Rewriter, options: RewriteOptions
                   ) -> tuple[list[str], list[str], dict[str, str]]:
    """(notes, warnings, header record) of how the program's run was taken: what the
    model's effects read, where the program tells it, and what had to be assumed."""
    needs = job.model.context_fields()
    cond = job.conditions
    notes: list[str] = []
    warnings: list[str] = []
    record: dict[str, str] = {}
    ok = job.plan_.ok
    if "payload_kg" in needs:
        grips = cond.grip_statements
        record["payload"] = "tool_loads+GripLoad" if grips else "tool_loads"
        notes.append("payload: each move's tool load (or \\TLoad)"
                     + (f" plus the gripped load of {grips} GripLoad statement(s), "
                        "followed in the order the moves execute" if grips else
                        "; the program sets no GripLoad"))
        if cond.grip_unknown:
            record["payload_unknown_moves"] = str(cond.grip_unknown)
            warnings.append(
                f"the gripped load of {cond.grip_unknown} move(s) is not known before run "
                "time (a GripLoad on only some paths to them, or a routine this program "
                "does not call): no gripped load assumed there")
    if "last_direction" in needs:
        direction = job.plan_.context.last_direction
        unknown = 0 if direction is None else int(
            np.count_nonzero((direction[ok] == 0).any(axis=1)))
        record["direction"] = "move_order"
        record["direction_unknown_moves"] = str(unknown)
        notes.append("motion direction: from the order the moves execute in"
                     + (f"; {unknown} move(s) start where the program cannot say before run "
                        "time (first move of a routine, loop or branch): taken midway "
                        "between the directions" if unknown else ""))
    if options.approach:
        inserted = len(job.approach)
        record["approach_points"] = str(inserted)
        if not inserted:
            notes.append("approach points: none inserted, since "
                         + ("no joint of the model has play (backlash)" if not np.any(
                             job.model.play() > 0) else "no compensated MoveJ ends at a "
                            "fine point"))
    free = cond.config_free & ok
    if free.any():
        other = int(np.count_nonzero(np.any(
            job.robot.confdata(job.plan_.q_ideal[free]) != job.targets.conf[free], axis=1)))
        record["configuration"] = "nearest_where_monitoring_off"
        record["config_free_moves"] = str(int(np.count_nonzero(free)))
        notes.append(f"configuration: {int(np.count_nonzero(free))} move(s) run with "
                     "configuration monitoring off (ConfL/ConfJ \\Off), so the controller "
                     "takes the configuration nearest the one it is in: compensated on that "
                     f"one, which differs from the confdata written for {other} of them")
    if options.temperature_c is not None and "temp_c" not in needs:
        notes.append(f"--temperature {options.temperature_c:g} °C: no effect of the model "
                     "depends on the cell temperature, so it changes nothing (recorded only)")
    for eff in job.model.robot_effects:
        fields = eff.context_fields()
        reference = getattr(eff, "reference", None)
        if "temp_c" in fields:
            if options.temperature_c is None:
                assumed = f"{reference:g} °C" if reference is not None else "its reference"
                record["temperature_c"] = (f"assumed_{reference:g}" if reference is not None
                                           else "assumed_reference")
                warnings.append(
                    f"the model's {eff.name} depends on the cell temperature and no "
                    f"--temperature was given: assumed the calibration's {assumed}")
            else:
                record["temperature_c"] = f"{options.temperature_c:g}"
        if "time_s" in fields:
            record["time_s"] = "assumed_reference"
            warnings.append(
                f"the model's {eff.name} depends on the time since the robot started, which "
                "a program cannot know: taken at the calibration's reference time")
    return notes, warnings, record


def _predicted_before(job: _Rewriter) -> tuple[float, float] | None:
    """The model's TCP error (mean, max, mm) of the compensated targets as the original
    program commands them (the ideal joints), in the conditions they run in."""
    p, t = job.plan_, job.targets
    rows = np.flatnonzero(p.ok)
    if rows.size == 0:
        return None
    flange = job.model.actual_flange(job.robot, p.q_ideal[rows], p.context.take(rows))
    tcp = t.placement.take(rows).tcp(flange)
    err = np.linalg.norm(tcp[:, :3, 3] - t.pose[rows, :3, 3], axis=1)
    return float(err.mean()), float(err.max())


def _module_indent(program: Program) -> str:
    """Indentation of the first item of the first module (for the header lines)."""
    module = program.modules[0]
    items = module.syntax.items
    if items:
        indent = _indent_before(program, items[0].start)
        if indent:
            return indent
    return "  "


def _strip_old_header(editor: Editor, text: str) -> None:
    """Remove the header lines of an earlier compensation (with --force)."""
    import re

    for match in re.finditer(r"\r?\n[ \t]*![ \t]*" + MARK + r"[^\r\n]*", text):
        editor.replace((match.start(), match.end()), "")


# ---------------------------------------------------------------------------- API
def rewrite_source(
    data: bytes, filename: str, comp: Compensator, options: RewriteOptions
) -> RewriteResult:
    """Compensate one program given as bytes; returns the new bytes and what was done."""
    with cyclic_gc_paused():
        return _rewrite(data, filename, comp, options)


def _rewrite(data: bytes, filename: str, comp: Compensator, options: RewriteOptions
             ) -> RewriteResult:
    program = parse_program(data, filename)
    old = read_header(program.text)
    if old is not None and not options.force:
        raise RapidSemanticError(
            f"already compensated by rapidfix {old.version} (model {old.model_path})",
            file=filename,
            hint="use --force to compensate it again",
        )
    job = _Rewriter(program, comp, options)
    job.plan()
    job.paths()
    expected = job.emit()
    for site in job.sites:
        if site.reason is not None:
            job.skipped.append(Skipped(site.where, site.label, site.reason))
    compensated = len(job.mode)
    filtered_sites = [i for i, m in job.mode.items()
                      if m == "filtered" and options.emit == "jointtargets"]
    filtered = len(filtered_sites)
    filtered_reasons: dict[str, int] = {}
    for i in filtered_sites:
        reason = job.filtered_reason.get(i, START_UNKNOWN)
        filtered_reasons[reason] = filtered_reasons.get(reason, 0) + 1
    points = 0
    worst_path = None
    if job.refinement is not None:
        keep = np.array([job.mode.get(i) == "joint" for i in job.refined_sites], dtype=bool)
        points = int(np.isin(job.refinement.seg, np.flatnonzero(keep)).sum())
        if keep.any():
            worst_path = float(job.refinement.deviation[keep].max())
    summary = (f"{compensated} of {len(job.sites)} moves compensated, {points} points added, "
               f"{len(job.skipped)} left as they were")
    notes, warnings, conditions = _run_statement(job, options)
    header = Header(
        version=__version__,
        model_path=comp.model_path,
        model_sha256=comp.model_sha256,
        input_sha256=sha256_bytes(data),
        options=header_options(options, comp),
        summary=summary,
        conditions=conditions,
    )
    if compensated:  # the header says "compensated": never on a file where nothing is
        if old is not None:
            _strip_old_header(job.editor, program.text)
        job.editor.insert(program.modules[0].header_end, header.render(
            _module_indent(program), "\n"))
        job.units.comments.extend(header.lines())
    output = job.editor.render()
    read = read_back(job.units, filename, expected)
    deviation = predicted_deviation(comp.model, comp.robot, read, expected, filename)
    worst = float(deviation.max()) if deviation.size else None
    return RewriteResult(
        filename=filename,
        data=output,
        moves_total=len(job.sites),
        moves_compensated=compensated,
        moves_filtered=filtered,
        points_added=points,
        skipped=job.skipped,
        worst_predicted_mm=worst,
        worst_path_mm=worst_path,
        header=header,
        inserted=job.inserted,
        notes=notes,
        warnings=warnings,
        predicted_before_mm=_predicted_before(job),
        filtered_reasons=filtered_reasons,
    )


def backup_path(path: Path) -> Path:
    """A free backup name beside `path`: PROG.mod.bak, PROG.mod.bak2, …"""
    candidate = path.with_name(path.name + ".bak")
    n = 1
    while candidate.exists():
        n += 1
        candidate = path.with_name(f"{path.name}.bak{n}")
    return candidate


def rewrite_file(
    source: str | Path,
    target: str | Path,
    comp: Compensator,
    options: RewriteOptions,
    *,
    in_place: bool = False,
    name: str | None = None,
) -> RewriteResult:
    """Rewrite `source` into `target` atomically; the input is only replaced with in_place
    (a backup is written first). With strict options and skipped targets nothing is written.
    `name` is how messages call the file (default: the source path)."""
    source, target = Path(source), Path(target)
    same = target.exists() and source.exists() and target.resolve() == source.resolve()
    if same and not in_place:
        raise OutputExistsError("the output would overwrite the input", file=target,
                                hint="choose another -o, or use --in-place (keeps a backup)")
    data = source.read_bytes()
    result = rewrite_source(data, name or str(source), comp, options)
    if result.skipped and options.strict:
        return result
    if in_place:
        backup = backup_path(source)
        write_bytes_atomic(backup, data)
        result.backup = str(backup)
        target = source
    write_bytes_atomic(target, result.data)
    result.written = True
    result.output = str(target)
    return result


__all__ = [
    "RewriteOptions",
    "RewriteResult",
    "Skipped",
    "backup_path",
    "header_options",
    "rewrite_file",
    "rewrite_source",
]
