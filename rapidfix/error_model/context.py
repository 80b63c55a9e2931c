"""The conditions a pose was commanded under: payload, time, temperature, motion direction.

Effects beyond the per-joint error need to know more than the commanded joints:
compliance needs the payload (and where its centre of gravity sits), thermal drift
the time or temperature, backlash the direction each joint last moved. That
direction is either given per pose (`last_direction`, as a rewrite knows it from
the order the program's moves execute in, 0 where it cannot be known) or taken
from the previous commanded pose of rows executed in order (`q_prev`, as a
measurement set records it). Every field is optional; a missing field means
"unknown" and each effect states what it assumes then.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from rapidfix.exceptions import ModelError


@dataclass(frozen=True)
class Context:
    """Per-pose conditions, each an array of length N or None.

    `q_prev` (N, 6) rad: the pose executed before each row; `last_direction` (N, 6):
    the sign (−1, 0, +1) of each joint's last motion when it arrived, 0 where it is
    not known (effects then take the value midway between the directions);
    `payload_cog_mm` (N, 3): the payload's centre of gravity in the flange frame
    (None: where the model's calibration put it).
    """

    payload_kg: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temp_c: np.ndarray | None = None
    q_prev: np.ndarray | None = None
    last_direction: np.ndarray | None = None
    payload_cog_mm: np.ndarray | None = None

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

    def __len__(self) -> int:
        """Rows described (0 when every field is unknown)."""
        for f in fields(self):
            value = getattr(self, f.name)
            if value is not None:
                return int(np.shape(value)[0])
        return 0

    def check_rows(self, n: int) -> None:
        """ModelError unless every given field has n rows."""
        for f in fields(self):
            value = getattr(self, f.name)
            if value is not None and (np.ndim(value) == 0 or np.shape(value)[0] != n):
                raise ModelError(f"context field {f.name} has shape {np.shape(value)}, "
                                 f"expected {n} rows")

    def take(self, index: np.ndarray | slice) -> Context:
        """The context of a subset of the poses (boolean mask, indices or slice)."""
        values = {
            f.name: (None if getattr(self, f.name) is None else getattr(self, f.name)[index])
            for f in fields(self)
        }
        return Context(**values)

    @classmethod
    def concatenate(cls, first: Context, second: Context) -> Context:
        """The rows of `first` followed by those of `second` (a field known in only one
        of them is unknown in the result)."""
        values = {}
        for f in fields(cls):
            a, b = getattr(first, f.name), getattr(second, f.name)
            values[f.name] = None if a is None or b is None else np.concatenate([a, b])
        return cls(**values)

    def with_q_prev(self, q_prev: np.ndarray | None) -> Context:
        """A copy with another previous-pose array."""
        return replace(self, q_prev=q_prev)

    def direction(self, q_cmd: np.ndarray) -> np.ndarray:
        """Sign (−1, 0, +1) of each joint's last motion, (N, 6); 0 where unknown.

        `last_direction` when given; else from `q_prev` over rows executed in order
        (a joint that did not move keeps the direction of its last motion).
        """
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        if self.last_direction is not None:
            return np.broadcast_to(np.asarray(self.last_direction, dtype=float), q.shape)
        return last_motion_direction(q, self.q_prev)

    def with_directions(self, q_cmd: np.ndarray) -> Context:
        """A copy with `last_direction` fixed from `q_prev` at these joints.

        Rows can then be taken apart (`take`) without losing the direction a joint
        that did not move inherits from the rows before it.
        """
        if self.last_direction is not None or self.q_prev is None:
            return self
        return replace(self, last_direction=last_motion_direction(q_cmd, self.q_prev))


#: joint motions smaller than this (rad) count as "did not move"
STILL_RAD = 1e-9


def last_motion_direction(q: np.ndarray, q_prev: np.ndarray | None) -> np.ndarray:
    """Sign (N, 6) of each joint's last motion over rows executed in order; 0 if unknown."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if q_prev is None:
        return np.zeros_like(q)
    step = q - np.atleast_2d(np.asarray(q_prev, dtype=float))
    sign = np.where(np.abs(step) > STILL_RAD, np.sign(step), 0.0)
    rows = np.arange(q.shape[0])[:, None]
    moved_at = np.maximum.accumulate(np.where(sign != 0, rows, -1), axis=0)
    filled = np.take_along_axis(sign, np.maximum(moved_at, 0), axis=0)
    return np.where(moved_at >= 0, filled, 0.0)


EMPTY = Context()
