"""The one name-lookup (scope) rule of RAPID data, shared by the program model
(`model_builder`, `Program.declaration`) and the read-back (`readback`).

A name is looked up in the innermost scope that declares it: a routine's data, then
its module's, then the task's global data; the first declaration of a name in a scope
is the one that counts. Callers pass their scopes as mappings from lower-case names.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TypeVar

T = TypeVar("T")


def find_visible(key: str, *scopes: Mapping[str, T]) -> T | None:
    """What `key` (lower case) names in the innermost of `scopes` that declares it, or
    None when none does."""
    for scope in scopes:
        found = scope.get(key)
        if found is not None:
            return found
    return None


def visible_names(*scopes: Mapping[str, T]) -> dict[str, T]:
    """Every name `find_visible` sees in `scopes` (innermost first), as one dict: many
    names are then looked up at list speed, with the same answers."""
    merged: dict[str, T] = {}
    for scope in reversed(scopes):
        merged.update(scope)
    return merged
