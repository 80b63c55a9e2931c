"""Every benchmark shape (tests/benchmarks/program_shapes.py), small: the fast route
builds the same syntax tree and the same model as the plain grammar."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
sys.path.insert(0, str(Path(__file__).resolve().parent))  # the comparisons of the fast path tests
from mixed_shapes import mixed_program
from more_shapes import MORE_SHAPES, more_moves
from odd_shapes import ODD_SHAPES, odd_moves
from program_shapes import SHAPES, shape_moves
from test_fastpath import shape
from test_shared_operands import assert_same_model

from rapidfix.rapid.fastpath import fast_parser
from rapidfix.rapid.grammar import rapid_parser
from rapidfix.rapid.source import decode_source

N_MOVES = 45


def _text(name: str) -> str:
    return decode_source(shape_moves(name, N_MOVES).encode(), "t").text


@pytest.mark.parametrize("name", SHAPES)
def test_every_shape_parses_to_the_plain_tree(name):
    text = _text(name)
    assert shape(fast_parser().parse(text)) == shape(rapid_parser().parse(text))


@pytest.mark.parametrize("name", SHAPES)
def test_every_shape_builds_the_plain_model(name):
    program = assert_same_model(_text(name))
    assert len(program.motions) >= N_MOVES * 2 // 3
    assert all(m.target.static for m in program.motions)


@pytest.mark.parametrize("name", MORE_SHAPES)
def test_more_shapes_parse_to_the_plain_tree_and_model(name):
    # layouts the fast path was not tuned on: arrays, nested calls, comments inside
    # statements, MoveAbsJ, TriggL / SearchL, routines with parameters, ...
    text = decode_source(more_moves(name, N_MOVES).encode(), "t").text
    assert shape(fast_parser().parse(text)) == shape(rapid_parser().parse(text))
    program = assert_same_model(text)
    assert len(program.motions) >= N_MOVES // 2


@pytest.mark.parametrize("name", ODD_SHAPES)
def test_odd_shapes_parse_to_the_plain_tree_and_model(name):
    # shapes no benchmark of the fast path uses: a routine every three moves, a hundred
    # tools, several statements on a line, nested IF/TEST/WHILE, arithmetic in targets,
    # many small modules, long non-ASCII comments and long names
    text = decode_source(odd_moves(name, N_MOVES).encode(), "t").text
    assert shape(fast_parser().parse(text)) == shape(rapid_parser().parse(text))
    program = assert_same_model(text)
    assert len(program.motions) >= N_MOVES // 2


@pytest.mark.parametrize("seed", range(12))
def test_random_mixes_of_statements_parse_to_the_plain_tree_and_model(seed):
    # each seed its own mix of a cell's statements, routine length and nesting
    # (mixed_shapes.py): the shapes a generator makes that no person chose
    text = decode_source(mixed_program(seed, 400).encode(), "t").text
    assert shape(fast_parser().parse(text)) == shape(rapid_parser().parse(text))
    assert assert_same_model(text).motions
