"""Every benchmark shape (tests/benchmarks/program_shapes.py), small: a rewrite through
the fast route (fast terminals, bulk read-back) writes the same bytes as one through
the plain grammar alone."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from mixed_shapes import mixed_program
from more_shapes import MORE_SHAPES, more_moves
from odd_shapes import ODD_SHAPES, odd_moves
from program_shapes import SHAPES, shape_moves

from rapidfix.postprocess.rewrite import RewriteOptions, rewrite_source
from rapidfix.rapid import parse, readback
from rapidfix.rapid.fastpath import NotFast
from rapidfix.rapid.grammar import rapid_parser

N_MOVES = 45


class _Refuse:
    """A run parser that never reads a program in bulk (the general read-back)."""

    def parse(self, text: str):
        raise NotFast(text[:10])


def _plain_parse_text(text: str):
    return rapid_parser().parse(text)


_ALL = {**{s: shape_moves for s in SHAPES}, **{s: more_moves for s in MORE_SHAPES},
        **{s: odd_moves for s in ODD_SHAPES}}


@pytest.mark.parametrize("name", list(_ALL))
def test_every_shape_rewrites_as_through_the_plain_grammar(name, comp, monkeypatch):
    # the benchmark shapes, and the more and odd shapes no fast path was tuned on
    data = _ALL[name](name, N_MOVES).encode()
    filename = "t.prg" if name in ("prg", "modules") else "t.mod"
    # a robot on a track: told its axis carries nothing, so that its moves are compensated
    options = RewriteOptions(static_external_axes=name == "track")
    fast = rewrite_source(data, filename, comp, options)
    with monkeypatch.context() as patch:
        patch.setattr(parse, "parse_text", _plain_parse_text)
        patch.setattr(readback, "run_parser", _Refuse)
        plain = rewrite_source(data, filename, comp, options)
    assert fast.moves_compensated == plain.moves_compensated
    assert fast.moves_compensated > 0 or name == "absj"  # MoveAbsJ only: left as written
    assert fast.skipped == plain.skipped and fast.warnings == plain.warnings
    if name in SHAPES:
        assert not fast.skipped
    assert fast.data == plain.data


@pytest.mark.parametrize("seed", range(6))
def test_random_mixes_of_statements_rewrite_as_through_the_plain_grammar(seed, comp,
                                                                          monkeypatch):
    # a seed's own mix of a cell's statements (mixed_shapes.py), 1,500 lines: past the
    # warm-up, so the fast route reads it (the process's first characters are the plain
    # grammar's), and the reader with every loose form in the mix
    data = mixed_program(seed, 1500).encode()
    monkeypatch.setattr(parse, "_read_plain", parse.WARM_UP_CHARS)
    fast = rewrite_source(data, "t.mod", comp, RewriteOptions())
    with monkeypatch.context() as patch:
        patch.setattr(parse, "parse_text", _plain_parse_text)
        patch.setattr(readback, "run_parser", _Refuse)
        plain = rewrite_source(data, "t.mod", comp, RewriteOptions())
    assert fast.moves_compensated == plain.moves_compensated > 0
    assert fast.skipped == plain.skipped and fast.warnings == plain.warnings
    assert fast.data == plain.data
