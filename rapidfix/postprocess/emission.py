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

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rapidfix.error_model import Context
from rapidfix.postprocess.compensator import Compensator
from rapidfix.postprocess.emission_forms import (
    joint_edits,
    joint_statement,
    jointtarget_declaration,
    jointtarget_literals,
    robtarget_literals,
    statement_variant,
)
from rapidfix.postprocess.naming import NameAllocator, count_identifiers
from rapidfix.postprocess.placement import Placement
from rapidfix.postprocess.planning import ProgramPlan
from rapidfix.postprocess.refinement import PathRefinement
from rapidfix.postprocess.reparse_changes import CheckUnits
from rapidfix.postprocess.resolve import Site
from rapidfix.postprocess.verify import Expected
from rapidfix.rapid import Editor, Program, format_declaration

#: optional arguments left off the intermediate points of a subdivided move
INTERMEDIATE_DROPS = frozenset({"inpos", "z", "t", "id"})
INTERMEDIATE_ZONE = "z0"


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


def indent_before(program: Program, offset: int) -> str | None:
    """Whitespace between the line start and offset, or None if text precedes it."""
    source = program.source
    before = source.text[source.line_start(offset):offset]
    return before if before.strip() == "" else None


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
        self.decl_blocks: dict[Any, list[str]] = {}
        self.decl_anchor_order: list[Any] = []
        self.inserted: set[str] = set()
        self.units = CheckUnits()
        # what verification reads back: (statement id, target slot, target row) ...
        self.checks: list[tuple[int, int, int]] = []
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
        r = self.refined.points
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

        approach = {i: d for i, d in self.planned.approach.items() if mode.get(i) == "joint"}
        approach_literal = {}
        if approach:
            keys = list(approach)
            rows = np.array([self.sites[i].rows[-1] for i in keys], dtype=int)
            start = p.q_cmd[rows] - np.array(list(approach.values())) * self.planned.approach_margin
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
            lines = []
            if i in inter or i in approach:  # points inserted before the move
                indent = indent_before(self.program, motion.syntax.start)
                sep = "\n" + indent if indent is not None else " "
                drops = [(op.argument.start, op.argument.end, "")
                         for key, op in motion.optional.items() if key in INTERMEDIATE_DROPS]
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
        t, p = self.planned.targets, self.solved
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
        t = self.planned.targets
        ids, slots, rows = np.array(self.checks, dtype=int).reshape(-1, 3).T
        placement = t.placement.take(rows)
        tcp, context = t.pose[rows], self.solved.context.take(rows)
        if self.inter_checks:
            inter_ids, seg, index = np.array(self.inter_checks, dtype=int).T
            frames = self.refined.frames.take(seg)
            placement = Placement(*(np.concatenate([a, b]) for a, b in (
                (placement.tool, frames.tool), (placement.wobj, frames.wobj),
                (placement.stationary, frames.stationary))))
            ids = np.concatenate([ids, inter_ids])
            slots = np.concatenate([slots, np.zeros(len(seg), int)])
            tcp = np.concatenate([tcp, self.refined.points.pose[index]])
            inter = self.refined.context.take(seg)
            if self.refined.direction is not None:
                inter = replace(inter, last_direction=self.refined.direction[index])
            context = Context.concatenate(context, inter)
        return Expected(ids, slots, tcp, placement, context)




__all__ = ["INTERMEDIATE_DROPS", "INTERMEDIATE_ZONE", "Emission", "emit_edits", "indent_before"]
