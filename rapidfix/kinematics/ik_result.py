"""What inverse kinematics returns: every solution slot and a named status per pose."""

from __future__ import annotations

import enum
import itertools
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rapidfix.exceptions import KinematicsError


class IKStatus(enum.IntEnum):
    """Per-pose outcome of inverse kinematics (smaller is better)."""

    OK = 0
    """At least one solution inside the joint limits."""
    WRIST_SINGULAR = 1
    """Solved, but axis 5 is at 0: only θ4 + θ6 is determined; θ4 kept at the previous value."""
    BEYOND_LIMITS = 2
    """The pose is reachable, but every solution breaks a joint limit."""
    UNREACHABLE = 3
    """No arm configuration reaches the pose (too far, too close, or not converged)."""
    NO_MATCHING_CONF = 4
    """Solutions exist, but none has the confdata the target names."""
    INVALID_POSE = 5
    """The pose is not a finite rigid transform."""

    @property
    def solved(self) -> bool:
        """True when a usable joint vector was returned."""
        return self in (IKStatus.OK, IKStatus.WRIST_SINGULAR)


def turn_table(counts: tuple[int, ...]) -> np.ndarray:
    """Whole-turn combinations (V, 6) int, axis 1 varying slowest, for variant counts."""
    return np.array(list(itertools.product(*(range(c) for c in counts))), dtype=int).reshape(
        -1, len(counts)
    )


def mask_dtype(counts: tuple[int, ...]) -> np.dtype:
    """Smallest unsigned integer type with one bit per whole-turn variant of any axis."""
    widest = max(counts)
    for dtype in (np.uint8, np.uint16, np.uint32, np.uint64):
        if widest <= np.iinfo(dtype).bits:
            return np.dtype(dtype)
    raise KinematicsError(f"an axis range of {widest} turns is more than IK supports (64)")


@dataclass(frozen=True, eq=False)
class IKSolutions:
    """All solutions of a batch of N poses, stored compactly and expanded on demand.

    The compact form is what inverse kinematics computes: `base_q (N, 8, 6)` rad,
    the eight arm/wrist branches (0–7: bit 2 θ1 turned by 180°, bit 1 the second
    elbow solution, bit 0 the flipped wrist), each angle wrapped into
    [lower limit, lower limit + 360°), NaN for unreachable branches;
    `reachable (N, 8)`; `turn_ok (N, 8, 6)` unsigned bit masks, bit k of axis j set
    when that angle plus k whole turns is within the joint limits; `base_singular
    (N, 8)` (wrist singularity, θ4 held); `status (N,)` IKStatus values; `counts`
    the number of whole-turn variants per axis; `backend` the code that solved
    the closed form ("numba" or "numpy").

    The expanded view has S = 8·∏counts slots: slot s holds branch `branch[s]`
    shifted by `turns[s] (6,)` whole turns. `q (N, S, 6)` rad (NaN for unreachable
    branches), `valid (N, S)` marks reachable slots within the joint limits, the
    only ones to use, and `singular (N, S)` slots at a wrist singularity. They are
    built on first use, so a caller that needs only the compact form never pays
    for every ±360° combination.
    """

    base_q: np.ndarray
    reachable: np.ndarray
    turn_ok: np.ndarray
    base_singular: np.ndarray
    status: np.ndarray
    counts: tuple[int, ...]
    backend: str = "numpy"

    def __len__(self) -> int:
        return int(self.status.shape[0])

    @cached_property
    def turns(self) -> np.ndarray:
        """Whole turns (S, 6) added to each axis in each slot."""
        return np.tile(turn_table(self.counts), (8, 1))

    @cached_property
    def branch(self) -> np.ndarray:
        """Arm/wrist branch (S,) of each slot."""
        return np.repeat(np.arange(8), int(np.prod(self.counts)))

    @cached_property
    def q(self) -> np.ndarray:
        """Joint angles (N, S, 6) rad of every slot (NaN for unreachable branches)."""
        n = len(self)
        shifts = 2.0 * np.pi * turn_table(self.counts)
        out = np.empty((n, 8, shifts.shape[0], 6))
        np.add(self.base_q[:, :, None, :], shifts, out=out)
        return out.reshape(n, 8 * shifts.shape[0], 6)

    @cached_property
    def valid(self) -> np.ndarray:
        """(N, S) mask of reachable slots whose every angle is within the joint limits."""
        n = len(self)
        table = turn_table(self.counts).astype(self.turn_ok.dtype)
        bits = (self.turn_ok[:, :, None, :] >> table) & 1
        inside = np.all(bits.astype(bool), axis=3) & self.reachable[:, :, None]
        return inside.reshape(n, 8 * table.shape[0])

    @cached_property
    def singular(self) -> np.ndarray:
        """(N, S) mask of slots at a wrist singularity."""
        return np.repeat(self.base_singular, int(np.prod(self.counts)), axis=1)

    def count(self) -> np.ndarray:
        """Number of valid solutions per pose (N,), counted without expanding."""
        per_axis = _POPCOUNT[self.turn_ok.astype(np.uint64) & 0xFF]
        wide = self.turn_ok.astype(np.uint64) >> 8
        while wide.any():  # masks wider than a byte (axes of more than eight turns)
            per_axis += _POPCOUNT[wide & 0xFF]
            wide >>= 8
        per_branch = np.prod(per_axis, axis=2) * self.reachable
        return per_branch.sum(axis=1)


_POPCOUNT = np.array([bin(i).count("1") for i in range(256)], dtype=np.int64)


def raise_for_status(status: np.ndarray, what: str = "pose") -> None:
    """Raise KinematicsError naming the first failing poses (0-based) and their status."""
    status = np.asarray(status)
    bad = np.flatnonzero(~np.isin(status, [IKStatus.OK, IKStatus.WRIST_SINGULAR]))
    if bad.size:
        shown = ", ".join(f"{what} {i}: {IKStatus(int(status[i])).name}" for i in bad[:5])
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        raise KinematicsError(f"no joint solution for {shown}{more}")
