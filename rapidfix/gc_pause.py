"""Pause Python's cyclic garbage collector while large batches of small objects are made.

Parsing and rewriting a CAM program allocate millions of small acyclic objects;
every generation-2 collection would walk all of them again, which makes large
programs far slower (a third of a rewrite's time). Reference counting still
frees everything as usual, and the collector runs again afterwards.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def cyclic_gc_paused() -> Iterator[None]:
    """Disable the cyclic collector inside the block (restored after, also on errors)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
