"""The wrist centre's sides behind confdata (`conf_compiled.wrist_sides_rows`) in numpy
columns.

`confdata.conf_quantities` places the wrist centre with the 4×4 products of the
arm's three axes and their prefixes (about 1 µs a joint vector). Here each
coordinate is one contiguous column and each axis's numbers are scalars, and every
quantity is formed as the compiled kernel forms it, term by term in its order: the
kernel's numbers (to the bit where numpy's sine is the C library's), three times
faster than the products. Used inside `screws.compiled_forward` where numba is not
installed.
"""

from __future__ import annotations

import numpy as np

from rapidfix import chunks

#: a 3-vector as three columns (or floats); a rotation as three rows of them
Vec = tuple
Rot = tuple


def wrist_sides(q: np.ndarray, w: np.ndarray, r: np.ndarray, c0: np.ndarray,
                fwd0: np.ndarray, side_sign: float) -> np.ndarray:
    """(M, 2): the wrist centre ahead of axis 1 and ahead of the lower arm (mm) for
    joints q (M, 6), as `conf_compiled._wrist_sides` measures them, in chunks of
    `chunks.FK_COLUMNS` joint vectors."""
    out = np.empty((q.shape[0], 2))
    axes = (np.asarray(w, dtype=float).tolist(), np.asarray(r, dtype=float).tolist(),
            tuple(np.asarray(c0, dtype=float).tolist()),
            tuple(np.asarray(fwd0, dtype=float).tolist()))
    for start in range(0, q.shape[0], chunks.FK_COLUMNS):
        rows = slice(start, start + chunks.FK_COLUMNS)
        _sides(q[rows], *axes, side_sign, out[rows])
    return out


def _sides(q: np.ndarray, w: list[list[float]], r: list[list[float]], c0: Vec, fwd0: Vec,
           side_sign: float, out: np.ndarray) -> None:
    """`wrist_sides` of one chunk into out."""
    p0, p1, p2 = (tuple(r[i]) for i in range(3))
    rot1 = _turn(w[0], q[:, 0])
    t1 = _sub(p0, _apply(rot1, p0))
    rot2 = _turn(w[1], q[:, 1])
    t2 = _sub(p1, _apply(rot2, p1))
    rot3 = _turn(w[2], q[:, 2])
    t3 = _sub(p2, _apply(rot3, p2))
    rot12 = _compose(rot1, rot2)
    t12 = _add(_apply(rot1, t2), t1)
    rot123 = _compose(rot12, rot3)
    t123 = _add(_apply(rot12, t3), t12)
    c = _add(_apply(rot123, c0), t123)
    out[:, 0] = _dot(_sub(c, p0), _apply(rot1, fwd0))
    a2 = _add(_apply(rot1, p1), t1)
    a3 = _add(_apply(rot12, p2), t12)
    w2 = _apply(rot1, tuple(w[1]))
    arm = _sub(a3, a2)
    arm_len = np.sqrt(_dot(arm, arm))
    out[:, 1] = _dot(_cross(arm, _sub(c, a2)), w2) / arm_len * side_sign


def _turn(w: list[float], theta: np.ndarray) -> Rot:
    """Rodrigues' rotation (rows) by theta about the unit axis w, as `conf_compiled._turn`."""
    s = np.sin(theta)
    half = np.sin(0.5 * theta)
    vers = 2.0 * half * half
    x, y, z = w
    return ((1.0 - vers * (y * y + z * z), vers * x * y - s * z, vers * x * z + s * y),
            (vers * x * y + s * z, 1.0 - vers * (x * x + z * z), vers * y * z - s * x),
            (vers * x * z - s * y, vers * y * z + s * x, 1.0 - vers * (x * x + y * y)))


def _apply(rot: Rot, v: Vec) -> Vec:
    return tuple(row[0] * v[0] + row[1] * v[1] + row[2] * v[2] for row in rot)


def _compose(a: Rot, b: Rot) -> Rot:
    """The rotation a·b (rows)."""
    cols = [_apply(a, (b[0][j], b[1][j], b[2][j])) for j in range(3)]
    return tuple((cols[0][i], cols[1][i], cols[2][i]) for i in range(3))


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _dot(a: Vec, b: Vec) -> np.ndarray:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


__all__ = ["wrist_sides"]
