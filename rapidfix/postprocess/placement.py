"""Per-move tool and work-object frames, and the TCP <-> flange conversion for a batch.

A robtarget is the TCP pose in a work-object frame. The robot is commanded by its
flange (tool0) pose in the base frame. With a robot-held tool (the usual case):
flange = wobj ∘ target ∘ tool⁻¹. With a stationary tool and a robot-held work
object: flange = tool ∘ target⁻¹ ∘ wobj⁻¹. This module keeps the frames of every
move of a program in arrays so the conversion is one vectorised expression, with
the stationary-tool moves selected by a mask (`rapidfix.kinematics.frames` holds
the same formulas for a single tool and work object).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.kinematics.screws import invert_transform


@dataclass(frozen=True)
class Placement:
    """Frames of N moves: `tool` (N,4,4) TCP in the flange (or in the world when
    stationary), `wobj` (N,4,4) uframe ∘ oframe (in the flange when robot-held),
    `stationary` (N,) bool: stationary tool with a robot-held work object."""

    tool: np.ndarray
    wobj: np.ndarray
    stationary: np.ndarray

    @classmethod
    def identity(cls, n: int) -> Placement:
        """tool0 in wobj0 for n moves."""
        eye = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        return cls(eye, eye.copy(), np.zeros(n, dtype=bool))

    def __len__(self) -> int:
        return int(self.stationary.shape[0])

    def take(self, index: np.ndarray) -> Placement:
        """The frames of a subset of the moves (indices or boolean mask)."""
        return Placement(self.tool[index], self.wobj[index], self.stationary[index])

    def flange(self, target: np.ndarray) -> np.ndarray:
        """Flange poses (N,4,4) in the base frame that put the TCP on `target` (N,4,4)."""
        out = self.wobj @ target @ invert_transform(self.tool)
        fixed = self.stationary
        if fixed.any():
            out[fixed] = (self.tool[fixed] @ invert_transform(target[fixed])
                          @ invert_transform(self.wobj[fixed]))
        return out

    def tcp(self, flange: np.ndarray) -> np.ndarray:
        """TCP poses (N,4,4) in the work-object frame for flange poses (N,4,4) in the base."""
        out = invert_transform(self.wobj) @ flange @ self.tool
        fixed = self.stationary
        if fixed.any():
            out[fixed] = (invert_transform(self.wobj[fixed]) @ invert_transform(flange[fixed])
                          @ self.tool[fixed])
        return out
