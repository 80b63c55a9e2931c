"""Entry points: RAPID text or bytes in, Program model out."""

from __future__ import annotations

import sys
from collections import namedtuple
from pathlib import Path

from lark.exceptions import UnexpectedInput

from rapidfix.exceptions import RapidSyntaxError
from rapidfix.gc_pause import cyclic_gc_paused
from rapidfix.rapid import syntax as s
from rapidfix.rapid.grammar import rapid_parser
from rapidfix.rapid.model_builder import build_program
from rapidfix.rapid.program import Program
from rapidfix.rapid.source import SourceText, decode_source
from rapidfix.rapid.syntax_errors import explain

# New container objects above which a build ends with one full collection.
_MANY_OBJECTS = 100_000


#: A process reads its first this many characters with the plain grammar. Building
#: the fast parser (compiling its terminals) costs about 0.1 s, what the plain grammar
#: needs for some 20,000 characters; a command on one small file never pays it, and a
#: process that reads more (a large file, a batch) builds it once and keeps it.
WARM_UP_CHARS = 20_000
_read_plain = 0  # characters this process has read with the plain grammar so far


def parse_text(text: str) -> s.SourceFile:
    """The fast route (rapidfix.rapid.fastpath.parse_text), imported when first taken: a
    command on one small file never imports the fast path (its patterns, 20 ms)."""
    from rapidfix.rapid.fastpath import parse_text as fast_route

    return fast_route(text)


_CacheInfo = namedtuple("_CacheInfo", "currsize")


class _FastParser:
    """Whether fastpath.fast_parser has been built (its cache), asked without importing
    the fast path."""

    @staticmethod
    def cache_info() -> _CacheInfo:
        fastpath = sys.modules.get("rapidfix.rapid.fastpath")
        return (_CacheInfo(0) if fastpath is None
                else _CacheInfo(fastpath.fast_parser.cache_info().currsize))


fast_parser = _FastParser()


def parse_source(source: SourceText) -> s.SourceFile:
    """The syntax tree of decoded source; raises RapidSyntaxError. The fast and the
    plain route give the same tree (tests/rapid: the equivalence tests)."""
    global _read_plain
    text = source.text
    try:
        if (_read_plain + len(text) <= WARM_UP_CHARS
                and fast_parser.cache_info().currsize == 0):
            _read_plain += len(text)
            return rapid_parser().parse(text)
        return parse_text(text)
    except UnexpectedInput as err:
        raise explain(source, err) from None


def parse_program(source: str | bytes, filename: str = "<string>") -> Program:
    """Parse RAPID text or file bytes into a Program; raises RapidSyntaxError.

    Bytes are decoded as described in rapidfix.rapid.source; the Program can
    write them back unchanged. The objects of a large program are kept out of the
    cyclic collector's later collections (rapidfix.gc_pause.settle_new_objects); they
    are freed by reference counting when the Program is dropped.
    """
    return parse_decoded(*decode_for_model(source, filename))


def decode_for_model(source: str | bytes, filename: str) -> tuple[SourceText, bytes | None]:
    """The decoded source and the bytes a Program must keep (`Program.kept_bytes`):
    None when the text encodes back to exactly `source`, as nearly every file does.
    A caller that lets go of `source` then spares a large file's bytes while its model
    is built and used."""
    decoded = decode_source(source, filename)
    if isinstance(source, str):
        decoded.encode()  # a character the encoding cannot hold is refused here, as read
        return decoded, None
    try:
        same = decoded.encode() == source
    except RapidSyntaxError:
        same = False
    return decoded, None if same else source


def parse_decoded(decoded: SourceText, kept_bytes: bytes | None) -> Program:
    """`parse_program` of source decoded by `decode_for_model`."""
    with cyclic_gc_paused(collect_above=_MANY_OBJECTS):
        return build_program(decoded, kept_bytes, parse_source(decoded))


def parse_owned(handed: list[bytes], filename: str = "<string>") -> Program:
    """`parse_program` of the file bytes `handed` holds, taken out of it: when the caller
    keeps no other reference, they are let go of once decoded (unless kept, see
    `decode_for_model`), not held while the model is built and used."""
    decoded, kept = decode_for_model(handed.pop(), filename)
    return parse_decoded(decoded, kept)


def load_program(path: str | Path) -> Program:
    """Read and parse a RAPID file (.mod, .modx, .prg, .sys)."""
    return parse_owned([Path(path).read_bytes()], str(path))
