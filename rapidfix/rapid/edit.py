"""Lossless span edits: change chosen text of a program, keep every other byte.

Edits are collected on an Editor and applied together; they may not overlap.
New text is written with '\\n' and converted to the file's dominant line
ending; the result is encoded with the file's encoding and BOM. With no edits,
`render()` returns the original bytes.
"""

from __future__ import annotations

import re
from array import array
from collections.abc import Sequence
from itertools import chain

import numpy as np

from rapidfix.rapid.program import Declaration, ModuleInfo, MotionInstruction, Program
from rapidfix.rapid.span import Span

#: new lines as an edit keeps them until it renders: (indentation, a line or the lines)
_Lines = tuple[str, str | list[str]]


class EditConflict(ValueError):
    """Two edits touch the same text."""


_BLANKS = re.compile(r"[ \t]*")


def _ends_its_line(text: str, offset: int, line_end: int, comment: bool = True) -> bool:
    """Whether nothing but blanks (or a comment, with `comment`) follows `offset` up to
    `line_end` (looking at the blanks after `offset` only: a line may be the program)."""
    if offset >= line_end:
        return True
    after = _BLANKS.match(text, offset, line_end).end()
    return after >= line_end or text[after] in ("!\r\n" if comment else "\r\n")


def _first_ahead(order: np.ndarray, start: np.ndarray, end: np.ndarray,
                 first: list[int]) -> np.ndarray:
    """`order` (the edits by start and end) with each edit of `first` moved ahead of
    the other insertions at its offset (they lead its run: an insertion ends where it
    starts)."""
    for edit in first:
        at = int(np.flatnonzero(order == edit)[0])
        lead = int(np.searchsorted(start, start[at]))
        if lead < at and end[lead] == start[lead]:
            order = np.concatenate((order[:lead], order[at:at + 1], order[lead:at],
                                    order[at + 1:]))
    return order


def _join_mid_line(order: np.ndarray, start: np.ndarray, mid_line: list[int],
                   texts: list[str | _Lines]) -> None:
    """Lines inserted after one anchor that code follows on its line, by several
    insertions (a filtered robtarget, then a jointtarget, after one declaration): each
    ends the line for that code, so all but the last at a place lose that line break
    (else an empty line stands between them). `order` and `start` are the edits by
    start, `texts` their texts in that order (changed in place)."""
    marked = np.zeros(len(order), dtype=bool)
    marked[np.isin(order, mid_line)] = True
    meets = np.flatnonzero(marked[:-1] & marked[1:] & (start[:-1] == start[1:]))
    for n in meets.tolist():
        texts[n] = texts[n][:-1]  # type: ignore[index]


def ends_its_line(text: str, offset: int, comment: bool = True) -> bool:
    """Whether nothing but blanks (or a comment, with `comment`) follows `offset` on its
    line. New lines inserted there go after the line; else what follows `offset` goes on
    a line of its own (a line comment inserted before code would swallow it)."""
    end = len(text)
    for newline in "\n\r":
        found = text.find(newline, offset)
        if 0 <= found < end:
            end = found
    return _ends_its_line(text, offset, end, comment)


