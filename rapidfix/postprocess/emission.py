"""Emission of a rewrite: from the plan and the refined paths to text edits.

Every compensated move becomes whole-statement edits: a MoveAbsJ to a new CONST
jointtarget (with its intermediate and approach points before it), or its own
instruction with a filtered robtarget (in its declaration when only compensated
moves use it, inline in place of an aggregate, else a new CONST). The written-out
forms are those of `emission_forms`. `emit_edits` returns the edits (an `Editor` not
yet rendered), the new units to check and what verification must read back from them;
it reads and writes no file.
"""

from __future__ import annotations

import re
from bisect import bisect_right
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from itertools import groupby
from typing import Any

import numpy as np

from rapidfix import chunks
from rapidfix.error_model import Context
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.emission_forms import (
    joint_edits,
    joint_statement,
    jointtarget_declaration,
    jointtarget_literals,
    robtarget_declaration,
    robtarget_literals,
    statement_variant,
)
from rapidfix.postprocess.naming import NameAllocator, count_identifiers
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.planning import ProgramPlan
from rapidfix.postprocess.refinement import PathRefinement
from rapidfix.postprocess.reparse_changes import SHAPE_TARGET, CheckUnits, JointSlot, TargetSlot
from rapidfix.postprocess.resolve import Site
from rapidfix.postprocess.verify import Expected
from rapidfix.rapid import Editor, MotionInstruction, Operand, Program, format_declaration

#: optional arguments left off the intermediate and approach points of a move: what belongs
#: to its end point (`\\T`, `\\Z`, `\\Inpos`), and `\\Conc` (the points fly by, so the
#: program runs ahead of them anyway, and a controller takes at most five concurrent moves
#: in succession)
INTERMEDIATE_DROPS = frozenset({"inpos", "z", "t", "conc"})
INTERMEDIATE_ZONE = "z0"
# where a name goes in a statement made once for several names (a program text with a
# NUL, which the reader refuses in a file, takes the statements one by one)
_NAME_MARK = "\x00"


@dataclass(frozen=True)
class Emission:
    """The edits of a rewrite and what to check of them.

    `editor` holds the edits (whole statements and declarations; more may be added, such
    as the header, before it renders); `units` the new statements and declarations as
    check units; `expected` what verification must read back from them; `inserted` the
    names of the intermediate and approach points' jointtargets.
    """

    editor: Editor
    units: CheckUnits
    expected: Expected
    inserted: set[str]


def emit_edits(program: Program, comp: Compensator, planned: ProgramPlan,
               refined: PathRefinement) -> Emission:
    """All edits of the compensated moves (see the module docstring)."""
    emitter = _Emitter(program, comp, planned, refined)
    expected = emitter.emit()
    return Emission(emitter.editor, emitter.units, expected, emitter.inserted)


def _stem(site: Site, slot: int) -> str:
    """The start of a new data name for a target: the robtarget's own name where it has
    one, else the instruction and its line."""
    motion = site.motion
    operand = site.targets[slot]
    if operand.form == "name" and operand.name:
        return operand.name
    if operand.form in ("offs", "reltool") and operand.name:
        return f"{operand.name}_{operand.form}"
    return f"{motion.name}_L{motion.span.line}"


_BLANKS = re.compile(r"\s*")  # what str.strip() takes


def indent_before(program: Program, offset: int) -> str | None:
    """Whitespace between the line start and offset, or None if text precedes it."""
    source = program.source
    # (a match of the blanks, not a slice: a line may hold the whole program)
    blank = _BLANKS.fullmatch(source.text, source.line_start(offset), offset)
    return blank.group() if blank is not None else None


def _target_slot(text: str, syntax: Any, spans: list[Any], targets: list[str], statement: str,
                 keep: Callable[[str, str], str]) -> TargetSlot | None:
    """The TargetSlot of a statement (`syntax` in `text`) whose targets stand at `spans`,
    written now as `targets`; None when they do not stand in that order or the slot does
    not give `statement` back (the read-back then parses the statement)."""
    parts: list[str] = []
    at = syntax.start
    for span, target in zip(spans, targets):
        if span.start < at:
            return None
        parts += [keep(text[at:span.start], text[at:span.start]), target]
        at = span.end
    parts.append(keep(text[at:syntax.end], text[at:syntax.end]))
    return tuple(parts) if "".join(parts) == statement else None


