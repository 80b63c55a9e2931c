"""Decoding RAPID source files so that they can be written back byte for byte.

Real programs are UTF-8 (with or without a byte-order mark), UTF-16 with a BOM
(rare; without one it is recognised by its zero bytes and written back without),
or a legacy single-byte code page (CP1252 comments are common). The
decoded text keeps every line ending as it was; offsets into it are what the
parser and the span edits use.
"""

from __future__ import annotations

import codecs
from array import array
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass, field

from rapidfix.exceptions import RapidSyntaxError

_BOMS: tuple[tuple[bytes, str], ...] = (
    (codecs.BOM_UTF8, "utf-8"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
)

# Control characters that never occur in RAPID text (tab, LF, VT, FF, CR and the
# old DOS end-of-file mark Ctrl-Z excepted). One of them means binary data.
_BINARY_BYTES = bytes(b for b in range(32) if b not in (9, 10, 11, 12, 13, 26))


@dataclass(frozen=True)
class SourceText:
    """A decoded source file: text plus how to turn it back into the same bytes."""

    text: str
    filename: str = "<string>"
    encoding: str = "utf-8"
    bom: bytes = b""
    #: the file's dominant line ending: '\n', '\r\n', or '\r' for a file whose lines all
    #: end in a lone CR (its `text` has '\n' there: see `text_newline`)
    newline: str = "\n"
    # offsets of the line starts, as machine integers: a million-line program's would
    # take 36 MB as a list of Python ints, 8 MB as an array
    _line_starts: Sequence[int] = field(default_factory=list, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self._line_starts:
            starts = array("q", [0])
            add = starts.append
            text = self.text
            find = text.find
            pos = find("\n")
            while pos >= 0:
                add(pos + 1)
                pos = find("\n", pos + 1)
            object.__setattr__(self, "_line_starts", starts)

    @property
    def text_newline(self) -> str:
        """The line ending in `text`: the file's, but '\\n' where a file's lone CRs were
        read as LF (`encode` writes them back)."""
        return "\n" if self.newline == "\r" else self.newline

    @property
    def line_count(self) -> int:
        """How many lines the text has, counted as its messages count them (by LF; a
        last line without one counts too)."""
        text = self.text
        return len(self._line_starts) - (not text or text.endswith("\n"))

    def line_column(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of a character offset."""
        line = bisect_right(self._line_starts, offset)
        return line, offset - self._line_starts[line - 1] + 1

    def line_start(self, offset: int) -> int:
        """Offset of the first character of the line holding `offset`."""
        return self._line_starts[bisect_right(self._line_starts, offset) - 1]

    def line_end(self, offset: int) -> int:
        """Offset just past the line holding `offset` (after its line ending)."""
        index = bisect_right(self._line_starts, offset)
        return self._line_starts[index] if index < len(self._line_starts) else len(self.text)

    def encode(self, text: str | None = None) -> bytes:
        """Bytes of `text` (default: the original text) in the file's encoding, BOM first."""
        body = self.text if text is None else text
        # read with LF where the file has a lone CR (see `_source_text`): written with CR
        written = body.replace("\n", "\r") if self.newline == "\r" else body
        try:
            return self.bom + written.encode(self.encoding)
        except UnicodeEncodeError as err:  # (the same offsets in `body`, counted by LF)
            line, column = self._position_in(body, err.start)
            raise RapidSyntaxError(
                f"character {body[err.start]!r} cannot be written in the file's "
                f"encoding {self.encoding}",
                file=self.filename,
                line=line,
                column=column,
            ) from None

    @staticmethod
    def _position_in(text: str, offset: int) -> tuple[int, int]:
        line = text.count("\n", 0, offset) + 1
        return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def dominant_newline(text: str) -> str:
    """'\\r\\n' when most line endings are CRLF, else '\\n' (also for one-line files)."""
    crlf = text.count("\r\n")
    lf = text.count("\n") - crlf
    return "\r\n" if crlf > lf else "\n"


def _lone_cr(body: str | bytes) -> bool:
    """Whether every line of a file's text (or bytes) ends in a lone CR: CR and no LF."""
    cr, lf = ("\r", "\n") if isinstance(body, str) else (b"\r", b"\n")
    return cr in body and lf not in body  # type: ignore[operator]


def _source_text(text: str, filename: str, encoding: str, bom: bytes) -> SourceText:
    """A SourceText of decoded `text`. A file whose lines end in a lone CR (old Mac
    editors) and never in LF is read with LF: its comments then end where its lines
    do and its lines are counted as an editor shows them; `encode` writes CR again."""
    if _lone_cr(text):
        return SourceText(text.replace("\r", "\n"), filename, encoding, bom, "\r")
    return SourceText(text, filename, encoding, bom, dominant_newline(text))


def decode_source(data: bytes | str, filename: str = "<string>") -> SourceText:
    """Decode file bytes (or take text as is) into a SourceText; binary data is refused."""
    if isinstance(data, str):
        text = data[1:] if data.startswith("\ufeff") else data
        bom = codecs.BOM_UTF8 if data.startswith("\ufeff") else b""
        return _source_text(text, filename, "utf-8", bom)
    bom, encoding = b"", ""
    for mark, name in _BOMS:
        if data.startswith(mark):
            bom, encoding = mark, name
            break
    body = data[len(bom):]
    if not encoding:
        encoding = _utf16_without_bom(body)
    if encoding.startswith("utf-16"):
        try:
            text = body.decode(encoding)
        except UnicodeDecodeError:
            raise _not_text(filename, "it has a UTF-16 byte-order mark but is not UTF-16") from None
    else:
        bad = _first_binary_byte(body)
        if bad >= 0:
            line = body.count(b"\r" if _lone_cr(body) else b"\n", 0, bad) + 1
            looks = (" (it looks like UTF-16 without a byte-order mark, but does not decode "
                     "as UTF-16)" if body[bad] == 0 and _half_zero(body) else "")
            raise RapidSyntaxError(
                f"not RAPID text: binary byte 0x{body[bad]:02X} at offset {bad + len(bom)}"
                + looks,
                file=filename,
                line=line,
            )
        text, encoding = _decode_8bit(body)
    return _source_text(text, filename, encoding, bom)


def _first_binary_byte(body: bytes) -> int:
    """Index of the first control byte that text never holds, or -1."""
    if len(body.translate(None, _BINARY_BYTES)) == len(body):
        return -1
    for index, byte in enumerate(body):
        if byte in _BINARY_BYTES:
            return index
    return -1  # pragma: no cover - unreachable, the translate test found one


def _half_zero(body: bytes) -> bool:
    """Zero bytes in most even or most odd positions: the mark of UTF-16 text."""
    n = max(1, len(body) // 2)
    return body[0::2].count(0) >= 0.5 * n or body[1::2].count(0) >= 0.5 * n


def _utf16_without_bom(body: bytes) -> str:
    """"utf-16-le" / "utf-16-be" for text that is evidently UTF-16 without a byte-order
    mark (a zero byte in every other position, as ASCII text in UTF-16 has), else ""."""
    if len(body) < 4 or len(body) % 2 or b"\x00" not in body:
        return ""
    even, odd = body[0::2], body[1::2]
    for name, high, low in (("utf-16-le", odd, even), ("utf-16-be", even, odd)):
        if high.count(0) >= 0.9 * len(high) and low.count(0) == 0:
            try:
                text = body.decode(name)
            except UnicodeDecodeError:
                continue
            if _first_binary_byte(text.encode("utf-8", "surrogatepass")) < 0:
                return name
    return ""


def _decode_8bit(body: bytes) -> tuple[str, str]:
    """UTF-8 if it decodes; else CP1252; else Latin-1, which maps every byte."""
    try:
        return body.decode("utf-8"), "utf-8"
    except UnicodeDecodeError:
        pass  # a stray UTF-8 BOM on a legacy file is kept as it is, like every byte
    try:
        return body.decode("cp1252"), "cp1252"
    except UnicodeDecodeError:
        return body.decode("latin-1"), "latin-1"


def _not_text(filename: str, why: str) -> RapidSyntaxError:
    return RapidSyntaxError(f"not RAPID text: {why}", file=filename)
