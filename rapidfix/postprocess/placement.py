"""Per-move tool and work-object frames, and the TCP <-> flange conversion for a batch.

A robtarget is the TCP pose in a work-object frame. The robot is commanded by its
flange (tool0) pose in the base frame. With a robot-held tool (the usual case):
flange = wobj ∘ target ∘ tool⁻¹. With a stationary tool and a robot-held work
object: flange = tool ∘ target⁻¹ ∘ wobj⁻¹. This module keeps the frames of every
move of a program in arrays so the conversion is one vectorised expression, with
the stationary-tool moves selected by a mask (`rapidfix.kinematics.frames` holds
the same formulas for a single tool and work object).

Most programs use one tool and one work object for every move: such frames are
one (4,4) matrix broadcast to (N,4,4) (`shared`), which costs no memory and is
inverted once; subsets of them stay broadcast.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rapidfix.kinematics import invert_transform


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
        stationary = self.stationary[index]
        n = stationary.shape[0]
        return Placement(_rows(self.tool, index, n), _rows(self.wobj, index, n), stationary)

    def flange(self, target: np.ndarray) -> np.ndarray:
        """Flange poses (N,4,4) in the base frame that put the TCP on `target` (N,4,4)."""
        out = self.wobj @ target @ _inverse(self.tool)
        fixed = self.stationary
        if fixed.any():
            out[fixed] = (self.tool[fixed] @ invert_transform(target[fixed])
                          @ invert_transform(self.wobj[fixed]))
        return out

    def tcp(self, flange: np.ndarray) -> np.ndarray:
        """TCP poses (N,4,4) in the work-object frame for flange poses (N,4,4) in the base."""
        out = _inverse(self.wobj) @ flange @ self.tool
        fixed = self.stationary
        if fixed.any():
            out[fixed] = (invert_transform(self.wobj[fixed]) @ invert_transform(flange[fixed])
                          @ self.tool[fixed])
        return out

    def tcp_positions(self, flange: np.ndarray) -> np.ndarray:
        """`tcp(flange)[:, :3, 3]` (N,3), the TCP's positions in the work-object frame,
        without the whole poses (all the path check and the predicted errors read):
        wobj_R^T (R_flange t_tool + p_flange − wobj_p), the same to rounding."""
        rot = flange[:, :3, :3]
        if _is_shared(self.tool):
            point = rot @ self.tool[0, :3, 3]
        else:
            point = np.einsum("nij,nj->ni", rot, self.tool[:, :3, 3])
        point += flange[:, :3, 3]
        if _is_shared(self.wobj):
            out = (point - self.wobj[0, :3, 3]) @ self.wobj[0, :3, :3]
        else:
            out = np.einsum("nji,nj->ni", self.wobj[:, :3, :3], point - self.wobj[:, :3, 3])
        fixed = self.stationary
        if fixed.any():  # the robot holds the work: its own formula, row by row as tcp's
            out[fixed] = self.take(fixed).tcp(flange[fixed])[:, :3, 3]
        return out


def shared(frame: np.ndarray, n: int) -> np.ndarray:
    """One frame (4,4) as the read-only (n,4,4) frames of n moves, without copies."""
    return np.broadcast_to(np.asarray(frame, dtype=float), (n, 4, 4))


def _is_shared(frames: np.ndarray) -> bool:
    return frames.ndim == 3 and frames.shape[0] > 0 and frames.strides[0] == 0


def _rows(frames: np.ndarray, index: np.ndarray, n: int) -> np.ndarray:
    """frames[index] (n rows), still shared when `frames` is."""
    return shared(frames[0], n) if _is_shared(frames) else frames[index]


def _inverse(frames: np.ndarray) -> np.ndarray:
    """invert_transform(frames), computed once for shared frames."""
    if _is_shared(frames):
        return shared(invert_transform(frames[0]), frames.shape[0])
    return invert_transform(frames)