def _interleave(counts: np.ndarray, before: bool
                ) -> tuple[list[int], list[int], list[int], list[int]]:
    """Where n items and their extras stand in one list, item j with `counts[j]`
    extras right after it (or right `before` it): (the items' places, the extras'
    places in order, the list as indices into the items followed by all extras, and
    the item each place belongs to)."""
    n = len(counts)
    per = counts + 1
    starts = np.cumsum(per) - per
    items = starts + counts if before else starts
    total = int(per.sum())
    extras = (np.repeat((starts if before else starts + 1) - (np.cumsum(counts) - counts),
                        counts) + np.arange(total - n))
    order = np.empty(total, dtype=np.int64)
    order[items] = np.arange(n)
    order[extras] = np.arange(n, total)
    return (items.tolist(), extras.tolist(), order.tolist(),
            np.repeat(np.arange(n), per).tolist())


def _intermediate_edits(motion: MotionInstruction, zone: bool = True) -> list[tuple]:
    """The edits of a statement to a point inserted before `motion`: the optional
    arguments it drops (INTERMEDIATE_DROPS; one before the target up to the argument
    after it, with its comma: `MoveL \\Conc, p1` -> `MoveAbsJ jt_p1_1`) and, with `zone`,
    its zone made INTERMEDIATE_ZONE."""
    dropped = [op.argument for key, op in motion.optional.items()
               if key in INTERMEDIATE_DROPS]
    edits = []
    if dropped:
        first = motion.targets[0].argument.start if motion.targets else motion.syntax.end
        starts = [arg.start for arg in motion.syntax.args]  # (in the text's order)
        text = motion.source.text
        for arg in dropped:
            end, gap = arg.end, ""
            if end <= first:  # before the target: what follows it too, up to the next
                end = starts[bisect_right(starts, arg.start)]
                # (`MoveJ\Conc,p1`: the name and the target keep a blank between them)
                gap = "" if text[arg.start - 1].isspace() else " "
            edits.append((arg.start, end, gap))
    value = motion.zone.argument.value if zone and motion.zone is not None else None
    if value is not None:
        edits.append((value.start, value.end, INTERMEDIATE_ZONE))
    return edits


