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