class Editor:
    """Collects replacements and insertions for one Program and renders the result."""

    def __init__(self, program: Program) -> None:
        self.program = program
        # what rendering needs, kept apart so that the model can go first (`release_program`)
        self._source = program.source
        self._kept_bytes = program.kept_bytes
        # the edits as columns, in the order they were made: (start, end) offsets and
        # new text (a CAM program has hundreds of thousands of them)
        # (machine integers: two Python ints an edit cost 72 bytes more)
        self._starts = array("q")
        self._ends = array("q")
        # new lines inserted after an anchor are kept as (indentation, text or lines)
        # until the output is rendered, not as one more string (see `insert_lines_after`)
        self._texts: list[str | _Lines] = []
        # the edits that insert new lines right after an anchor code follows on its line
        # (each "\n" + lines + "\n"): where two meet, the first's last line break goes
        self._mid_line: list[int] = []
        # the insertions that go ahead of the others at their offset (`insert_lines_first`)
        self._first: list[int] = []

    # ------------------------------------------------------------ primitives
    def replace(self, span: Span | tuple[int, int], text: str) -> None:
        """Replace the characters of `span` (a Span or (start, end) offsets) with `text`."""
        start, end = (span.start, span.end) if isinstance(span, Span) else span
        if not 0 <= start <= end <= len(self.program.text):
            raise ValueError(f"span {start}..{end} is outside the program text")
        self._starts.append(start)
        self._ends.append(end)
        self._texts.append(text)

    def replace_many(self, starts: Sequence[int], ends: Sequence[int],
                     texts: Sequence[str]) -> None:
        """`replace` for many (start, end) offsets at once, in order."""
        self._replace_many(starts, ends, texts)

    def _replace_many(self, starts: Sequence[int], ends: Sequence[int],
                      texts: Sequence[str | _Lines]) -> None:
        """`replace_many`, where a text may also be a line kept as (indentation, text)."""
        if not len(starts) == len(ends) == len(texts):
            raise ValueError("replace_many needs as many starts, ends and texts")
        if not starts:
            return
        size = len(self.program.text)
        if min(starts) < 0 or max(ends) > size or (
                np.asarray(starts, dtype=np.int64) > np.asarray(ends, dtype=np.int64)).any():
            raise ValueError("a span is outside the program text")
        self._starts.extend(starts)
        self._ends.extend(ends)
        self._texts.extend(texts)

    def insert(self, offset: int, text: str) -> None:
        """Insert `text` at a character offset."""
        self.replace((offset, offset), text)

    def insert_lines_first(self, offset: int, text: str) -> None:
        """Insert `text`, lines that each begin with their line break, at `offset`, ahead
        of every other insertion there (a file's header after its MODULE line). Where code
        or a comment follows `offset` on its line, that goes on a line of its own after
        them (and after any lines inserted there for an anchor that code follows)."""
        mid_line = not ends_its_line(self.program.text, offset, comment=False)
        if mid_line:
            self._mid_line.append(len(self._texts))
        self._first.append(len(self._texts))
        self.insert(offset, text + "\n" if mid_line else text)

    def insert_after(self, span: Span, text: str) -> None:
        """Insert `text` right after `span` (same line)."""
        self.insert(span.end, text)

    def insert_line_after(self, span: Span, text: str | list[str],
                          indent: str | None = None) -> None:
        """Insert `text` as new line(s) after the line where `span` ends.

        Each new line gets `indent`, by default the indentation of the line
        where `span` starts. `text` may also be given as its lines (a list: the same
        as joining them with '\\n', without making that string).
        """
        self.insert_lines_after([(span.start, span.end)], [text], indent)

    def insert_lines_after(self, anchors: Sequence[tuple[int, int]],
                           texts: Sequence[str | list[str]], indent: str | None = None) -> None:
        """`insert_line_after` for many (start, end) anchors at once, in order (a CAM
        program gets a new declaration after each of its hundred thousand)."""
        if not anchors:
            return
        source = self.program.source
        full = source.text
        size = len(full)
        source.line_start(0)  # makes the line table
        starts = np.asarray(source._line_starts)
        spans = np.asarray(anchors, dtype=np.int64).reshape(-1, 2)
        first = starts[np.searchsorted(starts, spans[:, 0], side="right") - 1].tolist()
        index = np.searchsorted(starts, spans[:, 1], side="right")
        ends = np.where(index < len(starts), starts[np.minimum(index, len(starts) - 1)],
                        size).tolist()
        positions: list[int] = []
        bodies: list[str | _Lines] = []
        pads: dict[str, str] = {}  # one string for each distinct indentation
        open_end = not full.endswith("\n")
        for line_start, start, stop, end, text in zip(first, spans[:, 0].tolist(),
                                                      spans[:, 1].tolist(), ends, texts):
            pad = indent
            if pad is None:  # the blanks the anchor's line starts with
                pad = _BLANKS.match(full, line_start, start).group()
            if not _ends_its_line(full, stop, end):
                # code follows on the anchor's line (`p1:=...; PROC main() ...`): the new
                # lines go right after the anchor, and that code on a line of its own
                if type(text) is list:
                    text = "\n".join(text)
                self._mid_line.append(len(self._texts) + len(positions))
                positions.append(stop)
                bodies.append("".join(f"\n{pad}{part}" if part else "\n"
                                      for part in text.split("\n")) + "\n")
                continue
            if type(text) is list:
                if text and "" not in text and not (end == size and open_end) and not any(
                        "\n" in part or "\r" in part for part in text):
                    # lines of their own (a CAM program's new declarations among the
                    # module's): written out by `text`, as the lines below are
                    positions.append(end)
                    bodies.append((pads.setdefault(pad, pad), text))
                    continue
                text = "\n".join(text)
            if text and "\n" not in text and "\r" not in text and not (end == size and open_end):
                # one line (the usual case): written out as pad + text + "\n" by `text`,
                # once the program model is gone (a CAM program inserts a hundred
                # thousand declarations, each text also held by the rewrite's checks)
                positions.append(end)
                bodies.append((pads.setdefault(pad, pad), text))
                continue
            if "\n" in text:
                parts = text.split("\n")
                if "" in parts:  # an empty line gets no indentation
                    body = "".join(f"{pad}{part}\n" if part else "\n" for part in parts)
                else:
                    body = pad + ("\n" + pad).join(parts) + "\n"
            else:
                body = f"{pad}{text}\n" if text else "\n"
            if end == size and not full.endswith("\n"):
                body = "\n" + body.rstrip("\n")
            positions.append(end)
            bodies.append(body)
        self._replace_many(positions, positions, bodies)

    def line_numbers(self, offsets: Sequence[int]) -> list[int]:
        """1-based line of each character offset of the program text (one search for all)."""
        source = self.program.source
        source.line_start(0)  # makes the line table
        starts = np.asarray(source._line_starts)
        return np.searchsorted(starts, np.asarray(offsets, dtype=np.int64),
                               side="right").tolist()

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

    def insert_declaration(self, module: ModuleInfo, text: str | list[str],
                           indent: str | None = None) -> None:
        """Insert a module-level declaration after the module's last one (or after the
        MODULE line when there is none); `text` may be given as its lines."""
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
        before = source.text[line_start:items[0].start]
        # (an item on the MODULE line, `MODULE M PROC main() ...`: the usual two spaces)
        return before if not before.strip(" \t") else "  "

    # ------------------------------------------------------------ output
    def release_program(self) -> None:
        """Let go of the program (its syntax tree and model); from here on the editor
        only renders. A million-line rewrite renders its output in the memory the model
        held, so the model's and the output's peaks do not add up."""
        del self.program

    def _newlines(self, text: str) -> str:
        text = text.replace("\r\n", "\n")
        newline = self._source.text_newline
        return text if newline == "\n" else text.replace("\n", newline)

    def _ordered(self) -> tuple[list[int], list[int], list[str | _Lines]]:
        """(starts, ends, texts) of the edits by start, end and the order they were made."""
        start = np.array(self._starts, dtype=np.int64)
        end = np.array(self._ends, dtype=np.int64)
        order = np.lexsort((end, start))  # stable: ties keep the order of making
        start, end = start[order], end[order]
        if len(order) > 1:
            # an edit may not start inside the one before it, nor two replacements
            # (not insertions) start at the same place; checked for all pairs at once
            nonempty = end > start
            clash = (start[1:] < end[:-1]) | (
                (start[1:] == start[:-1]) & nonempty[:-1] & nonempty[1:])
            if clash.any():
                after = int(np.argmax(clash)) + 1
                where = Span(int(start[after]), int(end[after]), self._source)
                raise EditConflict(f"edits overlap at {where.location}")
        if self._first:
            order = _first_ahead(order, start, end, self._first)
        texts = list(map(self._texts.__getitem__, order.tolist()))
        if self._mid_line:
            _join_mid_line(order, start, self._mid_line, texts)
        return start.tolist(), end.tolist(), texts

    def text(self) -> str:
        """The edited text (decoded)."""
        original = self._source.text
        # new text is written with '\n': in a '\n' file only a stray '\r\n' needs work
        marker = "\r" if self._source.text_newline == "\n" else "\n"
        newlines = self._newlines
        starts, ends, kept = self._ordered()
        gaps = [original[a:b] for a, b in zip([0, *ends], starts)]
        gaps.append(original[ends[-1] if ends else 0:])
        texts = [text if type(text) is str else f"{text[0]}{text[1]}\n"
                 if type(text[1]) is str else text[0] + ("\n" + text[0]).join(text[1]) + "\n"
                 for text in kept]
        del kept
        texts = [newlines(text) if marker in text else text for text in texts]
        return "".join(chain.from_iterable(zip(gaps, texts))) + gaps[-1]

    def render(self) -> bytes:
        """The edited file as bytes: original encoding, BOM and line endings."""
        if not self._texts:
            return self._source.encode() if self._kept_bytes is None else self._kept_bytes
        return self._source.encode(self.text())
