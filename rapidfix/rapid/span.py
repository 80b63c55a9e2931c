"""Source spans: where an item of the program model sits in its file."""

from __future__ import annotations

from dataclasses import dataclass, field

from rapidfix.rapid.source import SourceText


@dataclass(slots=True)
class Span:
    """Characters `start`..`end` (end exclusive) of the decoded text of a file.

    Line and column (1-based) are computed on demand from the offsets, so
    building spans for a large program costs almost nothing. Treat a span as
    read-only (it is not frozen only because frozen dataclasses are slower to
    create, and a large program has millions of spans).
    """

    start: int
    end: int
    source: SourceText = field(repr=False, compare=False)

    @property
    def file(self) -> str:
        return self.source.filename

    @property
    def line(self) -> int:
        return self.source.line_column(self.start)[0]

    @property
    def column(self) -> int:
        return self.source.line_column(self.start)[1]

    @property
    def end_line(self) -> int:
        return self.source.line_column(self.end)[0]

    @property
    def end_column(self) -> int:
        return self.source.line_column(self.end)[1]

    @property
    def text(self) -> str:
        """The source text the span covers."""
        return self.source.text[self.start:self.end]

    @property
    def location(self) -> str:
        """`file:line:col` for messages."""
        line, column = self.source.line_column(self.start)
        return f"{self.file}:{line}:{column}"
