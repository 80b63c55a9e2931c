"""Rewrite one RAPID program with compensated targets: the post-processor's main job.

This module holds the options, the result and its report, the header and the file
I/O, and runs the steps, each vectorised over all targets of the file:
1. parse; refuse a program rapidfix already compensated (unless forced);
2. plan (`planning.plan_program` -> `ProgramPlan`): resolve every motion target with
   its tool and work object, the program's run conditions, inverse kinematics on the
   confdata branch and compensation, approach points, each move's emission mode;
3. path refinement (`refinement.refine_paths` -> `PathRefinement`): for linear and
   circular moves that become MoveAbsJ, intermediate points until the
   joint-interpolated path stays within the tolerance;
4. emission (`emission.emit_edits` -> `Emission`): span edits, CONST jointtargets and
   MoveAbsJ (or filtered robtargets); here a header comment is added. Every other
   byte stays as it was. Each edit replaces or inserts whole statements and
   declarations, which are also collected as `CheckUnits`;
5. parse the output again — its new units, which is the same check as
   parsing all of it (`reparse_changes`) — and push what it commands through the
   model (`verify`): the predicted worst-case TCP deviation.

A MoveL or MoveC whose start is not known before run time (the first move of
a routine, a loop body or an IF branch) keeps its instruction and gets a
filtered robtarget instead, so its path stays the controller's line or arc.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from rapidfix import __version__, chunks
from rapidfix.atomic import write_bytes_atomic
from rapidfix.digest import sha256_bytes
from rapidfix.error_model import compiled_sums
from rapidfix.exceptions import (
    InvalidOption,
    OutputExistsError,
    RapidSemanticError,
)
from rapidfix.gc_pause import cyclic_gc_paused
from rapidfix.kinematics import compiled_forward, numpy_closed_form
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.emission import emit_edits, indent_before
from rapidfix.postprocess.header import MARK, Header, read_header
from rapidfix.postprocess.path import MIN_PATH_TOLERANCE_MM
from rapidfix.postprocess.plan import Plan
from rapidfix.postprocess.planning import ProgramPlan, plan_program
from rapidfix.postprocess.refinement import START_UNKNOWN, PathRefinement, refine_paths
from rapidfix.postprocess.resolve import Declarations, Targets
from rapidfix.postprocess.verify import predicted_deviation, read_back
from rapidfix.rapid import Editor, Program, foreign_target_calls, parse_owned

EMIT_CHOICES = ("jointtargets", "robtargets")
#: programs of this much kernel work or more are solved with the compiled kernels (numba):
#: their moves, an arc counting four (see `kernel_work`)
COMPILED_FROM_WORK = 20_000


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
    #: the external axes carry neither the robot nor the work (a servo gun, a positioner
    #: whose work objects are not coordinated): a target's external axis values do not
    #: move it. Else a target with one standing anywhere but 0 is left as it was
    static_external_axes: bool = False

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
    if options.static_external_axes:
        recorded["external_axes"] = "static"
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
            kept = "1 move kept its" if count == 1 else f"{count} moves kept their"
            lines.append(f"  {kept} instruction with a filtered robtarget ({reason})")
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


def _run_statement(comp: Compensator, planned: ProgramPlan, solved: Plan,
                   options: RewriteOptions) -> tuple[list[str], list[str], dict[str, str]]:
    """(notes, warnings, header record) of how the program's run was taken: what the
    model's effects read, where the program tells it, and what had to be assumed.
    `solved` is the targets' plan after path refinement."""
    model, robot = comp.model, comp.robot
    needs = model.context_fields()
    cond = planned.conditions
    notes: list[str] = []
    warnings: list[str] = []
    record: dict[str, str] = {}
    ok = solved.ok
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
        direction = solved.context.last_direction
        unknown = 0 if direction is None else int(
            np.count_nonzero((direction[ok] == 0).any(axis=1)))
        record["direction"] = "move_order"
        record["direction_unknown_moves"] = str(unknown)
        notes.append("motion direction: from the order the moves execute in"
                     + (f"; {unknown} move(s) start where the program cannot say before run "
                        "time (first move of a routine, loop or branch): taken midway "
                        "between the directions" if unknown else ""))
    if options.approach:
        inserted = len(planned.approach)
        record["approach_points"] = str(inserted)
        if not inserted:
            notes.append("approach points: none inserted, since "
                         + ("no joint of the model has play (backlash)" if not np.any(
                             model.play() > 0) else "no compensated MoveJ ends at a "
                            "fine point"))
    displaced = 0
    if cond.displaced.any():
        compensated = np.fromiter((site.reason is None for site in planned.sites), dtype=bool,
                                  count=len(planned.sites))
        displaced = int(np.count_nonzero(cond.displaced & compensated))
    if displaced:
        record["displaced_moves"] = str(displaced)
        warnings.append(
            f"{displaced} move(s) may run with a program displacement (PDispOn/PDispSet), "
            "known only at run time: they keep their instruction, their robtargets "
            "compensated where they stand undisplaced")
    free = cond.config_free & ok
    if free.any():
        other = int(np.count_nonzero(np.any(
            robot.confdata(solved.q_ideal[free]) != planned.targets.conf[free], axis=1)))
        record["configuration"] = "nearest_where_monitoring_off"
        record["config_free_moves"] = str(int(np.count_nonzero(free)))
        notes.append(f"configuration: {int(np.count_nonzero(free))} move(s) run with "
                     "configuration monitoring off (ConfL/ConfJ \\Off), so the controller "
                     "takes the configuration nearest the one it is in: compensated on that "
                     f"one, which differs from the confdata written for {other} of them")
    if options.temperature_c is not None and "temp_c" not in needs:
        notes.append(f"RewriteOptions.temperature_c {options.temperature_c:g} °C: no effect of "
                     "the model depends on the cell temperature, so it changes nothing "
                     "(recorded only)")
    for eff in model.robot_effects:
        fields = eff.context_fields()
        reference = getattr(eff, "reference", None)
        if "temp_c" in fields:
            if options.temperature_c is None:
                assumed = f"{reference:g} °C" if reference is not None else "its reference"
                record["temperature_c"] = (f"assumed_{reference:g}" if reference is not None
                                           else "assumed_reference")
                warnings.append(
                    f"the model's {eff.name} depends on the cell temperature and no "
                    f"RewriteOptions.temperature_c was given: assumed the calibration's {assumed}")
            else:
                record["temperature_c"] = f"{options.temperature_c:g}"
        if "time_s" in fields:
            record["time_s"] = "assumed_reference"
            warnings.append(
                f"the model's {eff.name} depends on the time since the robot started, which "
                "a program cannot know: taken at the calibration's reference time")
    return notes, warnings, record


