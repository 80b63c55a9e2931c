"""The text a rewrite changed, as whole statements and declarations, parsed on their own.

The rewrite changes a program only by replacing a whole statement or declaration
with a new one, inserting whole statements before a statement, inserting whole
declarations among declarations, and inserting or removing comment lines; every
other byte is the input's, which parsed. RAPID's grammar is context-free and a
statement (`_statement`) or declaration (`data_decl`) is one of its symbols, so
the output parses exactly when every new unit parses as a unit of its kind: the
output's derivation is the input's with those subtrees exchanged. Parsing only
the new units, grouped by module and routine as they stand in the output, is
therefore the same check as parsing the whole output again, at the cost of the
changed text only. It also gives back the values the output commands (a
jointtarget and the MoveAbsJ that names it sit in the same check module).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import groupby

from rapidfix.rapid import MotionInstruction, Program, parse_program

#: a statement naming the jointtarget it moves to: (text before the name, the name, text after)
JointSlot = tuple[str, str, str]
#: a statement whose targets are robtargets named or written inline: the texts around its
#: targets and the targets, (text, target, text, ..., target, text)
TargetSlot = tuple[str, ...]


#: the target every statement of `CheckUnits.shapes` names
SHAPE_TARGET = "rapidfix_shape_target"


@dataclass
class CheckUnits:
    """New statements and declarations of one rewrite, by (module, routine).

    `add_statement` returns the statement's id; `order()` lists the ids in the
    order their motion instructions appear in the check program. Declarations of
    jointtargets (`add_jointtarget_declarations`) and of robtargets
    (`add_robtarget_declarations`), and statements given with their `JointSlot` (a
    MoveAbsJ to a jointtarget by name) or their `TargetSlot` (an instruction kept, its
    filtered robtargets named or inline) are also kept apart, so that the read-back can
    take them as columns (`verify`).
    """

    comments: list[str] = field(default_factory=list)
    #: statements whose syntax alone is checked, one of each distinct shape, their target
    #: named `SHAPE_TARGET` (the approach points': their joints are not read back)
    shapes: set[str] = field(default_factory=set)
    #: by scope: the declarations in the order they came, and the kind of each
    #: ("joint", "robtarget" or "other")
    _decls: dict[tuple[str, str | None], list[str]] = field(default_factory=dict)
    _kinds: dict[tuple[str, str | None], list[str]] = field(default_factory=dict)
    #: by scope: runs of statements with consecutive ids, (first id, texts) (not an
    #: (id, text) pair per statement: a CAM program has hundreds of thousands)
    _statements: dict[tuple[str, str], list[tuple[int, list[str]]]] = field(default_factory=dict)
    #: by statement id: its JointSlot, or None
    _slots: list[JointSlot | None] = field(default_factory=list)
    #: by statement id: its TargetSlot, or None
    _target_slots: list[TargetSlot | None] = field(default_factory=list)
    _count: int = 0

    def add_declaration(self, module: str, routine: str | None, text: str) -> None:
        """A new or replaced declaration (`routine` None at module level)."""
        self._add((module, routine), [text], "other")

    def add_robtarget_declarations(self, module: str, routine: str | None,
                                   texts: list[str]) -> None:
        """`add_declaration` for many robtarget declarations (new or replaced) of one
        scope."""
        self._add((module, routine), texts, "robtarget")

    def _add(self, scope: tuple[str, str | None], texts: list[str], kind: str) -> None:
        self._decls.setdefault(scope, []).extend(texts)
        self._kinds.setdefault(scope, []).extend([kind] * len(texts))

    def _declarations(self, kind: str) -> dict[tuple[str, str | None], list[str]]:
        """The declarations of one kind, by scope (a scope's own list where all are)."""
        found = {}
        for scope, kinds in self._kinds.items():
            count = kinds.count(kind)
            if count == len(kinds):
                found[scope] = self._decls[scope]
            elif count:
                found[scope] = [text for text, of in zip(self._decls[scope], kinds)
                                if of == kind]
        return found

    def add_statement(self, module: str, routine: str, text: str) -> int:
        """A new or replaced motion instruction; returns its id."""
        ident = self._count
        self._count += 1
        runs = self._statements.setdefault((module, routine), [])
        if runs and runs[-1][0] + len(runs[-1][1]) == ident:
            runs[-1][1].append(text)
        else:
            runs.append((ident, [text]))
        self._slots.append(None)
        self._target_slots.append(None)
        return ident

    def add_jointtarget_declarations(self, module: str, routine: str | None,
                                     texts: list[str]) -> None:
        """`add_declaration` for many `CONST jointtarget` declarations of one scope."""
        self._add((module, routine), texts, "joint")

    def add_statements(self, modules: list[str], routines: list[str], texts: list[str],
                       slots: list[JointSlot | None] | None = None,
                       target_slots: list[TargetSlot | None] | None = None) -> range:
        """`add_statement` for many statements (module and routine of each, and the
        JointSlot or the TargetSlot of each or None); their ids."""
        first = self._count
        self._count += len(texts)
        statements = self._statements
        pos = first
        for key, run in groupby(zip(modules, routines)):
            size = len(list(run))
            part = texts[pos - first:pos - first + size]
            runs = statements.setdefault(key, [])
            if runs and runs[-1][0] + len(runs[-1][1]) == pos:
                runs[-1][1].extend(part)
            else:
                runs.append((pos, part))
            pos += size
        none = [None] * len(texts)
        self._slots.extend(slots if slots is not None else none)
        self._target_slots.extend(target_slots if target_slots is not None else none)
        return range(first, self._count)

    @property
    def statement_count(self) -> int:
        return self._count

    def joint_slots(self) -> list[JointSlot | None]:
        """The JointSlot of each statement (by id), None for the others."""
        return self._slots

    def target_slots(self) -> list[TargetSlot | None]:
        """The TargetSlot of each statement (by id), None for the others."""
        return self._target_slots

    def joint_declarations(self) -> dict[tuple[str, str | None], list[str]]:
        """The jointtarget declarations by (module, routine or None)."""
        return self._declarations("joint")

    def robtarget_declarations(self) -> dict[tuple[str, str | None], list[str]]:
        """The robtarget declarations by (module, routine or None)."""
        return self._declarations("robtarget")

    def other_declarations(self) -> dict[tuple[str, str | None], list[str]]:
        """The declarations other than `joint_declarations` and `robtarget_declarations`,
        by (module, routine or None)."""
        return self._declarations("other")

    def statement_scopes(self) -> list[tuple[tuple[str, str], list[int]]]:
        """(module, routine) and the ids of its statements, for each scope."""
        return [(key, [ident for first, texts in runs
                       for ident in range(first, first + len(texts))])
                for key, runs in self._statements.items()]

    def _routines(self) -> dict[str, dict[str, None]]:
        """Module -> its routines (an ordered set: a program may have thousands)."""
        by_module: dict[str, dict[str, None]] = {}
        for module, routine in [*self._decls, *self._statements]:
            routines = by_module.setdefault(module, {})
            if routine is not None:
                routines[routine] = None
        return by_module

    def text(self, without: tuple[str, ...] = ()) -> tuple[str, list[int]]:
        """The check program and the statement ids in the order they appear in it;
        `without` "joint": without the jointtarget declarations and the statements with
        a JointSlot; "robtarget": without the robtarget declarations and the statements
        with a TargetSlot."""
        out: list[str] = []
        order: list[int] = []
        modules = self._routines() or {"RapidfixCheck": {}}  # the comments alone
        joint, robtarget = "joint" in without, "robtarget" in without
        decls = self._decls
        if without:
            decls = {scope: [text for text, kind in zip(texts, self._kinds[scope])
                             if kind not in without] for scope, texts in self._decls.items()}
        slots, target_slots = self._slots, self._target_slots
        for n, (module, routines) in enumerate(modules.items()):
            out.append(f"MODULE {module}")
            if n == 0:
                out.extend(self.comments)
            out.extend(decls.get((module, None), []))
            for routine in routines:
                out.append(f"PROC {routine}()")
                out.extend(decls.get((module, routine), []))
                for first, texts in self._statements.get((module, routine), []):
                    for ident, statement in enumerate(texts, first):
                        if ((joint and slots[ident] is not None)
                                or (robtarget and target_slots[ident] is not None)):
                            continue
                        out.append(statement)
                        order.append(ident)
                out.append("ENDPROC")
            out.append("ENDMODULE")
        return "\n".join(out) + "\n", order

    def parse_shapes(self, filename: str) -> None:
        """Parse the `shapes`, one statement each, in one check program; raises
        RapidfixError (syntax) or ValueError when one is not one motion instruction."""
        if not self.shapes:
            return
        body = "\n".join(sorted(self.shapes))
        text = f"MODULE rapidfix_shapes\nPROC rapidfix_shapes()\n{body}\nENDPROC\nENDMODULE\n"
        program = parse_program(text, f"{filename} (rewritten parts)")
        if len(program.motions) != len(self.shapes):
            raise ValueError(f"{len(program.motions)} motion instructions in "
                             f"{len(self.shapes)} statements")

    def parse(self, filename: str) -> tuple[Program, list[MotionInstruction]]:
        """Parse the check program; the motions (one per statement id, by id).

        Raises RapidfixError (syntax) or ValueError when a statement is not exactly
        one motion instruction.
        """
        text, order = self.text()
        program = parse_program(text, f"{filename} (rewritten parts)")
        if len(program.motions) != len(order):
            raise ValueError(f"{len(program.motions)} motion instructions in the rewritten "
                             f"parts, {len(order)} expected")
        by_id: list[MotionInstruction | None] = [None] * len(order)
        for ident, motion in zip(order, program.motions):
            by_id[ident] = motion
        return program, by_id  # type: ignore[return-value]
