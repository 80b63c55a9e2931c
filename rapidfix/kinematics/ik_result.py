"""What inverse kinematics returns: every solution slot and a named status per pose."""

from __future__ import annotations

import enum
from dataclasses import dataclass

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


@dataclass(frozen=True)
class IKSolutions:
    """All solutions of a batch of N poses in S slots.

    `q (N, S, 6)` rad: slot s holds arm/wrist branch `branch[s]` (0–7: bit 2 θ1 turned
    by 180°, bit 1 the second elbow solution, bit 0 the flipped wrist), each angle
    wrapped into [lower limit, lower limit + 360°) and shifted by `turns[s] (6,)` whole
    turns. Slots of unreachable branches hold NaN; `valid (N, S)` marks reachable
    slots within the joint limits, the only ones to use. `status (N,)` holds IKStatus
    values; `singular (N, S)` marks slots at a wrist singularity (θ4 held).
    """

    q: np.ndarray
    valid: np.ndarray
    status: np.ndarray
    branch: np.ndarray
    turns: np.ndarray
    singular: np.ndarray

    def __len__(self) -> int:
        return int(self.q.shape[0])

    def count(self) -> np.ndarray:
        """Number of valid solutions per pose (N,)."""
        return self.valid.sum(axis=1)


def raise_for_status(status: np.ndarray, what: str = "pose") -> None:
    """Raise KinematicsError naming the first failing poses (0-based) and their status."""
    status = np.asarray(status)
    bad = np.flatnonzero(~np.isin(status, [IKStatus.OK, IKStatus.WRIST_SINGULAR]))
    if bad.size:
        shown = ", ".join(f"{what} {i}: {IKStatus(int(status[i])).name}" for i in bad[:5])
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        raise KinematicsError(f"no joint solution for {shown}{more}")