def _foreign_call_warnings(program: Program) -> list[str]:
    """One warning per procedure that is not a motion instruction rapidfix knows nor a
    routine of the program, yet is passed targets: they are left as written."""
    by_name: dict[str, list] = {}
    for call in foreign_target_calls(program):
        by_name.setdefault(call.name.lower(), []).append(call)
    warnings = []
    for calls in by_name.values():
        first = program.span(calls[0].start, calls[0].start).location
        names = list(dict.fromkeys(t if len(t) <= 40 else t[:36] + " ..."
                                   for call in calls for t in call.targets))
        shown = ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")
        more = f" ({len(calls)} calls)" if len(calls) > 1 else ""
        warnings.append(
            f"{first}: {calls[0].name}{more} is not a motion instruction rapidfix knows nor a "
            f"routine of this program: the targets passed to it ({shown}) are left as "
            "written; if it moves the robot to them, those moves are not compensated")
    return warnings


def _declared_twice_warnings(program: Program, outside: Declarations) -> list[str]:
    """One warning naming the program's global data that a module read for its data
    (its task's other modules, the declaration files) declares too."""
    twice = outside.declared_twice(program)
    if not twice:
        return []
    shown = ", ".join(twice[:3]) + (f" and {len(twice) - 3} more" if len(twice) > 3 else "")
    return [f"{program.filename}: {len(twice)} name(s) this program declares are declared "
            f"by a module read for its data too: {shown}; the controller does not load a "
            "task with a global name declared twice (this program's own declarations were "
            "used)"]


def _predicted_before(comp: Compensator, targets: Targets, p: Plan
                      ) -> tuple[float, float] | None:
    """The model's TCP error (mean, max, mm) of the compensated targets as the original
    program commands them (the ideal joints), in the conditions they run in; in chunks
    of `chunks.PREDICTED_BEFORE` targets, as this comes at the rewrite's peak."""
    t = targets
    rows = np.flatnonzero(p.ok)
    if rows.size == 0:
        return None
    err = np.empty(rows.size)
    step = chunks.PREDICTED_BEFORE
    for at in range(0, rows.size, step):
        part = rows[at:at + step]
        flange = comp.model.actual_flange(comp.robot, p.q_ideal[part], p.context.take(part))
        tcp = t.placement.take(part).tcp_positions(flange)
        err[at:at + step] = np.linalg.norm(tcp - t.pose[part, :3, 3], axis=1)
    return float(err.mean()), float(err.max())


