"""Collision-free RAPID identifiers (postprocess/naming.py)."""

from __future__ import annotations

import re

from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.postprocess.naming import MAX_IDENTIFIER, NameAllocator, identifiers_in

IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")


@settings(max_examples=60, deadline=None)
@given(
    taken=st.lists(st.from_regex(r"[A-Za-z][A-Za-z0-9_]{0,40}", fullmatch=True), max_size=30),
    stems=st.lists(st.text(min_size=0, max_size=45), min_size=1, max_size=30),
)
def test_allocated_names_are_valid_and_unique(taken, stems):
    names = NameAllocator(taken)
    used = {t.lower() for t in taken}
    for stem in stems:
        name = names.allocate(stem)
        assert IDENT.match(name) and len(name) <= MAX_IDENTIFIER
        assert name.lower() not in used
        used.add(name.lower())


@settings(max_examples=100, deadline=None)
@given(
    words=st.lists(st.from_regex(r"[A-Za-z0-9_]{0,12}", fullmatch=True), max_size=20),
    separators=st.lists(st.sampled_from([" ", "\n", ",", ":=", "(", "9", "_", "!", "é"]),
                        min_size=20, max_size=20),
    stems=st.lists(st.sampled_from(["p1", "P1", "x", "p1_2", "a9", "Ⅷ", ""]), min_size=1,
                   max_size=12),
    prefix=st.sampled_from(["jt_", "ft_", "JT_", "_", ""]),
)
def test_names_avoid_every_identifier_of_the_texts_it_is_given(words, separators, stems, prefix):
    text = "".join(w + s for w, s in zip(words, separators))
    names = NameAllocator(texts=[text])
    used = identifiers_in(text)  # every identifier, the independent way
    for stem in stems:
        name = names.allocate(stem, prefix)
        assert IDENT.match(name) and name.lower() not in used
        used.add(name.lower())
    assert not names.is_free(next(iter(used)))


def test_names_follow_the_robtarget_and_avoid_collisions():
    names = NameAllocator(["JT_P10", "jt_p20"])
    assert names.allocate("p30") == "jt_p30"
    assert names.allocate("p10") == "jt_p10_2"  # case-insensitive collision
    assert names.allocate("p20") == "jt_p20_2"
    assert names.allocate("p20") == "jt_p20_3"
    long = names.allocate("x" * 40)
    assert len(long) == MAX_IDENTIFIER and long.startswith("jt_x")


@settings(max_examples=400, deadline=None)
@given(
    taken=st.lists(st.sampled_from(["jt_p1", "JT_P2", "jt_p1_2", "x", "jt_", "jt_p3_2"]),
                   max_size=4),
    stems=st.lists(st.sampled_from(["p1", "P1", "p2", "p3", "_p4", "a" * 31, "b c", "9",
                                    "p1_2", "P1_3", "a" * 29, "A" * 29, "a" * 27 + "_2"]),
                   max_size=12),
    prefix=st.sampled_from(["jt_", "ft_", "_"]),
)
def test_allocating_many_names_gives_what_allocating_one_by_one_gives(taken, stems, prefix):
    text = " ".join(taken)
    one = NameAllocator(texts=[text])
    many = NameAllocator(texts=[text])
    assert many.allocate_many(stems, prefix) == [one.allocate(s, prefix) for s in stems]
    assert many.allocate("p1", prefix) == one.allocate("p1", prefix)


def _first_free(taken: set[str], base: str) -> str:
    """The definition: `base` cut to 32 characters, else the smallest suffix _2, _3, …
    whose name is free (case-insensitive)."""
    candidate, counter = base[:MAX_IDENTIFIER], 1
    while candidate.lower() in taken:
        counter += 1
        candidate = base[: MAX_IDENTIFIER - len(f"_{counter}")] + f"_{counter}"
    return candidate


@settings(max_examples=200, deadline=None)
@given(steps=st.lists(st.tuples(st.booleans(), st.sampled_from(
    ["p1", "P1", "p1_2", "w" * 29, "w" * 29 + "x", "W" * 40, "w" * 40 + "y",
     "w" * 27 + "_2", "w" * 28 + "_10"])), max_size=40))
def test_each_name_is_the_first_free_one_whatever_was_reserved_between(steps):
    """Many stems that cut to the same 32 characters (long robtarget names) each get
    the smallest free suffix, as the definition says, with names reserved in between."""
    names, taken = NameAllocator(), set()
    for reserve, stem in steps:
        if reserve:
            names.reserve("jt_" + stem)
            taken.add(("jt_" + stem).lower())
        else:
            expected = _first_free(taken, "jt_" + stem)
            assert names.allocate(stem) == expected
            taken.add(expected.lower())


