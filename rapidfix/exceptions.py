"""The project's exceptions: every error a user can cause, with where it happened.

Each carries an optional location (file; line and column for text, or row and
column name for tables) so the CLI can print one clear line per problem.
"""

from __future__ import annotations

from pathlib import Path


class RapidfixError(Exception):
    """Base class of every error a user can cause (bad input, unreachable pose, …)."""

    def __init__(
        self,
        message: str,
        *,
        file: str | Path | None = None,
        line: int | None = None,
        column: int | str | None = None,
        row: int | None = None,
        hint: str | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.file = str(file) if file is not None else None
        self.line = line
        self.column = column
        self.row = row
        self.hint = hint

    @property
    def location(self) -> str:
        """`file:line:col` for text, `file: row N, column 'x'` for tables, or ''."""
        if self.row is not None:
            parts = [f"row {self.row}"]
            if self.column is not None:
                parts.append(f"column {self.column!r}")
            where = ", ".join(parts)
            return f"{self.file}: {where}" if self.file else where
        pieces = [p for p in (self.file, self.line, self.column) if p is not None]
        return ":".join(str(p) for p in pieces)

    def __str__(self) -> str:
        text = f"{self.location}: {self.message}" if self.location else self.message
        if self.hint:
            text += f" ({self.hint})"
        return text


class RapidSyntaxError(RapidfixError):
    """A RAPID file that does not parse, or is not RAPID text at all."""


class RapidSemanticError(RapidfixError):
    """A RAPID program that parses but cannot be used as asked (unknown data, bad value)."""


class KinematicsError(RapidfixError):
    """A robot model that is malformed, or a pose that cannot be solved."""


class MeasurementError(RapidfixError):
    """A measurement file that is missing, malformed or implausible."""


class ModelError(RapidfixError):
    """An error model file that is malformed, or made for another robot."""


class LinkError(RapidfixError):
    """A serial upload that failed: no port, no answer, wrong protocol, broken link."""


class OutputExistsError(RapidfixError):
    """An output that would overwrite an input or an existing file without permission."""


class UsageError(RapidfixError):
    """Options that do not go together, or a missing one: wrong use of the command line
    (exit status 2)."""


class InvalidOption(RapidfixError):
    """An option of a library call is out of range; `option` names it, `detail` says why.

    The message names the option as the library does (`path_tolerance_mm must be …`);
    a command line words it with its own flag (`--path-tolerance must be …`).
    """

    def __init__(self, option: str, detail: str) -> None:
        super().__init__(f"{option} {detail}")
        self.option = option
        self.detail = detail


class RapidfixWarning(UserWarning):
    """A warning for the user: the CLI prints it as `rapidfix: warning: …` (exit status 3)."""