def _after_path_check(planned: ProgramPlan, refined: PathRefinement
                      ) -> tuple[ProgramPlan, PathRefinement]:
    """The plans without what only the path check reads: the intended flange poses
    (N,4,4) and the plan's emission modes (the refinement has its own). A million-line
    program's would otherwise stay through the emission, the rewrite's peak (about
    200 bytes a target)."""
    none = np.empty((0, 4, 4))
    solved = replace(planned.solved, flange=none)
    after = solved if refined.solved is planned.solved else replace(refined.solved,
                                                                     flange=none)
    return replace(planned, solved=solved, mode={}), replace(refined, solved=after)


def _module_indent(program: Program) -> str:
    """Indentation of the first item of the first module (for the header lines)."""
    module = program.modules[0]
    items = module.syntax.items
    if items:
        indent = indent_before(program, items[0].start)
        if indent:
            return indent
    return "  "


def _strip_old_header(editor: Editor, text: str) -> None:
    """Remove the header lines of an earlier compensation (RewriteOptions(force=True))."""
    for match in re.finditer(r"\r?\n[ \t]*![ \t]*" + MARK + r"[^\r\n]*", text):
        editor.replace((match.start(), match.end()), "")


# ---------------------------------------------------------------------------- API
#: the steps a rewrite reports to its `progress` callback, in order (`rewrite_file` reports
#: the last)
REWRITE_STEPS = ("reading the program", "planning", "checking the paths", "writing the edits",
                 "reading the output back", "writing the file")


def _no_progress(_step: str) -> None:
    pass


def rewrite_source(
    data: bytes, filename: str, comp: Compensator, options: RewriteOptions,
    progress: Callable[[str], None] | None = None,
) -> RewriteResult:
    """Compensate one program given as bytes; returns the new bytes and what was done.
    `progress` is called with each of the first five `REWRITE_STEPS` as it starts."""
    return _rewrite_owned([data], filename, comp, options, progress)


def _rewrite_owned(handed: list[bytes], filename: str, comp: Compensator,
                   options: RewriteOptions,
                   progress: Callable[[str], None] | None = None) -> RewriteResult:
    """`rewrite_source` of the bytes `handed` holds, taken out of it: when the caller
    keeps no other reference, a large file's bytes are let go of once decoded."""
    step = progress or _no_progress
    with cyclic_gc_paused():
        step(REWRITE_STEPS[0])
        digest = sha256_bytes(handed[0])
        program = parse_owned(handed, filename)
        work = kernel_work(program)
        # _rewrite holds the only reference, so the program model is freed where it lets
        # it go (before the read-back), not after the collector is back on: then its
        # first collection would walk every object of the model once more
        models = [program]
        del program
        with _kernels_for(work):
            return _rewrite(models, digest, filename, comp, options, step)


def kernel_work(program: Program) -> int:
    """How much of the compiled kernels' work a program makes: one per move, four per
    arc (its circle point, and the points its path check samples and inserts)."""
    motions = program.motions
    return len(motions) + 3 * sum(1 for motion in motions if len(motion.targets) == 2)


@contextmanager
def _kernels_for(work: int) -> Iterator[None]:
    """The compiled kernels (IK, forward kinematics, RBF sums) for a program of at least
    COMPILED_FROM_WORK of `kernel_work`, numpy's below: their one-time load (numba and
    its registries, `compiled._numba_ready`: about 0.3 s of CPU, 100 MB) costs more than
    they save, about 10 µs a move, on a smaller program. Chosen by the program alone, so
    the same program gives the same bytes whatever a process (a batch worker) rewrote
    before."""
    with ExitStack() as stack:
        if work >= COMPILED_FROM_WORK:
            stack.enter_context(compiled_sums())
            stack.enter_context(compiled_forward())
        else:
            stack.enter_context(numpy_closed_form())
        yield


