"""Lossless span edits: change chosen text of a program, keep every other byte.

Edits are collected on an Editor and applied together; they may not overlap.
New text is written with '\\n' and converted to the file's dominant line
ending; the result is encoded with the file's encoding and BOM. With no edits,
`render()` returns the original bytes.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

from rapidfix.rapid.program import Declaration, ModuleInfo, MotionInstruction, Program
from rapidfix.rapid.span import Span


class EditConflict(ValueError):
    """Two edits touch the same text."""


@dataclass(frozen=True)
class Edit:
    start: int
    end: int
    text: str
    order: int


class Editor:
    """Collects replacements and insertions for one Program and renders the result."""

    def __init__(self, program: Program) -> None:
        self.program = program
        self._edits: list[Edit] = []

    # ------------------------------------------------------------ primitives
    def replace(self, span: Span | tuple[int, int], text: str) -> None:
        """Replace the characters of `span` (a Span or (start, end) offsets) with `text`."""
        start, end = (span.start, span.end) if isinstance(span, Span) else span
        if not 0 <= start <= end <= len(self.program.text):
            raise ValueError(f"span {start}..{end} is outside the program text")
        self._edits.append(Edit(start, end, self._newlines(text), len(self._edits)))

    def insert(self, offset: int, text: str) -> None:
        """Insert `text` at a character offset."""
        self.replace((offset, offset), text)

    def insert_after(self, span: Span, text: str) -> None:
        """Insert `text` right after `span` (same line)."""
        self.insert(span.end, text)

    def insert_line_after(self, span: Span, text: str, indent: str | None = None) -> None:
        """Insert `text` as new line(s) after the line where `span` ends.

        Each new line gets `indent`, by default the indentation of the line
        where `span` starts.
        """
        source = self.program.source
        if indent is None:
            line_start = source.line_start(span.start)
            line = source.text[line_start:span.start]
            indent = line[: len(line) - len(line.lstrip(" \t"))]
        end = source.line_end(span.end)
        body = "".join(f"{indent}{line}\n" if line else "\n" for line in text.split("\n"))
        if end == len(source.text) and not source.text.endswith("\n"):
            body = "\n" + body.rstrip("\n")
        self.insert(end, body)

    # ------------------------------------------------------------ conveniences
    def replace_statement(self, motion: MotionInstruction, text: str) -> None:
        """Replace a whole instruction, `;` included (`text` should end with ';')."""
        self.replace(motion.span, text)

    def replace_value(self, declaration: Declaration, literal: str) -> None:
        """Replace a declaration's initial value (after `:=`)."""
        if declaration.value_span is None:
            raise ValueError(f"{declaration.name} has no initial value to replace")
        self.replace(declaration.value_span, literal)

    def insert_declaration_after(self, declaration: Declaration, text: str) -> None:
        """Insert a new declaration on the line after `declaration`, same indentation."""
        self.insert_line_after(declaration.span, text)

    def insert_declaration(self, module: ModuleInfo, text: str, indent: str | None = None) -> None:
        """Insert a module-level declaration after the module's last one (or after the
        MODULE line when there is none)."""
        if indent is None and module.declarations_end == module.header_end:
            indent = self._first_item_indent(module)
        anchor = self.program.span(module.declarations_end, module.declarations_end)
        if indent is None:
            last = [d for d in self.program.declarations
                    if d.routine is None and d.module == module.name
                    and d.span.end == module.declarations_end]
            anchor = last[0].span if last else anchor
        self.insert_line_after(anchor, text, indent)

    def _first_item_indent(self, module: ModuleInfo) -> str:
        items = module.syntax.items
        if not items:
            return "  "
        source = self.program.source
        line_start = source.line_start(items[0].start)
        return source.text[line_start:items[0].start] or ""

    # ------------------------------------------------------------ output
    def _newlines(self, text: str) -> str:
        text = text.replace("\r\n", "\n")
        return text if self.program.newline == "\n" else text.replace("\n", self.program.newline)

    def _ordered(self) -> list[Edit]:
        edits = sorted(self._edits, key=lambda e: (e.start, e.end, e.order))
        for before, after in itertools.pairwise(edits):
            if after.start < before.end or (after.start == before.start
                                            and before.end > before.start
                                            and after.end > after.start):
                raise EditConflict(
                    f"edits overlap at {self.program.span(after.start, after.end).location}")
        return edits

    def text(self) -> str:
        """The edited text (decoded)."""
        original = self.program.text
        pieces = []
        position = 0
        for edit in self._ordered():
            pieces.append(original[position:edit.start])
            pieces.append(edit.text)
            position = edit.end
        pieces.append(original[position:])
        return "".join(pieces)

    def render(self) -> bytes:
        """The edited file as bytes: original encoding, BOM and line endings."""
        if not self._edits:
            return self.program.original
        return self.program.source.encode(self.text())
