"""The conditions a pose was commanded under: payload, time, temperature, previous pose.

Effects beyond the per-joint error need to know more than the commanded joints:
compliance needs the payload, thermal drift the time or temperature, backlash the
direction each joint last moved (from the previous commanded pose, i.e. row order).
Every field is optional; a missing field means "unknown" and an effect that needs
it must say so (ModelError) rather than guess.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np


@dataclass(frozen=True)
class Context:
    """Per-pose conditions, each an array of length N (q_prev of shape (N, 6), rad) or None."""

    payload_kg: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temp_c: np.ndarray | None = None
    q_prev: np.ndarray | None = None

    @classmethod
    def from_rows(
        cls,
        q_cmd: np.ndarray,
        *,
        payload_kg: np.ndarray | float | None = None,
        time_s: np.ndarray | None = None,
        temp_c: np.ndarray | None = None,
        q_start: np.ndarray | None = None,
    ) -> Context:
        """Context for poses executed in row order: q_prev is the row before.

        The first row's previous pose is `q_start` (rad) when given, else itself
        (direction unknown, treated as "no motion").
        """
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        n = q.shape[0]
        q_prev = np.empty_like(q)
        q_prev[1:] = q[:-1]
        q_prev[0] = q[0] if q_start is None else np.asarray(q_start, dtype=float)

        def column(value: np.ndarray | float | None) -> np.ndarray | None:
            if value is None:
                return None
            return np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()

        return cls(column(payload_kg), column(time_s), column(temp_c), q_prev)

    def take(self, index: np.ndarray | slice) -> Context:
        """The context of a subset of the poses (boolean mask, indices or slice)."""
        values = {
            f.name: (None if getattr(self, f.name) is None else getattr(self, f.name)[index])
            for f in fields(self)
        }
        return Context(**values)

    def with_q_prev(self, q_prev: np.ndarray | None) -> Context:
        """A copy with another previous-pose array."""
        return replace(self, q_prev=q_prev)

    def direction(self, q_cmd: np.ndarray) -> np.ndarray:
        """Sign (−1, 0, +1) of each joint's last motion, (N, 6); 0 where unknown."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        if self.q_prev is None:
            return np.zeros_like(q)
        return np.sign(q - self.q_prev)


EMPTY = Context()
