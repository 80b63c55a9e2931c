"""The written-out emission forms against the general edits and format functions
(postprocess/emission_forms.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.rapid import load_program

joint_values = st.one_of(
    st.floats(-400, 400, allow_nan=False),
    st.sampled_from([0.0, -0.0, -4e-7, 4e-7, -5e-7, 5e-7, 1e-6, -1e-6, 10.0, -100.0, 12.5,
                     0.0000105, 359.9999996, -179.9999995, 100.0, -1000.0, 1e7, 20.5, -0.1,
                     1e8, -3e9]),
)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(*[joint_values] * 6), min_size=1, max_size=8),
       st.sampled_from([9e9, 0.0, -12.25]))
def test_jointtarget_literals_are_what_format_jointtarget_writes(rows, ext):
    from rapidfix.postprocess.emission_forms import jointtarget_literals
    from rapidfix.rapid.format import format_jointtarget

    q = np.array(rows)
    extax = np.full((len(rows), 6), ext)
    got = jointtarget_literals(q, extax)
    assert got == [format_jointtarget(r, e) for r, e in zip(q.tolist(), extax.tolist())]


def test_the_written_out_moveabsj_is_the_statement_the_general_edits_make():
    from rapidfix.postprocess.emission_forms import joint_edits, joint_statement, statement_variant
    from rapidfix.postprocess.resolve import Declarations, resolve

    samples = Path(__file__).resolve().parents[2] / "samples"
    checked = 0
    for path in sorted(samples.glob("*.mod")):
        program = load_program(path)
        sites, _ = resolve(program, Declarations([]), "jointtargets")
        for site in sites:
            if site.kind in "LJC" and site.targets:
                general = statement_variant(program, site.motion, joint_edits(site, "jt_x"))
                assert joint_statement(program.text, site, "jt_x") == general
                checked += 1
    assert checked > 20


@settings(max_examples=200, deadline=None)
@given(st.from_regex(r"jt_[A-Za-z0-9_]{0,29}", fullmatch=True),
       st.lists(st.tuples(*[joint_values] * 6), min_size=1, max_size=1))
def test_the_written_out_declaration_is_what_format_declaration_writes(name, rows):
    from rapidfix.postprocess.emission_forms import jointtarget_declaration, jointtarget_literals
    from rapidfix.rapid import parse_program
    from rapidfix.rapid.format import format_declaration

    literal = jointtarget_literals(np.array(rows), np.full((1, 6), 9e9))[0]
    text = jointtarget_declaration(name, literal)
    assert text == format_declaration("CONST", "jointtarget", name, literal)
    program = parse_program(f"MODULE M\n  {text}\nENDMODULE\n")
    assert program.declarations[0].name == name


@settings(max_examples=50, deadline=None)
@given(st.from_regex(r"ft_[A-Za-z0-9_]{0,29}", fullmatch=True),
       st.tuples(st.floats(-3000, 3000), st.floats(-3000, 3000), st.floats(-3000, 3000)))
def test_the_written_out_robtarget_declaration_is_what_format_declaration_writes(name, xyz):
    from rapidfix.postprocess.emission_forms import robtarget_declaration
    from rapidfix.rapid import parse_program
    from rapidfix.rapid.format import format_declaration, format_robtarget

    literal = format_robtarget(xyz, (1, 0, 0, 0), (0, -1, 0, 1), [9e9] * 6)
    text = robtarget_declaration(name, literal)
    assert text == format_declaration("CONST", "robtarget", name, literal)
    program = parse_program(f"MODULE M\n  {text}\nENDMODULE\n")
    assert program.declarations[0].name == name
    assert program.declarations[0].type_key == "robtarget"


def test_jointtarget_literals_of_a_large_block_round_as_python_formats_each_number():
    """The digits built in numpy for a whole block: halves exactly between two millionths
    (k/128), numbers a rounding error away from a half, every magnitude below 1e8,
    negatives that round to zero."""
    from rapidfix.postprocess.emission_forms import jointtarget_literals
    from rapidfix.rapid.format import format_jointtarget

    rng = np.random.default_rng(7)
    exact_halves = rng.integers(-10**6, 10**6, 600) / 128.0
    near_halves = (rng.integers(-10**9, 10**9, 600) + 0.5) / 1e6
    near_halves = near_halves + rng.choice([-1, 0, 1], 600) * np.spacing(near_halves)
    magnitudes = rng.uniform(-1, 1, 600) * 10.0 ** rng.integers(-8, 8, 600)
    micro = rng.integers(-10**7, 10**7, 600) / 1e6
    tiny = rng.uniform(-6e-7, 6e-7, 600)
    large = rng.uniform(-1e8, 1e8, 600)
    q = np.concatenate([exact_halves, near_halves, magnitudes, micro, tiny, large]).reshape(-1, 6)
    q = q[rng.permutation(len(q))]
    extax = np.where(rng.random((len(q), 1)) < 0.5, 9e9, rng.uniform(-500, 500, (len(q), 6)))
    got = jointtarget_literals(q, extax)
    assert got == [format_jointtarget(r, e) for r, e in zip(q.tolist(), extax.tolist())]


def test_jointtarget_literals_built_in_blocks_of_rows_are_those_of_one_block(monkeypatch):
    """The literals are built `_BLOCK_ROWS` rows at a time (the numpy temporaries of a
    million-line program at once took ~1 KB a row): blocks that do not divide the rows,
    with each row's own external axes, give what `format_jointtarget` writes."""
    import rapidfix.postprocess.emission_forms as forms
    from rapidfix.rapid.format import format_jointtarget

    rng = np.random.default_rng(3)
    q = np.concatenate([rng.uniform(-400, 400, (27, 6)).round(3), rng.uniform(-400, 400, (26, 6))])
    extax = np.where(rng.random((53, 1)) < 0.5, 9e9, rng.uniform(-50, 50, (53, 6)))
    want = [format_jointtarget(r, e) for r, e in zip(q.tolist(), extax.tolist())]
    for rows in (1, 7, 53, 64):
        monkeypatch.setattr(forms, "_BLOCK_ROWS", rows)
        assert forms.jointtarget_literals(q, extax) == want