def _rewrite(handed: list[Program], digest: str, filename: str, comp: Compensator,
             options: RewriteOptions, step: Callable[[str], None] = _no_progress
             ) -> RewriteResult:
    """The steps after parsing; `handed` holds the program model, taken out here;
    `digest` is the input's SHA-256."""
    program = handed.pop()
    old = read_header(program.text)
    if old is not None and not options.force:
        raise RapidSemanticError(
            f"already compensated by rapidfix {old.version} (model {old.model_path})",
            file=filename,
            hint="use RewriteOptions(force=True) to compensate it again",
        )
    step(REWRITE_STEPS[1])
    planned = plan_program(program, comp, options.emit,
                           temperature_c=options.temperature_c, approach=options.approach,
                           static_external_axes=options.static_external_axes)
    step(REWRITE_STEPS[2])
    refined = refine_paths(program, comp.model, comp.robot, planned,
                           options.path_tolerance_mm, options.emit)
    planned, refined = _after_path_check(planned, refined)
    step(REWRITE_STEPS[3])
    emission = emit_edits(program, comp, planned, refined)
    skipped = [Skipped(site.where, site.label, site.reason)
               for site in planned.sites if site.reason is not None]
    mode = refined.mode
    compensated = len(mode)
    filtered_sites = [i for i, m in mode.items()
                      if m == "filtered" and options.emit == "jointtargets"]
    filtered = len(filtered_sites)
    filtered_reasons: dict[str, int] = {}
    for i in filtered_sites:
        reason = refined.filtered_reason.get(i, START_UNKNOWN)
        filtered_reasons[reason] = filtered_reasons.get(reason, 0) + 1
    points = refined.points_added()
    worst_path = refined.worst_path_mm()
    summary = (f"{compensated} of {len(planned.sites)} moves compensated, {points} points "
               f"added, {len(skipped)} left as they were")
    notes, warnings, conditions = _run_statement(comp, planned, refined.solved, options)
    warnings.extend(_foreign_call_warnings(program))
    warnings.extend(_declared_twice_warnings(program, planned.outside))
    header = Header(
        version=__version__,
        model_path=comp.model_path,
        model_sha256=comp.model_sha256,
        input_sha256=digest,
        options=header_options(options, comp),
        summary=summary,
        conditions=conditions,
    )
    editor, units, expected = emission.editor, emission.units, emission.expected
    if compensated:  # the header says "compensated": never on a file where nothing is
        if old is not None:
            _strip_old_header(editor, program.text)
        at = program.modules[0].header_end
        block = header.render(_module_indent(program), "\n")
        # the block is line comments: what follows on the MODULE line (code, or a comment
        # the header would take in) goes on a line of its own, after the header and any
        # declarations inserted there
        editor.insert_lines_first(at, block)
        units.comments.extend(header.lines())
    moves_total, inserted = len(planned.sites), emission.inserted
    before = _predicted_before(comp, planned.targets, refined.solved)
    # the program model and the plan are done with: the output is rendered, and the
    # read-back parses, in the memory they held (a million-line program's peaks would
    # otherwise add up); the editor keeps only the source text and the edits
    editor.release_program()
    del program, planned, refined, emission
    output = editor.render()
    del editor
    step(REWRITE_STEPS[4])
    read = read_back(units, filename, expected)
    deviation = predicted_deviation(comp.model, comp.robot, read, expected, filename)
    worst = float(deviation.max()) if deviation.size else None
    return RewriteResult(
        filename=filename,
        data=output,
        moves_total=moves_total,
        moves_compensated=compensated,
        moves_filtered=filtered,
        points_added=points,
        skipped=skipped,
        worst_predicted_mm=worst,
        worst_path_mm=worst_path,
        header=header,
        inserted=inserted,
        notes=notes,
        warnings=warnings,
        predicted_before_mm=before,
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
    progress: Callable[[str], None] | None = None,
) -> RewriteResult:
    """Rewrite `source` into `target` atomically; the input is only replaced with in_place
    (a backup is written first). With strict options and skipped targets nothing is written.
    `name` is how messages call the file (default: the source path); `progress` is called
    with each of `REWRITE_STEPS` as it starts."""
    source, target = Path(source), Path(target)
    same = target.exists() and source.exists() and target.resolve() == source.resolve()
    if same and not in_place:
        raise OutputExistsError(
            "the output would overwrite the input", file=target,
            hint="choose another target, or pass in_place=True (keeps a backup)")
    # the bytes are kept only for an in-place rewrite's backup; else they are let go of
    # once decoded (a large file is not held twice while its model is built and used)
    handed = [source.read_bytes()]
    data = handed[0] if in_place else None
    result = _rewrite_owned(handed, name or str(source), comp, options, progress)
    if result.skipped and options.strict:
        return result
    (progress or _no_progress)(REWRITE_STEPS[5])
    if data is not None:
        backup = backup_path(source)
        write_bytes_atomic(backup, data)
        result.backup = str(backup)
        target = source
    write_bytes_atomic(target, result.data)
    result.written = True
    result.output = str(target)
    return result


__all__ = [
    "REWRITE_STEPS",
    "RewriteOptions",
    "RewriteResult",
    "Skipped",
    "backup_path",
    "header_options",
    "rewrite_file",
    "rewrite_source",
]
