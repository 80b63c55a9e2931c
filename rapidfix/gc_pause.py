"""Pause Python's cyclic garbage collector while large batches of small objects are made.

Parsing and rewriting a CAM program allocate millions of small acyclic objects;
every generation-2 collection would walk all of them again, which makes large
programs far slower (a third of a rewrite's time). Reference counting still
frees everything as usual, and the collector runs again afterwards.

Pauses nest: only the outermost one turns the collector back on.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def cyclic_gc_paused(collect_above: int | None = None) -> Iterator[None]:
    """Disable the cyclic collector inside the block (restored after, also on errors).

    With `collect_above`, the outermost pause ends with one full collection when more
    than that many new container objects were made: it moves them straight to the
    oldest generation. Left to itself the collector would walk them three times within
    the caller's next few thousand allocations (as young, middle and old objects);
    this walks them once.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
            if collect_above is not None and gc.get_count()[0] > collect_above:
                gc.collect()