position_values = st.one_of(
    st.floats(-5000, 5000, allow_nan=False),
    st.sampled_from([0.0, -0.0, 5e-5, -5e-5, 0.00015, 2.00005, -0.00001, 1e-10, 12.5,
                     1e7, -99999999.99999, 1e8, 3e9]),
)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(*[position_values] * 3), min_size=1, max_size=8),
       st.sampled_from([4, 6, 9]))
def test_number_rows_are_what_format_num_writes(rows, decimals):
    from rapidfix.postprocess.emission_forms import number_rows
    from rapidfix.rapid.format import format_num

    x = np.array(rows)
    got = number_rows(x, decimals)
    if got is None:  # a number format_num writes with an exponent, or 1e8 after rounding
        assert any(abs(round(v, decimals)) >= 1e8 for row in rows for v in row)
        return
    assert got == [",".join(format_num(v, decimals) for v in row) for row in rows]


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.tuples(*[position_values] * 3),
                          st.floats(0, 2 * np.pi), st.floats(-1, 1), st.floats(0, 2 * np.pi),
                          st.tuples(*[st.integers(-4, 4)] * 3), st.integers(0, 7),
                          st.sampled_from([9e9, 0.0, -12.25, 1e-5])),
                min_size=1, max_size=6))
def test_robtarget_literals_are_what_format_robtarget_writes(rows):
    from scipy.spatial.transform import Rotation

    from rapidfix.kinematics import pose_to_pos_quat
    from rapidfix.postprocess.emission_forms import robtarget_literals
    from rapidfix.rapid.format import format_robtarget

    k = len(rows)
    tcp = np.tile(np.eye(4), (k, 1, 1))
    tcp[:, :3, 3] = [r[0] for r in rows]
    tcp[:, :3, :3] = Rotation.from_euler(
        "zyz", [(a, np.arccos(c), b) for _, a, c, b, *_ in rows]).as_matrix()
    conf = np.array([(*r[4], r[5]) for r in rows])
    extax = np.array([[r[6]] * 3 + [9e9] * 3 for r in rows])
    pos, quat = pose_to_pos_quat(tcp)
    want = [format_robtarget(p, q, c, e) for p, q, c, e in
            zip(pos.tolist(), quat.tolist(), conf.tolist(), extax.tolist())]
    assert robtarget_literals(tcp, conf, extax) == want


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.integers(-5, 5), min_size=4, max_size=4), min_size=1, max_size=40),
       st.sampled_from([1, 10**6, 2**40, 2**58, 2**60]), st.sampled_from(["i8", "i4", "f8"]))
def test_each_distinct_row_written_once_gives_each_row_its_text(rows, scale, dtype):
    """`_distinct_texts`: the text of each row, whether the rows are integers (confdata,
    found distinct as one number a row; ranges too wide for one number are sorted as
    rows) or not."""
    from rapidfix.postprocess.emission_forms import _distinct_texts

    array = np.array(rows, dtype=np.int64)
    array[:, 0] *= scale if dtype != "i4" else 1
    array = array.astype(dtype)

    def text(row):
        return "[" + ",".join(map(str, row)) + "]"

    assert _distinct_texts(array, text) == [text(row) for row in array.tolist()]
