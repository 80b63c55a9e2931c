"""Typed views of values: the quick shape test agrees with the full conversion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.rapid.values import ValueShapeError, fits_type, typed_value

leaf = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.sampled_from(["", "x"]),
    st.integers(-3, 3),
)
numbers = st.floats(-1e3, 1e3) | st.sampled_from([9e9, -0.0, math.inf, math.nan])


def group(size: int) -> st.SearchStrategy:
    """Mostly a tuple of `size` numbers; else one with a wrong item, length or type."""
    exact = st.tuples(*[numbers] * size)
    return st.one_of(
        exact, exact, exact,
        st.integers(0, size - 1).flatmap(
            lambda i: st.tuples(*[numbers] * i, leaf, *[numbers] * (size - 1 - i))),
        st.lists(numbers, min_size=size - 1, max_size=size + 1).map(tuple),
        leaf,
    )


SHAPES = {  # a type and values of about its shape
    "robtarget": st.tuples(group(3), group(4), group(4), group(6)),
    "jointtarget": st.tuples(group(6), group(6)),
    "tooldata": st.tuples(st.booleans(), st.tuples(group(3), group(4)), group(6)),
    "speeddata": group(4),
    "num": leaf,
}
values = st.one_of(
    *SHAPES.values(),
    st.lists(group(4), max_size=5).map(tuple),
)


def converts(type_name: str, value: object) -> bool:
    try:
        typed_value(type_name, value)
    except ValueShapeError:
        return False
    return True


@settings(max_examples=300, deadline=None)
@given(st.sampled_from([*SHAPES, "RobTarget", "pos"]), values)
def test_the_quick_test_never_accepts_what_the_conversion_refuses(type_name, value):
    if fits_type(type_name, value):
        assert converts(type_name, value)


@pytest.mark.parametrize("type_name", sorted(SHAPES))
@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_the_quick_test_agrees_on_values_of_about_the_right_shape(type_name, data):
    value = data.draw(SHAPES[type_name])
    if fits_type(type_name, value):
        assert converts(type_name, value)


@pytest.mark.parametrize("type_name,value", [
    ("robtarget", ((1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0), (0.0, -1.0, 2.0, 0.0), (9e9,) * 6)),
    ("ROBTARGET", ((1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0), (0.0, -1.0, 2.0, 0.0), (9e9,) * 6)),
    ("jointtarget", ((0.0, -20.0, 30.5, 0.0, 80.0, -10.0), (9e9,) * 6)),
    ("num", 5.0),
])
def test_the_quick_test_accepts_well_formed_bulk_data(type_name, value):
    assert fits_type(type_name, value) and converts(type_name, value)


@pytest.mark.parametrize("conf", [math.inf, -math.inf, math.nan])
def test_confdata_that_is_not_a_whole_number_is_a_shape_error(conf):
    value = ((1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0), (0.0, conf, 0.0, 0.0), (9e9,) * 6)
    assert not fits_type("robtarget", value)
    with pytest.raises(ValueShapeError, match="confdata"):
        typed_value("robtarget", value)


def test_a_shared_rest_is_judged_once_and_each_position_still_checked():
    rot, conf, extax = (1.0, 0.0, 0.0, 0.0), (0.0, -1.0, 2.0, 0.0), (9e9,) * 6
    assert fits_type("robtarget", ((1.0, 2.0, 3.0), rot, conf, extax))
    assert fits_type("robtarget", ((4.0, 5.0, 6.0), rot, conf, extax))  # the kept verdict
    assert not fits_type("robtarget", ((4.0, 5.0), rot, conf, extax))
    assert not fits_type("robtarget", ((4.0, 5.0, "x"), rot, conf, extax))
    # the same orientation tuple with other confdata is judged on its own
    assert not fits_type("robtarget", ((1.0, 2.0, 3.0), rot, (0.0, math.nan, 0.0, 0.0), extax))
    assert not fits_type("robtarget", ((1.0, 2.0, 3.0), rot, conf, (9e9,) * 5))
    # a position of float's subclasses (numpy's) fits as before; a bool or int does not
    assert fits_type("robtarget", ((np.float64(1.0), 2.0, np.float64(3.0)), rot, conf, extax))
    assert not fits_type("robtarget", ((True, 2.0, 3.0), rot, conf, extax))
    assert not fits_type("robtarget", ((1, 2.0, 3.0), rot, conf, extax))
