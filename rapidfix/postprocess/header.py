"""The header comment of a compensated program, and recognising one.

The header is a block of RAPID comments inserted after the first MODULE line
(the rewrite places it with the RAPID layer's span edits). It
records what produced the file: the rapidfix version, the model file and its
sha256, the sha256 of the input, and the options. The same marker lets the
post-processor refuse to compensate a program twice, and lets a batch run skip
files whose output is already up to date.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

MARK = "rapidfix-compensated"
_LINE = re.compile(r"^[ \t]*!\s*" + MARK + r"\s+(\w+):[ \t]*(.*?)[ \t]*\r?$", re.MULTILINE)


def _clean(value: str) -> str:
    """One line of printable ASCII (a RAPID comment ends at the line end)."""
    text = value.encode("ascii", "backslashreplace").decode("ascii")
    return re.sub(r"[\r\n\t]+", " ", text)


@dataclass(frozen=True)
class Header:
    """What a compensated file records about how it was made."""

    version: str
    model_path: str
    model_sha256: str
    input_sha256: str
    options: dict[str, str] = field(default_factory=dict)
    summary: str = ""
    #: how the program's run was taken: payload, motion directions, temperature
    conditions: dict[str, str] = field(default_factory=dict)

    def lines(self) -> list[str]:
        """The comment lines, without indentation or line ends."""
        opts = " ".join(
            f"{k}={_clean(v).replace(' ', '_')}" for k, v in sorted(self.options.items())
        )
        out = [
            f"! {MARK} version: rapidfix {_clean(self.version)}",
            f"! {MARK} model: {_clean(self.model_path)}",
            f"! {MARK} model_sha256: {self.model_sha256}",
            f"! {MARK} input_sha256: {self.input_sha256}",
            f"! {MARK} options: {opts}",
        ]
        if self.summary:
            out.append(f"! {MARK} summary: {_clean(self.summary)}")
        if self.conditions:
            conditions = " ".join(f"{k}={_clean(v).replace(' ', '_')}"
                                  for k, v in sorted(self.conditions.items()))
            out.append(f"! {MARK} conditions: {conditions}")
        return out

    def render(self, indent: str, newline: str) -> str:
        """The block as text to insert at the end of the MODULE line (before its line end)."""
        return "".join(f"{newline}{indent}{line}" for line in self.lines())


def read_header(text: str) -> Header | None:
    """The header of a compensated program, or None when the text has none."""
    fields: dict[str, str] = {}
    if MARK not in text:  # a plain search is far quicker than the line pattern
        return None
    for match in _LINE.finditer(text):
        fields.setdefault(match.group(1).lower(), match.group(2))
    if "version" not in fields:
        return None
    options, conditions = {}, {}
    for item in fields.get("options", "").split():
        key, _, value = item.partition("=")
        options[key] = value
    for item in fields.get("conditions", "").split():
        key, _, value = item.partition("=")
        conditions[key] = value
    return Header(
        version=fields["version"].removeprefix("rapidfix ").strip(),
        model_path=fields.get("model", ""),
        model_sha256=fields.get("model_sha256", ""),
        input_sha256=fields.get("input_sha256", ""),
        options=options,
        summary=fields.get("summary", ""),
        conditions=conditions,
    )


def is_compensated(text: str) -> bool:
    """True when the text carries a rapidfix header (it was compensated already)."""
    return read_header(text) is not None
