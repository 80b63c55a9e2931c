"""Backlash: a joint lags by half its play against the direction it last moved.

Gears and belts have play b: approached from below a joint stops b/2 short,
from above b/2 beyond, so its error flips sign with the direction of its last
motion, Δθ_j = −(b_j / 2) · d_j, d_j = ±1. The direction comes from the row
order (the context's previous pose): rows are taken as executed in order, and a
joint that did not move keeps the direction of its last motion. Before its
first motion a joint's direction is unknown and it contributes nothing.
The error depends on θ_j and the context only, so it is compensated joint by joint.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rapidfix.errors.candidates.vector import VectorEffect
from rapidfix.errors.context import Context

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


class Backlash(VectorEffect):
    """Δθ_j = −(b_j / 2) · direction_j for all six joints (b in rad)."""

    type_name: ClassVar[str] = "backlash"
    separable: ClassVar[bool] = True
    adds_joint_delta: ClassVar[bool] = True

    def __init__(self, name: str | None = None, *, free: bool = True) -> None:
        super().__init__([f"j{j + 1}_play_rad" for j in range(6)], name, steps=[2e-6] * 6,
                         free=free)

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Half the play against the last motion, per joint."""
        direction = last_motion_direction(q_cmd, ctx.q_prev)
        return -0.5 * self._p * direction
