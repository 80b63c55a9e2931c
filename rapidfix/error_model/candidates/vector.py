"""A base for effects whose parameters are one named float vector.

Subclasses list `names` (units in the names) and optionally `steps`, a typical
parameter change that moves a point by about a micrometre, which finite-difference
fitters use as their step. Everything else (hyper-parameters) goes in `_state`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rapidfix.error_model.effect import Effect


class VectorEffect(Effect):
    """An effect with a plain named parameter vector, zero by default."""

    def __init__(self, names: Sequence[str], name: str | None = None, *,
                 steps: Sequence[float] | None = None, free: bool = True) -> None:
        super().__init__(name, free=free)
        self._names = tuple(names)
        self._p = np.zeros(len(self._names))
        self.steps = (np.full(len(self._names), 1e-6) if steps is None
                      else np.asarray(steps, dtype=float))

    @property
    def param_names(self) -> tuple[str, ...]:
        """Names of the parameter vector's entries."""
        return self._names

    def params(self) -> np.ndarray:
        """A copy of the parameter vector."""
        return self._p.copy()

    def set_fitted(self, p: np.ndarray) -> None:
        """Write the parameter vector."""
        self._p = self._check_length(p).copy()

    def value(self, key: str) -> float:
        """One parameter by name."""
        return float(self._p[self._names.index(key)])

    def _state(self) -> dict[str, Any]:
        return {}
