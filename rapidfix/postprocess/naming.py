"""Collision-free RAPID identifiers for the data the post-processor declares.

RAPID identifiers are case-insensitive, start with a letter, hold letters, digits
and underscores, and are at most 32 characters long. A new jointtarget is named
after the robtarget it replaces (`p10` -> `jt_p10`); when that name is already
taken anywhere in the program (any identifier at all, keywords and routine names
included) a numeric suffix makes it unique, shortening the stem to stay within
32 characters.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable
from itertools import repeat

MAX_IDENTIFIER = 32
#: an identifier-shaped word of RAPID text (keywords included)
IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_LOWER_IDENTIFIER = re.compile(r"[a-z][a-z0-9_]*")
_BAD = re.compile(r"[^A-Za-z0-9_]+")
_WORD = re.compile(r"[a-z0-9_]*")
# Stems joined by newlines, each an identifier that needs no cleaning: a letter first,
# no '_' at either end (what `allocate` would strip)
_PLAIN_STEMS = re.compile(r"[A-Za-z](?:[A-Za-z0-9_]*[A-Za-z0-9])?"
                          r"(?:\n[A-Za-z](?:[A-Za-z0-9_]*[A-Za-z0-9])?)*")


def identifiers_in(text: str) -> set[str]:
    """Every identifier-shaped word of a RAPID text, lower-cased (a superset is harmless)."""
    if text.isascii():  # lower-casing first is quicker and, for ASCII, the same
        return set(IDENTIFIER.findall(text.lower()))
    return {word.lower() for word in IDENTIFIER.findall(text)}


def identifier_counts(text: str) -> Counter[str]:
    """How often each identifier-shaped word occurs in a RAPID text, lower-cased."""
    if text.isascii():  # lower-casing first is quicker and, for ASCII, the same
        return Counter(_LOWER_IDENTIFIER.findall(text.lower()))
    return Counter(map(str.lower, IDENTIFIER.findall(text)))


#: names up to this many are found by one pattern built from them (compiling it costs
#: about 15 µs a name); more are found by their first letters and looked up
_PATTERN_NAMES = 1000
#: the names found after digits or underscores by the first letters' route: up to this
#: many by one pattern of them, more place by place
_LATE_NAMES = 1000
#: longer names stand in that pattern as plain alternatives (bounded nesting)
_TRIE_DEPTH = 64
_NAME_SHAPE = re.compile(r"[a-z][a-z0-9_]*")
_NAME_LINES = re.compile(r"[a-z][a-z0-9_]*(?:\n[a-z][a-z0-9_]*)*")  # names joined by newlines
_NOT_LETTERS = frozenset("0123456789_")  # word characters other than letters
_LETTERS = frozenset("abcdefghijklmnopqrstuvwxyz")


def _ascii_lowered(text: str) -> str:
    """The text lower-cased in ASCII, every other character one '?' (not a word character
    either): the same words at the same offsets (a non-ASCII character may lower-case to
    two, or to an ASCII letter, as the Kelvin sign does)."""
    if text.isascii():
        return text.lower()
    return text.encode("ascii", "replace").decode("ascii").lower()


def _trie(names: Iterable[str]) -> str:
    """A regular expression matching exactly `names` (lower-case words), shaped as their
    prefix tree so that the engine follows one branch per character read."""
    root: dict = {}
    for name in names:
        node = root
        for char in name:
            node = node.setdefault(char, {})
        node[""] = True

    def branch(node: dict) -> str:
        ends = "" in node
        alternatives = [char + branch(child) for char, child in sorted(node.items()) if char]
        if not alternatives:
            return ""
        body = (alternatives[0] if len(alternatives) == 1 and not ends
                else "(?:" + "|".join(alternatives) + ")")
        return body + "?" if ends else body

    return branch(root)


def _starts_word(lowered: str, start: int) -> bool:
    """True when a word of `IDENTIFIER.findall` starts at `start` (a letter): no letter in
    the run of word characters before it."""
    back = start - 1
    while back >= 0 and lowered[back] in _NOT_LETTERS:
        back -= 1
    return back < 0 or lowered[back] not in _LETTERS


def _pattern_counts(lowered: str, names: set[str]) -> dict[str, int]:
    """How often each of `names` (lower-case identifier-shaped words) stands as a word of
    `lowered`: one pattern of them all finds each place a name ends a run of word
    characters; a place counts when no letter precedes it in that run."""
    short = [name for name in names if len(name) <= _TRIE_DEPTH]
    long = [name for name in names if len(name) > _TRIE_DEPTH]
    pattern = "|".join(filter(None, [_trie(short), *long]))
    counts = dict.fromkeys(names, 0)
    for match in re.finditer(f"(?:{pattern})(?![a-z0-9_])", lowered):
        if _starts_word(lowered, match.start()):
            counts[match.group()] += 1
    return counts


def _first_letter_counts(lowered: str, names: set[str]) -> dict[str, int]:
    """`_pattern_counts` for many names: every word starting with one of the names' first
    letters after a character that is not a word character (or at the text's start) is
    counted; the names that also follow digits or underscores somewhere (`1_p1` holds
    `p1`) are then counted in full by `_pattern_counts` or, when there are many, their
    places after digits or underscores added one by one."""
    letters = "".join(sorted({name[0] for name in names}))
    # the first letter, then a look back at it and the character before (a pattern
    # beginning with a class of letters is searched for quickly)
    words = Counter(re.findall(f"[{letters}](?<![a-z0-9_].)[a-z0-9_]*", lowered))
    counts = dict(zip(names, map(words.get, names, repeat(0))))
    after = f"[{letters}](?<=[0-9_].)[a-z0-9_]*"  # after a digit or an underscore
    late = names.intersection(re.findall(after, lowered))
    if not late:
        return counts
    if len(late) <= _LATE_NAMES:
        counts.update(_pattern_counts(lowered, late))
        return counts
    # many (a program already compensated holds `jt_p1` beside `p1`): each place is
    # looked at, too many names for one pattern of them
    for match in re.finditer(after, lowered):
        word = match.group()
        if word in late and _starts_word(lowered, match.start()):
            counts[word] += 1
    return counts


def count_identifiers(text: str, names: Iterable[str]) -> dict[str, int]:
    """`identifier_counts(text)[name]` for the lower-case `names` only: the names are
    searched for, not every word of the text counted (a large program holds millions).

    A place where the name stands counts when a word of `IDENTIFIER.findall` starts
    there (a letter, with no letter in the run of word characters before it) and ends
    there (no word character after it). A name that is not a lower-case identifier
    counts 0.
    """
    wanted = set(names)
    joined = "\n".join(wanted)
    if joined.count("\n") == len(wanted) - 1 and _NAME_LINES.fullmatch(joined):
        words = wanted  # all identifier-shaped (the usual case): checked at once
    else:
        words = {name for name in wanted if _NAME_SHAPE.fullmatch(name)}
    if not words:
        return dict.fromkeys(wanted, 0)
    lowered = _ascii_lowered(text)
    counts = (_pattern_counts(lowered, words) if len(words) <= _PATTERN_NAMES
              else _first_letter_counts(lowered, words))
    return counts if words is wanted else {name: counts.get(name, 0) for name in wanted}


class NameAllocator:
    """Hands out identifiers that collide with nothing already used, case-insensitively.

    `taken` names are used; so is every identifier in `texts` (program texts). A
    text is not split into all its words: the names handed out all begin with their
    prefix, so the first time a prefix is used every word beginning with it is
    looked up (a plain search; a CAM program holds none).
    """

    def __init__(self, taken: Iterable[str] = (), texts: Iterable[str] = ()) -> None:
        self._taken = {name.lower() for name in taken}
        # the texts as given, lowered only while one is searched: a lowered copy kept for
        # the allocator's life is a million-line program's size once more
        self._texts = list(texts)
        self._heads: set[str] = set()
        #: truncated base -> the suffix counter of the name last handed out for it: the
        #: free counters of a base only grow (names are never released), so the next
        #: search starts there
        self._counter: dict[str, int] = {}
        #: (the text a suffix of so many digits follows, the digits) -> a counter below
        #: which every suffix of that many digits is taken: long stems that differ only
        #: past what a suffix cuts off (`...Slot00123`, `...Slot00124`) share these
        #: names, and each would otherwise try every one taken before (`_free_from`)
        self._families: dict[tuple[str, int], int] = {}

    def _scan(self, head: str) -> None:
        """Take every word of the texts that begins with `head` (lower case): a superset
        of the identifiers that do."""
        if head in self._heads:
            return
        self._heads.add(head)
        taken = self._taken
        for text in map(str.lower, self._texts):
            pos = text.find(head)
            while pos >= 0:
                taken.add(_WORD.match(text, pos).group())
                pos = text.find(head, pos + 1)

    def reserve(self, name: str) -> None:
        """Mark a name as used (it will never be handed out)."""
        self._taken.add(name.lower())

    def is_free(self, name: str) -> bool:
        """True when `name` is not used yet."""
        key = name.lower()
        self._scan(key)
        return key not in self._taken

    def allocate_many(self, stems: list[str], prefix: str = "jt_") -> list[str]:
        """`allocate` for each stem in turn: at list speed when every stem is a plain
        identifier and every name new and distinct, by a lean loop when some are not,
        one by one through `allocate` otherwise."""
        if not stems:
            return []
        joined = "\n".join(stems)
        simple = (prefix[:1].isalpha() and prefix.isascii() and joined.isascii()
                  and joined.count("\n") == len(stems) - 1
                  and _PLAIN_STEMS.fullmatch(joined) is not None
                  and max(map(len, stems)) + len(prefix) <= MAX_IDENTIFIER)
        if simple:
            head = prefix[:16].lower()
            if head not in self._heads:
                self._scan(head)
            names = [prefix + s for s in stems]
            keys = (prefix + joined.replace("\n", "\n" + prefix)).lower().split("\n")
            taken = self._taken
            if len(set(keys)) == len(keys) and taken.isdisjoint(keys):
                taken.update(keys)
                return names
            # one by one, as `allocate` does for a stem that needs no cleaning; the
            # suffixes a name has tried stay taken, so its next use starts after them
            tried: dict[str, int] = {}
            for n, key in enumerate(keys):
                if key in taken:
                    base = names[n]
                    counter = self._free_from(base, tried.get(key, 1) + 1)
                    suffix = f"_{counter}"
                    names[n] = base[: MAX_IDENTIFIER - len(suffix)] + suffix
                    tried[key] = counter
                    key = names[n].lower()
                taken.add(key)
            return names
        return [self.allocate(s, prefix) for s in stems]

    def allocate(self, stem: str, prefix: str = "jt_") -> str:
        """A fresh identifier `prefix + stem`, suffixed `_2`, `_3`, … when taken."""
        # an identifier-shaped stem (the usual case) needs no cleaning
        clean = stem if stem.isascii() and stem.isidentifier() else _BAD.sub("_", stem)
        base = prefix + (clean.strip("_") or "target")
        head = len(prefix)  # every candidate begins with the prefix (or 't' and the prefix)
        if not base[0].isalpha():
            base = "t" + base
            head += 1
        head_key = base[: min(max(head, 1), 16)].lower()  # kept by every truncated candidate
        if head_key not in self._heads:
            self._scan(head_key)
        candidate = base[:MAX_IDENTIFIER]
        key = candidate.lower()
        taken = self._taken
        memo = key  # every candidate of `base` is made from these characters
        counter = self._counter.get(memo, 1)
        if counter > 1 or key in taken:
            counter = self._free_from(base, max(counter, 2))
            suffix = f"_{counter}"
            candidate = base[: MAX_IDENTIFIER - len(suffix)] + suffix
            key = candidate.lower()
        taken.add(key)
        self._counter[memo] = counter
        return candidate

    def _free_from(self, base: str, counter: int) -> int:
        """The smallest suffix counter from `counter` (2 or more) whose name, `base` (an
        ASCII identifier) cut to leave room for `_<counter>`, is free; the caller takes
        that name. What it finds taken is remembered per family (`_families`): the
        names it passed over stay taken, as does the one the caller takes."""
        taken, families = self._taken, self._families
        lower = base.lower()
        while True:
            digits = len(str(counter))
            top = 10 ** digits  # the first counter with more digits
            family = (lower[: MAX_IDENTIFIER - 1 - digits], digits)
            known = families.get(family, 2 if digits == 1 else top // 10)
            start = counter = max(counter, known)
            head = family[0] + "_"
            while counter < top and head + str(counter) in taken:
                counter += 1
            if start == known:  # taken from the family's first counter up to here
                families[family] = counter + 1 if counter < top else top
            if counter < top:
                return counter
