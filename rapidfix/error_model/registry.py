"""The effect registry: every module that defines an Effect subclass, imported here.

An effect defined in a module listed here can be loaded from a model file by its type
name (`effect_from_dict`). Add one import line per new effect module.
"""

from __future__ import annotations

from typing import Any

import rapidfix.error_model.candidates  # noqa: F401  (defines every candidate effect)
from rapidfix.error_model import joint_rbf  # noqa: F401  (defines JointRBF)
from rapidfix.error_model.effect import Effect, build_effect, defined_effects


def registered_effects() -> dict[str, type[Effect]]:
    """Type name → class of every registered effect."""
    return defined_effects()


def effect_from_dict(data: dict[str, Any], where: str = "effect") -> Effect:
    """Rebuild an effect from `to_dict()` output; ModelError names the bad key."""
    return build_effect(data, registered_effects(), where)
