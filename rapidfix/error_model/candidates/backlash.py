"""Backlash: a joint lags by half its play against the direction it last moved.

Gears and belts have play b: approached from below a joint stops b/2 short,
from above b/2 beyond, so its error flips sign with the direction of its last
motion, Δθ_j = −(b_j / 2) · d_j, d_j = ±1. The direction is the context's
(`Context.direction`): given per pose, or from the row order (the previous pose),
where a joint that did not move keeps the direction of its last motion. Where it
is unknown (before a joint's first motion, or a move whose start is not known
before run time) d_j = 0: the value midway between the directions.
The error depends on θ_j and the context only, so it is compensated joint by joint.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import STILL_RAD, Context, last_motion_direction


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
        return -0.5 * self._p * ctx.direction(q_cmd)

    def play(self) -> np.ndarray:
        """Play (6,) rad of each joint: the motor travel a reversing joint needs before
        it moves. A fractional direction between the old and the new one describes that
        take-up (the joint stands still while it lasts)."""
        return np.abs(self._p)

    def context_fields(self) -> frozenset[str]:
        """What this effect reads from the context."""
        return frozenset({"last_direction"})


__all__ = ["STILL_RAD", "Backlash", "last_motion_direction"]  # the direction rule lives in context