class _Emitter:
    """The edits being built: names allocated, declarations queued, check units."""

    def __init__(self, program: Program, comp: Compensator, planned: ProgramPlan,
                 refined: PathRefinement) -> None:
        self.program = program
        self.robot = comp.robot
        self.planned = planned
        self.sites = planned.sites
        self.refined = refined
        #: the targets' plan after path refinement (the joints and conditions to emit)
        self.solved = refined.solved
        self.editor = Editor(program)
        self.names = NameAllocator(
            texts=[program.text, *(decl_program.text for decl_program in comp.decls)])
        # anchor -> its queued declaration, or their list once there are several (a
        # CAM program queues one after each of its hundred thousand robtargets)
        self.decl_blocks: dict[Any, str | list[str]] = {}
        self.decl_anchor_order: list[Any] = []
        self.inserted: set[str] = set()
        #: (stem lower-cased, literal) -> the jointtarget's name: one declaration for both
        self.jt_names: dict[tuple[str, str], str] = {}
        #: (instruction, MoveAbsJ head, tail) -> an intermediate point's statement parts
        self.variant_parts: dict[tuple[str, str, str], tuple[str, str] | tuple[()]] = {}
        self.units = CheckUnits()
        # what verification reads back: (statement id, target slot, target row), move
        # by move, and as (k,3) arrays for the moves emitted as columns ...
        self.checks: list[tuple[int, int, int]] = []
        self._check_columns: list[np.ndarray] = []
        # ... and intermediate points: (statement id, refined segment, its index there)
        self.inter_checks: list[tuple[int, int, int]] = []

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
        if local and not text.startswith("LOCAL"):
            text = "LOCAL " + text
        self._queue(anchor, target, [text])
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
        return self.refined.intermediates()

    def emit(self) -> Expected:
        """All edits (whole statements and declarations); returns what verification must find."""
        t, p, mode = self.planned.targets, self.solved, self.refined.mode
        joint_sites = [i for i in sorted(mode) if mode[i] == "joint"]
        filtered_sites = [i for i in sorted(mode) if mode[i] == "filtered"]
        inter = self._intermediates()
        segment_of = {site: k for k, site in enumerate(self.refined.sites)}
        # joint literals for all destinations and intermediate points at once
        dest_rows = np.array([self.sites[i].rows[-1] for i in joint_sites], dtype=int)
        inter_sites = [i for i in joint_sites if i in inter]
        q_all, ext_all = p.q_cmd[dest_rows], t.extax[dest_rows]
        if inter_sites:  # each point with its move's external axes
            span = np.array([inter[i] for i in inter_sites], dtype=np.int64)
            count = span[:, 1] - span[:, 0]
            at = np.repeat(span[:, 0] - (np.cumsum(count) - count), count)
            rows = np.array([self.sites[i].rows[-1] for i in inter_sites], dtype=int)
            q_all = np.concatenate([q_all, self.refined.points.q_cmd[
                at + np.arange(at.size)]])
            ext_all = np.concatenate([ext_all, t.extax[np.repeat(rows, count)]])
        literals = jointtarget_literals(np.degrees(q_all), ext_all)
        del q_all, ext_all
        dest_literal = literals[: len(joint_sites)]
        inter_start = len(joint_sites)
        self._filtered(filtered_sites)

        approach = {i: d for i, d in self.planned.approach.items() if mode.get(i) == "joint"}
        approach_literal = {}
        if approach:
            keys = list(approach)
            rows = np.array([self.sites[i].rows[-1] for i in keys], dtype=int)
            start = p.q_cmd[rows] - np.array(list(approach.values())) * self.planned.approach_margin
            approach_literal = dict(zip(keys, jointtarget_literals(np.degrees(start),
                                                                   t.extax[rows])))
        if not self._columns:  # the reference: move by move
            for k, i in enumerate(joint_sites):
                points = (literals[inter_start:inter_start + inter[i][1] - inter[i][0]]
                          if i in inter else [])
                inter_start += len(points)
                self._emit_joint_with_points(i, dest_literal[k], inter.get(i), points,
                                             approach_literal.get(i), segment_of.get(i))
            del literals, dest_literal, approach_literal
            self.jt_names.clear()
            self._flush_declarations()
            return self._expected()
        # the points inserted before a move: (its intermediate rows, their literals, its
        # approach point's literal, its refined segment), by the move's place in joint_sites
        extras: dict[int, tuple] = {}
        for k, i in enumerate(joint_sites):
            if i in inter or i in approach:
                points = (literals[inter_start:inter_start + inter[i][1] - inter[i][0]]
                          if i in inter else [])
                inter_start += len(points)
                extras[k] = (inter.get(i), points, approach_literal.get(i), segment_of.get(i))
        del literals  # dest_literal and extras hold what is still needed
        self._emit_joints(joint_sites, dest_literal, extras)  # empties dest_literal
        del dest_literal, extras, approach_literal
        self._flush_declarations()
        return self._expected()

    #: False: every move through `_emit_joint_with_points` and `_filtered_moves` (tests
    #: compare the two routes)
    _columns = True

    def _jointtarget_name(self, stem: str, literal: str, site: Site) -> str:
        """The jointtarget named after `stem` holding `literal`: declared on first use."""
        key = (stem.lower(), literal)
        name = self.jt_names.get(key)
        if name is None:
            name = self.jt_names[key] = self.names.allocate(stem, "jt_")
            self._add_declaration(site, len(site.targets) - 1,
                                  jointtarget_declaration(name, literal))
        return name

    def _emit_joint_with_points(self, i: int, literal: str, inter: tuple[int, int] | None,
                                points: list[str], approach: str | None,
                                segment: int | None) -> None:
        """One move as MoveAbsJ, with its intermediate (`inter`: their rows in the
        refinement, `points` their literals) and approach points inserted before it
        (the reference for `_emit_joints`)."""
        site = self.sites[i]
        motion = site.motion
        stem = _stem(site, len(site.targets) - 1)
        name = self._jointtarget_name(stem, literal, site)
        inter_names = [self._jointtarget_name(f"{stem}_{j + 1}", point, site)
                       for j, point in enumerate(points)]
        approach_name = (self._jointtarget_name(f"{stem}_app", approach, site)
                         if approach is not None else None)
        add_statement = self.units.add_statement
        if inter is not None or approach is not None:  # points inserted before the move
            lines, variants, _ = self._points_before(site, inter, inter_names, approach_name)
            for j, variant in enumerate(variants):
                ident = add_statement(motion.module, motion.routine, variant)
                self.inter_checks.append((ident, segment, inter[0] + j))
            if lines:
                self.editor.insert(motion.syntax.start, "".join(lines))
        statement = joint_statement(self.program.text, site, name)
        self.editor.replace((motion.syntax.start, motion.syntax.end), statement)
        ident = add_statement(motion.module, motion.routine, statement)
        self.checks.append((ident, 0, site.rows[-1]))

    def _emit_joints(self, joint_sites: list[int], literals: list[str],
                     extras: dict[int, tuple]) -> None:
        """Every move as MoveAbsJ, as columns over all moves (the same names,
        declarations and statements as `_emit_joint_with_points` move by move, built by
        list operations instead of several calls per move): the names of all
        destinations and inserted points in the order the moves use them, their
        declarations, the statements. `extras` holds the points inserted before a move
        (see `emit`). `literals` (the destinations' jointtargets) is emptied once they
        are declared."""
        sites = list(map(self.sites.__getitem__, joint_sites))
        motions = [site.motion for site in sites]
        operands = [site.targets[-1] for site in sites]
        stems = self._stems(motions, operands)
        # the jointtargets in the order their names are first asked for: each move's
        # destination, then the points inserted before it
        if extras:  # (placed among the destinations by `_interleave`)
            keys = list(extras)
            ex_stems: list[str] = []
            ex_literals: list[str] = []
            ex_counts: list[int] = []
            for k, (span, points, approach, _segment) in extras.items():
                stem, count = stems[k], len(ex_stems)
                if span is not None:
                    ex_stems += [f"{stem}_{j + 1}" for j in range(len(points))]
                    ex_literals += points
                if approach is not None:
                    ex_stems.append(f"{stem}_app")
                    ex_literals.append(approach)
                ex_counts.append(len(ex_stems) - count)
            per_move = np.zeros(len(sites), dtype=np.int64)
            per_move[keys] = ex_counts
            dest_at, _, order, owner = _interleave(per_move, before=False)
            want_stems = list(map((stems + ex_stems).__getitem__, order))
            want_literals = list(map((literals + ex_literals).__getitem__, order))
            del ex_stems, ex_literals
            names = self._jointtarget_names(want_stems, want_literals,
                                            list(map(motions.__getitem__, owner)),
                                            list(map(operands.__getitem__, owner)))
            dest_names = list(map(names.__getitem__, dest_at))
            del want_stems, want_literals, order, owner
        else:
            dest_names = self._jointtarget_names(stems, literals, motions, operands)
        # the declarations hold the literals now: they go (with the names cache, which
        # nothing asks after this) before the statements are made, the emission's peak
        del stems
        literals.clear()
        self.jt_names.clear()
        text = self.program.text
        syntaxes = [motion.syntax for motion in motions]
        starts = [syntax.start for syntax in syntaxes]
        ends = [syntax.end for syntax in syntaxes]
        values = [operand.argument.value for operand in operands]
        heads = [text[start + len(syntax.name):value.start]
                 for syntax, start, value in zip(syntaxes, starts, values)]
        for n, site in enumerate(sites):
            if len(site.targets) == 2:  # a circular move: the circle point goes
                targets = site.targets
                heads[n] = (text[starts[n] + len(syntaxes[n].name):targets[0].argument.start]
                            + text[targets[1].argument.start:values[n].start])
        # the texts around the names repeat (a program has a few dozen speed, zone and
        # tool combinations): one string for each distinct one, which the statements'
        # JointSlots then share
        distinct: dict[str, str] = {}
        keep = distinct.setdefault
        tails = [keep(tail, tail) for tail in
                 [text[value.end:end] for value, end in zip(values, ends)]]
        heads = [keep(head, head) for head in ["MoveAbsJ" + head for head in heads]]
        del distinct
        statements = list(map("".join, zip(heads, dest_names, tails)))
        slots = list(zip(heads, dest_names, tails))
        modules = [motion.module for motion in motions]
        routines = [motion.routine for motion in motions]
        rows = [site.rows[-1] for site in sites]
        if not extras:
            self.editor.replace_many(starts, ends, statements)
            idents = self.units.add_statements(modules, routines, statements, slots)
            self._add_checks(idents, rows)
            return
        # the statements in the order of the move-by-move route: a move's inserted
        # points, then the move
        var_texts: list[str] = []
        var_slots: list[JointSlot | None] = []
        var_checks: list[tuple[int, int]] = []  # (refined segment, row there)
        var_counts: list[int] = []
        insert_at: list[int] = []
        insert_texts: list[str] = []
        for k, (span, points, approach, segment) in extras.items():
            first = dest_at[k] + 1
            lines, variants, variant_slots = self._points_before(
                sites[k], span, names[first:first + len(points)],
                names[first + len(points)] if approach is not None else None,
                (heads[k], tails[k]))
            if variants:
                var_texts += variants
                var_slots += variant_slots
                var_checks += [(segment, span[0] + j) for j in range(len(variants))]
            var_counts.append(len(variants))
            if lines:
                insert_at.append(starts[k])
                insert_texts.append("".join(lines))
        per_move = np.zeros(len(sites), dtype=np.int64)  # now the statements before each
        per_move[keys] = var_counts
        main_at, inter_at, order, owner = _interleave(per_move, before=True)
        all_texts = list(map((statements + var_texts).__getitem__, order))
        all_slots = list(map((slots + var_slots).__getitem__, order))
        all_modules = list(map(modules.__getitem__, owner))
        all_routines = list(map(routines.__getitem__, owner))
        del var_texts, var_slots, order, owner
        self.editor.replace_many(insert_at, insert_at, insert_texts)
        self.editor.replace_many(starts, ends, statements)
        idents = self.units.add_statements(all_modules, all_routines, all_texts, all_slots)
        self._add_checks(list(map(idents.__getitem__, main_at)), rows)
        self.inter_checks.extend((idents[n], segment, row)
                                 for n, (segment, row) in zip(inter_at, var_checks))

    def _jointtarget_names(self, stems: list[str], literals: list[str],
                           motions: list[MotionInstruction], operands: list[Operand]
                           ) -> list[str]:
        """`_jointtarget_name` for many jointtargets in turn: the names, the new ones
        allocated and declared together."""
        return self._data_names(stems, literals, motions, operands, self.jt_names, "jt_",
                                jointtarget_declaration, joint=True)

    def _data_names(self, stems: list[str], literals: list[str],
                    motions: list[MotionInstruction], operands: list[Operand],
                    known: dict[tuple[str, str], str], prefix: str,
                    declaration: Callable[[str, str], str], joint: bool) -> list[str]:
        """The name of each (stem, literal) in turn, as asked one by one: `known` (stem
        lower-cased, literal) -> name, the names given before, the new ones allocated
        from `prefix` + stem and declared (`declaration(name, literal)`) together, after
        the targets' robtargets or among their modules' declarations. `known` is
        extended by the new names only when a (stem, literal) recurs among these; both
        callers let it go after the call. `joint`: the declarations are jointtargets'
        (read back as columns)."""
        keys = list(zip(map(str.lower, stems), literals))
        first: dict[tuple[str, str], int] = {}
        deque(map(first.setdefault, keys, range(len(keys))), maxlen=0)  # first use of each
        if len(first) == len(keys) and known.keys().isdisjoint(first):
            # every target its own new data (the usual case)
            order: list[int] | range = range(len(keys))
            names = self.names.allocate_many(stems, prefix)
            name_at = names
        else:
            order = [n for key, n in first.items() if key not in known]
            names = self.names.allocate_many([stems[n] for n in order], prefix)
            known.update(zip([keys[n] for n in order], names))
            name_at = list(map(known.__getitem__, keys))
        # the keys (a tuple and a table entry each) go before the declarations are made,
        # the emission's peak
        del keys, first
        self._add_declarations(
            [motions[n] for n in order], [operands[n] for n in order],
            list(map(declaration, names, literals if type(order) is range
                     else [literals[n] for n in order])), joint)
        return name_at

    def _points_before(self, site: Site, inter: tuple[int, int] | None, inter_names: list[str],
                       approach_name: str | None, shape: tuple[str, str] | None = None,
                       ) -> tuple[list[str], list[str], list[JointSlot | None]]:
        """The statements inserted before a move, to its intermediate points (`inter`:
        their rows in the refinement) and its approach point: (the lines to insert, the
        intermediate points' statements, their JointSlots — None in the move-by-move
        route, which makes each statement from its edits). `shape`: the move's MoveAbsJ
        statement around its target's name (see `_variant_parts`)."""
        motion = site.motion
        indent = indent_before(self.program, motion.syntax.start)
        sep = "\n" + indent if indent is not None else " "
        lines: list[str] = []
        variants: list[str] = []
        slots: list[JointSlot | None] = []
        if inter is not None:
            self.inserted.update(inter_names)
            parts = self._variant_parts(site, shape) if self._columns else None
            if parts is not None:  # one statement with a place where the name goes
                slots = [(parts[0], sub, parts[1]) for sub in inter_names]
                variants = list(map("".join, slots))
            else:
                edits = _intermediate_edits(motion)
                variants = [statement_variant(self.program, motion,
                                              joint_edits(site, sub) + edits)
                            for sub in inter_names]
                slots = [None] * len(variants)
            lines = [variant + sep for variant in variants]
        if approach_name is not None:  # stands still there (fine), then arrives from one side
            self.inserted.add(approach_name)
            drops = _intermediate_edits(motion, zone=False)
            statement = statement_variant(self.program, motion,
                                          joint_edits(site, approach_name) + drops)
            lines.append(statement + sep)
            self.units.shapes.add(statement.replace(approach_name, SHAPE_TARGET))
        return lines, variants, slots

    def _variant_parts(self, site: Site, shape: tuple[str, str] | None
                       ) -> tuple[str, str] | None:
        """(text before, text after) the name in the statement to one of the move's
        intermediate points, or None where a name mark cannot stand for it.

        `shape` is (the text before, the text after) the name in the move's own MoveAbsJ
        statement. What an intermediate point changes (its zone, the optional arguments
        it drops) all stands after the target, so moves of one instruction with the same
        shape have the same parts: a program's thousands of arcs cost one variant each
        distinct speed, zone and tool combination, and their operands are not made. (The
        shape holds the statement's whole text but the target's, so moves that differ
        before their target, `MoveL \\Conc, p1, ...` and `MoveL p1, ...`, have their own.)"""
        key = None if shape is None else (site.motion.syntax.name, *shape)
        parts = self.variant_parts.get(key) if key is not None else None
        if parts is None:
            motion = site.motion
            edits = _intermediate_edits(motion)
            split = statement_variant(self.program, motion, joint_edits(
                site, _NAME_MARK) + edits).split(_NAME_MARK)
            parts = (split[0], split[1]) if len(split) == 2 else ()
            if key is not None:
                self.variant_parts[key] = parts
        return parts or None

    def _stems(self, motions: list[MotionInstruction], operands: list[Operand]) -> list[str]:
        """`_stem` of many targets: a name where the target has one, else the
        instruction and its line (the lines found in one search)."""
        stems: list[str | None] = [
            operand.name if operand.form == "name" and operand.name
            else f"{operand.name}_{operand.form}"
            if operand.form in ("offs", "reltool") and operand.name else None
            for operand in operands]
        unnamed = [n for n, stem in enumerate(stems) if stem is None]
        if unnamed:
            lines = self.editor.line_numbers([motions[n].syntax.start for n in unnamed])
            for n, line in zip(unnamed, lines):
                stems[n] = f"{motions[n].name}_L{line}"
        return stems  # type: ignore[return-value]

    def _add_declarations(self, motions: list[MotionInstruction], operands: list[Operand],
                          texts: list[str], joint: bool = True) -> None:
        """`_add_declaration` for many targets: each anchor's block and the check units
        are extended by runs of targets with the same anchor (a CAM program's new
        declarations all go among one module's). `joint`: jointtarget declarations, else
        robtarget ones (the check units keep either apart, to be read back as columns)."""
        add_units = (self.units.add_jointtarget_declarations if joint
                     else self.units.add_robtarget_declarations)
        module_of: dict[str, Any] = {}
        for module in self.program.modules:
            module_of.setdefault(module.name, module)
        modules = [motion.module for motion in motions]
        if all(operand.declaration is None for operand in operands) and len(set(modules)) == 1:
            # no target declared in the program (inline targets): all among one module's
            module = modules[0] if modules else ""
            if modules:
                self._queue(module.lower(), module_of[module], texts)
                add_units(module, None, texts)
            return
        anchors: list[Any] = []
        targets: list[Any] = []
        wheres: list[tuple[str, str | None]] = []
        scope = {}  # one (module, routine) tuple for all targets of a scope
        for n, (motion, operand) in enumerate(zip(motions, operands)):
            decl = operand.declaration
            if (decl is not None and operand.form == "name" and decl.module == motion.module
                    and (decl.routine is None or decl.routine.lower() == motion.routine.lower())):
                anchors.append(id(decl))  # after the declaration
                targets.append(decl)
                where = (decl.module, decl.routine)
                wheres.append(scope.setdefault(where, where))
                if decl.syntax.local and not texts[n].startswith("LOCAL"):
                    texts[n] = "LOCAL " + texts[n]
            else:
                anchors.append(motion.module.lower())  # among the module's declarations
                targets.append(module_of[motion.module])
                where = (motion.module, None)
                wheres.append(scope.setdefault(where, where))
        blocks, order, get = self.decl_blocks, self.decl_anchor_order, self.decl_blocks.get
        for anchor, target, text in zip(anchors, targets, texts):
            block = get(anchor)
            if block is None:
                blocks[anchor] = text
                order.append((anchor, target))
            elif type(block) is str:
                blocks[anchor] = [block, text]
            else:
                block.append(text)
        pos = 0
        for where, run in groupby(wheres):  # the check units, by runs of one scope
            size = len(list(run))
            add_units(*where, texts[pos:pos + size])
            pos += size

    def _queue(self, anchor: Any, target: Any, texts: list[str]) -> None:
        """Queue declarations at an anchor (after `target`, a declaration, or among the
        declarations of `target`, a module)."""
        block = self.decl_blocks.get(anchor)
        if block is None:
            self.decl_anchor_order.append((anchor, target))
            block = self.decl_blocks[anchor] = []
        elif type(block) is str:
            block = self.decl_blocks[anchor] = [block]
        block.extend(texts)

    def _filtered(self, filtered_sites: list[int]) -> None:
        """Filtered robtargets: in the declaration when only compensated moves use it,
        inline in place of an aggregate, else as a new CONST robtarget."""
        if not filtered_sites:
            return
        t, p = self.planned.targets, self.solved
        sites = list(map(self.sites.__getitem__, filtered_sites))
        rows_all = [r for site in sites for r in site.rows]
        rows_a = np.array(rows_all, dtype=int)
        tcp = t.placement.take(rows_a).tcp(self.robot.fk(p.q_cmd[rows_a]))
        conf = self.robot.confdata(p.q_cmd[rows_a])
        literals = robtarget_literals(tcp, conf, t.extax[rows_a])
        del tcp, conf
        if not self._columns:  # the reference: move by move
            self._filtered_moves(sites, dict(zip(rows_all, literals)))
            return
        operands = list(map(t.operand.__getitem__, rows_all))
        replaced = self._filtered_declarations(operands, literals)
        self._filtered_columns(sites, rows_all, operands, literals, replaced)

    def _filtered_declarations(self, operands: list[Operand], literals: list[str]) -> set[int]:
        """Write the filtered robtarget into the declarations of the targets named that
        only compensated moves use, all with one literal; the ids of those declarations.
        `operands` and `literals`: the filtered targets' (a row each)."""
        by_decl: dict[int, list[int]] = {}  # a declaration -> its targets (indices)
        add = by_decl.setdefault
        for n, op in enumerate(operands):
            if op.declaration is not None and op.form == "name":
                add(id(op.declaration), []).append(n)
        if not by_decl:
            return set()
        groups = list(by_decl.values())
        decls = [operands[found[0]].declaration for found in groups]
        keys = [decl.name.lower() for decl in decls]
        uses = count_identifiers(self.program.text, keys)
        # a declaration takes its targets' literal when all have one and nothing else
        # names it (the declaration's own name and its targets' are all its uses)
        chosen = [k for k, (key, found, decl) in enumerate(zip(keys, groups, decls))
                  if uses[key] == 1 + len(found) and decl.syntax.init is not None
                  and (len(found) == 1
                       or all(literals[n] == literals[found[0]] for n in found))]
        if not chosen:
            return set()
        text = self.program.text
        syntaxes = [decls[k].syntax for k in chosen]
        starts = [syntax.start for syntax in syntaxes]
        ends = [syntax.end for syntax in syntaxes]
        news = [text[start:syntax.init.start] + literals[groups[k][0]]
                + text[syntax.init.end:end]
                for k, syntax, start, end in zip(chosen, syntaxes, starts, ends)]
        self.editor.replace_many(starts, ends, news)
        pos = 0
        scopes = [(decls[k].module, decls[k].routine) for k in chosen]
        for where, run in groupby(scopes):  # the check units, by runs of one scope
            size = len(list(run))
            self.units.add_robtarget_declarations(*where, news[pos:pos + size])
            pos += size
        return {id(decls[k]) for k in chosen}

    def _filtered_moves(self, sites: list[Site], f_literal: dict[int, str]) -> None:
        """The declarations that take the filtered robtarget, the moves' statements and
        new robtargets, move by move (the reference for `_filtered_declarations` and
        `_filtered_columns`); `f_literal` the filtered robtarget of each row."""
        t = self.planned.targets
        by_decl: dict[int, list[int]] = {}
        for row in f_literal:
            op = t.operand[row]
            if op.form == "name" and op.declaration is not None:
                by_decl.setdefault(id(op.declaration), []).append(row)
        uses = count_identifiers(self.program.text, {
            t.operand[rows[0]].declaration.key for rows in by_decl.values()}) if by_decl else {}
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
        for site in sites:
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

    def _filtered_columns(self, sites: list[Site], rows: list[int], operands: list[Operand],
                          literals: list[str], replaced: set[int]) -> None:
        """`_filtered_moves` as columns over all targets (rows, their operands and
        filtered literals): the targets that need a new robtarget named and declared
        together (`_data_names`), the statements made by list operations."""
        site_of = [k for k, site in enumerate(sites) for _ in site.rows]
        slot_of = [slot for site in sites for slot in range(len(site.rows))]
        # what goes in place of each target's value: None (its declaration holds the
        # filtered robtarget), the literal (inline) or a name (filled in below)
        new: list[str | None] = [None] * len(operands)
        named: list[int] = []
        for n, op in enumerate(operands):
            form = op.form
            if form == "inline":
                new[n] = literals[n]
            elif not (form == "name" and op.declaration is not None
                      and id(op.declaration) in replaced):
                named.append(n)
        if named:
            motions = [sites[site_of[n]].motion for n in named]
            # the declaration goes beside the robtarget of the site's own operand
            named_ops = [sites[site_of[n]].targets[slot_of[n]] for n in named]
            stems = self._stems(motions, named_ops)
            names = self._data_names(stems, [literals[n] for n in named], motions, named_ops,
                                     {}, "ft_", robtarget_declaration, joint=False)
            for n, name in zip(named, names):
                new[n] = name
        # the statements: a site's text with its targets' values replaced, each with its
        # TargetSlot (the texts around its targets, and the targets as written now)
        text = self.program.text
        motions = [site.motion for site in sites]
        syntaxes = [motion.syntax for motion in motions]
        spans = [op.argument.value for op in operands]
        targets = [text[span.start:span.end] if value is None else value
                   for span, value in zip(spans, new)]
        # the texts around the targets repeat (a few dozen speed, zone and tool
        # combinations): one string for each distinct one, which the slots then share
        keep = {}.setdefault
        slots: list[TargetSlot | None]
        if len(operands) == len(sites):  # a target a site (the usual case)
            heads = [keep(head, head) for head in
                     [text[syntax.start:span.start] for syntax, span in zip(syntaxes, spans)]]
            tails = [keep(tail, tail) for tail in
                     [text[span.end:syntax.end] for syntax, span in zip(syntaxes, spans)]]
            slots = list(zip(heads, targets, tails))
            statements = list(map("".join, slots))
            edited = [k for k, value in enumerate(new) if value is not None]
        else:  # a site of several targets (a MoveC) by its edits
            statements, slots = [], []
            edited = []  # the sites whose statement changes
            n = 0
            for k, site in enumerate(sites):
                size = len(site.rows)
                edits = [(spans[m].start, spans[m].end, new[m])
                         for m in range(n, n + size) if new[m] is not None]
                statements.append(statement_variant(self.program, site.motion, edits))
                slots.append(_target_slot(text, syntaxes[k], spans[n:n + size],
                                          targets[n:n + size], statements[-1], keep))
                if edits:
                    edited.append(k)
                n += size
        self.editor.replace_many([syntaxes[k].start for k in edited],
                                 [syntaxes[k].end for k in edited],
                                 [statements[k] for k in edited])
        idents = self.units.add_statements([motion.module for motion in motions],
                                           [motion.routine for motion in motions], statements,
                                           target_slots=slots)
        self._add_checks([idents[k] for k in site_of], rows, slot_of)

    def _flush_declarations(self) -> None:
        """Insert the queued declarations, in the order their anchors were first used
        (runs of declarations after declarations go in as one batch). The queue is
        emptied: the editor and the check units hold the texts from here on."""
        after: list[tuple[int, int]] = []
        after_texts: list[str] = []
        order, blocks = self.decl_anchor_order, self.decl_blocks
        self.decl_anchor_order, self.decl_blocks = [], {}
        for anchor, target in order:
            block = blocks.pop(anchor)
            if type(anchor) is int:
                after.append((target.syntax.start, target.syntax.end))
                after_texts.append(block if type(block) is str else "\n".join(block))
                if len(after) == chunks.INSERTED_DECLARATIONS:  # the same edits, in order
                    self.editor.insert_lines_after(after, after_texts)
                    after, after_texts = [], []
            else:
                self.editor.insert_lines_after(after, after_texts)
                after, after_texts = [], []
                # given as lines: not joined into one more copy of them all
                self.editor.insert_declaration(target, [block] if type(block) is str else block)
        self.editor.insert_lines_after(after, after_texts)

    def _add_checks(self, idents: Sequence[int], rows: Sequence[int],
                    slots: Sequence[int] | None = None) -> None:
        """Checks of many statements at once (of slot 0, or of `slots`), kept as one (k,3)
        array (a hundred thousand tuples of three ints cost several times as much)."""
        if self.checks:  # the checks made move by move before these keep their place
            self._check_columns.append(np.array(self.checks, dtype=int).reshape(-1, 3))
            self.checks = []
        block = np.zeros((len(rows), 3), dtype=int)
        block[:, 0] = idents
        if slots is not None:
            block[:, 1] = slots
        block[:, 2] = rows
        self._check_columns.append(block)

    def _expected(self) -> Expected:
        """Each compensated pose: the check statement and slot it is read from, its
        intended TCP position, frames and the conditions it runs in."""
        t = self.planned.targets
        ids, slots, rows = np.concatenate(
            [*self._check_columns, np.array(self.checks, dtype=int).reshape(-1, 3)]).T
        placement = t.placement.take(rows)
        position, context = t.pose[rows, :3, 3], self.solved.context.take(rows)
        joints = self.solved.q_cmd[rows]  # as written where a jointtarget is
        if self.inter_checks:
            inter_ids, seg, index = np.array(self.inter_checks, dtype=int).T
            frames = self.refined.frames.take(seg)
            placement = Placement(*(np.concatenate([a, b]) for a, b in (
                (placement.tool, frames.tool), (placement.wobj, frames.wobj),
                (placement.stationary, frames.stationary))))
            ids = np.concatenate([ids, inter_ids])
            slots = np.concatenate([slots, np.zeros(len(seg), int)])
            position = np.concatenate([position, self.refined.points.pose[index, :3, 3]])
            joints = np.concatenate([joints, self.refined.points.q_cmd[index]])
            inter = self.refined.context.take(seg)
            if self.refined.direction is not None:
                inter = replace(inter, last_direction=self.refined.direction[index])
            context = Context.concatenate(context, inter)
        return Expected(ids, slots, position, placement, context, joints)




__all__ = ["INTERMEDIATE_DROPS", "INTERMEDIATE_ZONE", "Emission", "emit_edits", "indent_before"]
