"""The product of exponentials of `fk_compiled` in numpy, one column per matrix entry.

`screws.forward_pose` builds every joint's 4×4 exponential for the batch and
multiplies the batch of 4×4 matrices joint by joint: a dozen strided passes and a
small matrix product per pose and joint. Here each entry of the 3×4 rigid
transform is one contiguous column (K,), each joint's axis numbers are scalars,
and every entry is the sum `fk_compiled` forms, term by term in its order: the
same poses as the compiled kernel (to the bit where numpy's sine is the C
library's), about three times faster than the 4×4 products. The post-processor
uses it inside `screws.compiled_forward` where numba is not installed.
"""

from __future__ import annotations

import numpy as np

from rapidfix import chunks

#: rows of a transform as columns: entry [i][j] is a (K,) array or a float
Rows = list[list]


def forward_poses(axis_dirs: np.ndarray, axis_points: np.ndarray, home: np.ndarray,
                  q: np.ndarray, out: np.ndarray) -> None:
    """out[p] = e^[S1]q[p,0] … e^[Sn]q[p,n-1] · home for every pose p (out (N,4,4)), in
    chunks of `chunks.FK_COLUMNS` poses."""
    dirs = np.asarray(axis_dirs, dtype=float).tolist()
    points = np.asarray(axis_points, dtype=float).tolist()
    home = np.asarray(home, dtype=float)
    for start in range(0, q.shape[0], chunks.FK_COLUMNS):
        rows = slice(start, start + chunks.FK_COLUMNS)
        cur: Rows = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
        for k, (w, r) in enumerate(zip(dirs, points)):
            cur = _times(cur, _exponential(w, r, q[rows, k]))
        part = out[rows]
        for i in range(3):
            c0, c1, c2, c3 = cur[i]
            for j in range(4):
                part[:, i, j] = c0 * home[0, j] + c1 * home[1, j] + c2 * home[2, j] \
                    + c3 * home[3, j]
        part[:, 3, :] = home[3]


def _exponential(w: list[float], r: list[float], theta: np.ndarray) -> Rows:
    """The revolute exponential about the line through r along w, as `fk_compiled` forms
    it: Rodrigues with sin θ and the versine 2 sin²(θ/2), translation (I − R) r."""
    x, y, z = w
    s = np.sin(theta)
    half = np.sin(0.5 * theta)
    vers = 2.0 * half * half
    xy, xz, yz = vers * x * y, vers * x * z, vers * y * z
    sx, sy, sz = s * x, s * y, s * z
    step: Rows = [[1.0 - vers * (y * y + z * z), xy - sz, xz + sy, None],
                  [xy + sz, 1.0 - vers * (x * x + z * z), yz - sx, None],
                  [xz - sy, yz + sx, 1.0 - vers * (x * x + y * y), None]]
    px, py, pz = r
    for i in range(3):
        row = step[i]
        row[3] = r[i] - (row[0] * px + row[1] * py + row[2] * pz)
    return step


def _times(cur: Rows, step: Rows) -> Rows:
    """The rigid product cur · step, the bottom row [0 0 0 1] not multiplied."""
    out: Rows = []
    for c0, c1, c2, c3 in cur:
        row = [c0 * step[0][j] + c1 * step[1][j] + c2 * step[2][j] for j in range(4)]
        row[3] = row[3] + c3
        out.append(row)
    return out


__all__ = ["forward_poses"]
