"""The effect registry's import list: every module that defines an Effect subclass.

`rapidfix.errors.effect.registered_effects()` imports this module, so an effect
defined in a module listed here can be loaded from a model file by its type name.
Add one import line per new effect module.
"""

import rapidfix.errors.candidates  # noqa: F401
from rapidfix.errors import joint_rbf  # noqa: F401