def test_a_thousand_long_names_cut_alike_are_distinct_and_numbered_in_order():
    names = NameAllocator()
    got = [names.allocate("pWeldSeamStartApproachPositionOfTheLeftBracket" + str(k))
           for k in range(1000)]
    assert len({g.lower() for g in got}) == 1000
    assert got[0] == ("jt_pWeldSeamStartApproachPositionOfTheLeftBracket")[:MAX_IDENTIFIER]
    assert got[1:] == [_first_free({g.lower() for g in got[:k]}, "jt_pWeldSeamStartApproach"
                                   "PositionOfTheLeftBracket" + str(k)) for k in range(1, 1000)]


class _CountedSet(set):
    """A set that counts how often it is asked whether it holds a name."""

    looks = 0

    def __contains__(self, key: object) -> bool:
        self.looks += 1
        return super().__contains__(key)


def test_long_names_that_differ_past_the_cut_are_found_in_linear_time():
    """Stems that differ only in what a suffix cuts off (`...Slot00123`, `...Slot00124`)
    share their suffixed names: each is still the first free one, and the allocator asks
    about a bounded number of names per name (it asked about every one taken before:
    three quarters of a 200,000-line rewrite of such targets went there)."""
    stems = [f"pPickPositionStationA_Slot{k:05d}" for k in range(1200)]
    names = NameAllocator()
    names._taken = counted = _CountedSet()
    got = [names.allocate(stem) for stem in stems]
    expected: list[str] = []
    for stem in stems:
        expected.append(_first_free({e.lower() for e in expected}, "jt_" + stem))
    assert got == expected
    assert counted.looks <= 4 * len(stems)
    # the list route: names that fit, each taken already (a program rewritten again)
    stems = [f"pPickPositionStationA_Sl{k:05d}" for k in range(1200)]
    names = NameAllocator(["jt_" + stem for stem in stems])
    names._taken = counted = _CountedSet(names._taken)
    got = names.allocate_many(stems)
    taken = {"jt_" + stem.lower() for stem in stems}
    expected = []
    for stem in stems:
        expected.append(_first_free(taken, "jt_" + stem))
        taken.add(expected[-1].lower())
    assert got == expected
    assert counted.looks <= 6 * len(stems)


# texts of letters (two cases), digits, underscores, separators and characters that are
# not ASCII (one lower-cases to two characters, one to an ASCII letter)
_WORDY = st.text(alphabet="abpAP_19 ,;\n!xéKİ", max_size=80)
_NAMES = st.lists(st.one_of(st.sampled_from(["a", "ab", "p1", "b_1", "x", "ba", "P1", "", "1a",
                                             "é", "k", "i", "a\nb", "ab\n"]),
                            st.from_regex(r"[abp][abp19_]{0,3}", fullmatch=True),
                            st.text(alphabet="abpAP19_é", max_size=4)), max_size=12)


@settings(max_examples=300, deadline=None)
@given(text=_WORDY, names=_NAMES, pieces=st.lists(st.sampled_from(
    ["p1", "1_p1", "ap1", "p1a", "_p1", "9E+09", "é", "p1_2", "AB", "b_1"]), max_size=8))
def test_counting_names_agrees_with_counting_every_word(text, names, pieces):
    """`count_identifiers` finds the names it is asked about (one pattern of them, or
    their first letters and a look-up for many): on random texts it gives the counts of
    the full word-by-word count (words after digits or underscores, words inside words,
    text that is not ASCII, names that are not lower-case identifiers), by both routes
    and with the names of the text's own words added."""
    from rapidfix.postprocess import naming
    from rapidfix.postprocess.naming import count_identifiers, identifier_counts

    text = " ".join([text, *pieces]) if pieces else text
    counts = identifier_counts(text)
    for asked in (names, [*names, *counts]):
        want = {name: counts.get(name, 0) for name in asked}
        assert count_identifiers(text, asked) == want
        limits = naming._PATTERN_NAMES, naming._LATE_NAMES
        try:  # the route for many names (the first letters), on these few, with the
            # names also found after digits or underscores by a pattern or place by place
            for late in (1000, 0):
                naming._PATTERN_NAMES, naming._LATE_NAMES = 0, late
                assert count_identifiers(text, asked) == want
        finally:
            naming._PATTERN_NAMES, naming._LATE_NAMES = limits


def test_counting_names_longer_than_the_pattern_tree_is_exact():
    from rapidfix.postprocess.naming import _TRIE_DEPTH, count_identifiers, identifier_counts

    long = "p" * (_TRIE_DEPTH + 5)
    text = f"{long} 1_{long} a{long} {long}1 {long[:-1]} {long.upper()};p1"
    counts = identifier_counts(text)
    names = [long, long[:-1], long + "1", "p1", "p" * _TRIE_DEPTH]
    assert count_identifiers(text, names) == {name: counts.get(name, 0) for name in names}
    assert counts[long] == 3  # as itself, after '1_', upper-cased
