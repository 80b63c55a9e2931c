"""The product of exponentials of `screws.forward_pose` compiled with numba.

numpy builds each joint's 4×4 exponential for the whole batch and multiplies the
batch of 4×4 matrices joint by joint: a dozen passes over memory and a small matrix
product per pose and joint, about 5 µs a pose. This kernel does the same per pose
in registers: Rodrigues' formula with sin θ and the versine 2 sin²(θ/2) (as
`rotation_about`), the translation (I − R) q (as `revolute_exp`), and the product
of the rigid transforms row by row (the bottom row [0 0 0 1] is not multiplied).
The sums are taken in another order than numpy's matrix product, so poses agree
to rounding (~1e-13 mm); tests compare both.

This module imports numba; `screws` imports it only when numba is installed.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def forward_poses(axis_dirs: np.ndarray, axis_points: np.ndarray, home: np.ndarray,
                  q: np.ndarray, out: np.ndarray) -> None:
    """out[p] = e^[S1]q[p,0] … e^[Sn]q[p,n-1] · home for every pose p (out (N,4,4)).
    `fk_columns` forms the same sums in numpy columns, where numba is not installed: a
    change here belongs there too."""
    n = axis_dirs.shape[0]
    cur = np.empty((3, 4))
    nxt = np.empty((3, 4))
    step = np.empty((3, 4))
    for p in range(q.shape[0]):
        for i in range(3):
            for j in range(4):
                cur[i, j] = 1.0 if i == j else 0.0
        for k in range(n):
            theta = q[p, k]
            x, y, z = axis_dirs[k, 0], axis_dirs[k, 1], axis_dirs[k, 2]
            s = math.sin(theta)
            half = math.sin(0.5 * theta)
            vers = 2.0 * half * half
            step[0, 0] = 1.0 - vers * (y * y + z * z)
            step[1, 1] = 1.0 - vers * (x * x + z * z)
            step[2, 2] = 1.0 - vers * (x * x + y * y)
            step[0, 1] = vers * x * y - s * z
            step[1, 0] = vers * x * y + s * z
            step[0, 2] = vers * x * z + s * y
            step[2, 0] = vers * x * z - s * y
            step[1, 2] = vers * y * z - s * x
            step[2, 1] = vers * y * z + s * x
            px, py, pz = axis_points[k, 0], axis_points[k, 1], axis_points[k, 2]
            for i in range(3):
                step[i, 3] = (axis_points[k, i]
                              - (step[i, 0] * px + step[i, 1] * py + step[i, 2] * pz))
            for i in range(3):
                for j in range(4):
                    acc = cur[i, 0] * step[0, j] + cur[i, 1] * step[1, j] \
                        + cur[i, 2] * step[2, j]
                    nxt[i, j] = acc + cur[i, 3] if j == 3 else acc
            for i in range(3):
                for j in range(4):
                    cur[i, j] = nxt[i, j]
        for i in range(3):
            for j in range(4):
                acc = cur[i, 0] * home[0, j] + cur[i, 1] * home[1, j] + cur[i, 2] * home[2, j]
                out[p, i, j] = acc + cur[i, 3] * home[3, j]
        for j in range(4):
            out[p, 3, j] = home[3, j]


__all__ = ["forward_poses"]
