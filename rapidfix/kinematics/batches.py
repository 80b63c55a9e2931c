"""Array shapes at the kinematics' interface: joint batches (N, 6), pose batches (N, 4, 4).

Every kinematics function takes one value or a batch; these helpers turn either into a
batch and say which it was, so a (6,) input gives a single result back.
"""

from __future__ import annotations

import numpy as np

from rapidfix.exceptions import KinematicsError


def frozen(a: np.ndarray) -> np.ndarray:
    """A read-only float copy (a model's arrays never change after it is made)."""
    out = np.array(a, dtype=float, copy=True)
    out.setflags(write=False)
    return out


def as_joint_batch(q: np.ndarray) -> tuple[np.ndarray, bool]:
    """(N, 6) float joints and whether the input was a single (6,) vector."""
    arr = np.asarray(q, dtype=float)
    single = arr.ndim == 1
    arr = np.atleast_2d(arr)
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise KinematicsError(f"joint values must have shape (N, 6) or (6,), got {arr.shape}")
    return arr, single


def as_pose_batch(T: np.ndarray) -> tuple[np.ndarray, bool]:
    """(N, 4, 4) float poses and whether the input was a single (4, 4) pose."""
    arr = np.asarray(T, dtype=float)
    single = arr.ndim == 2
    if single:
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise KinematicsError(f"poses must have shape (N, 4, 4) or (4, 4), got {arr.shape}")
    return arr, single
