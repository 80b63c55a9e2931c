"""Screw-theory building blocks: exponentials of revolute twists and their products.

A revolute joint is the unit screw S = (w, v) with v = -w x q for a point q on the
axis. Its exponential e^[S]θ is a rotation by θ about that line. Everything here
works on batches: angles of shape (N,) and axes broadcast against them.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from types import ModuleType

import numpy as np

from rapidfix import chunks
from rapidfix.compiled import Switch, load_kernel, numpy_only
from rapidfix.kinematics import fk_columns

#: batches smaller than this stay in numpy (a kernel call has a fixed cost)
_COMPILED_FROM = 64
_COMPILED = Switch("rapidfix_fk_compiled")


def compiled_forward() -> AbstractContextManager[None]:
    """Inside the block, `forward_pose` runs the compiled kernel (`fk_compiled`) when numba
    is installed, and its arithmetic in numpy columns (`fk_columns`) when it is not: the
    same poses to rounding, several times faster. The post-processor turns it on (what
    it writes is rounded far above that level); outside, the poses are the 4×4 products,
    so a fit or a diagnosis gives the same numbers with or without numba."""
    return _COMPILED.on()


def forward_is_compiled() -> bool:
    """Whether the current block asked for the compiled kinematics (`compiled_forward`)
    and they are at hand (numba installed, RAPIDFIX_IK_BACKEND not numpy)."""
    return _COMPILED.get() and _kernel() is not None


def forward_switched_on() -> bool:
    """Whether the current block asked for the kernels' arithmetic (`compiled_forward`),
    compiled or in numpy columns."""
    return _COMPILED.get()


def _kernel() -> ModuleType | None:
    """The compiled product of exponentials, or None: numba not installed, or
    RAPIDFIX_IK_BACKEND=numpy (which keeps all the kinematics in numpy)."""
    return None if numpy_only() else load_kernel("rapidfix.kinematics.fk_compiled")


def rotation_about(w: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) by angles θ (N,) about unit axes w (3,) or (N, 3).

    Rodrigues' formula with sin θ and the versine 2 sin²(θ/2) evaluated directly,
    so tiny angles keep full relative precision (1 - cos θ would round to zero).
    """
    theta = np.asarray(theta, dtype=float)
    w = np.broadcast_to(np.asarray(w, dtype=float), (*theta.shape, 3))
    s = np.sin(theta)
    half = np.sin(0.5 * theta)
    vers = 2.0 * half * half
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    out = np.empty((*theta.shape, 3, 3))
    out[..., 0, 0] = 1.0 - vers * (y * y + z * z)
    out[..., 1, 1] = 1.0 - vers * (x * x + z * z)
    out[..., 2, 2] = 1.0 - vers * (x * x + y * y)
    out[..., 0, 1] = vers * x * y - s * z
    out[..., 1, 0] = vers * x * y + s * z
    out[..., 0, 2] = vers * x * z + s * y
    out[..., 2, 0] = vers * x * z - s * y
    out[..., 1, 2] = vers * y * z - s * x
    out[..., 2, 1] = vers * y * z + s * x
    return out


def revolute_exp(w: np.ndarray, q: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Homogeneous transforms (N, 4, 4) e^[S]θ of the revolute screw through q along w.

    The translation is (I - R) q, the exact closed form for a pure rotation about
    a line (equal to the general (Iθ + (1-cos θ)[w] + (θ - sin θ)[w]²) v term).
    """
    theta = np.asarray(theta, dtype=float)
    rot = rotation_about(w, theta)
    q = np.broadcast_to(np.asarray(q, dtype=float), (*theta.shape, 3))
    out = np.zeros((*theta.shape, 4, 4))
    out[..., :3, :3] = rot
    out[..., :3, 3] = q - np.einsum("...ij,...j->...i", rot, q)
    out[..., 3, 3] = 1.0
    return out


def screw_rows(axis_dirs: np.ndarray, axis_points: np.ndarray) -> np.ndarray:
    """Screw coordinates (n, 6) as rows (w, v) with v = -w × q."""
    w = np.asarray(axis_dirs, dtype=float)
    q = np.asarray(axis_points, dtype=float)
    return np.concatenate([w, -np.cross(w, q)], axis=-1)


def invert_transform(T: np.ndarray) -> np.ndarray:
    """Inverse of rigid transforms (..., 4, 4) using the transpose of the rotation."""
    T = np.asarray(T, dtype=float)
    rot_t = np.swapaxes(T[..., :3, :3], -1, -2)
    out = np.zeros_like(T)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rot_t, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def product_of_exponentials(
    axis_dirs: np.ndarray, axis_points: np.ndarray, home: np.ndarray, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """PoE forward kinematics: (tool pose (N, 4, 4), prefix products (N, n, 4, 4)).

    prefix[:, i] = e^[S1]θ1 … e^[Si]θi-1 is the transform that carries joint i's
    home axis to where it is now (prefix[:, 0] is the identity).
    """
    q = np.asarray(q, dtype=float)
    count = q.shape[0]
    out = np.empty((count, 4, 4))
    prefix = np.empty((count, axis_dirs.shape[0], 4, 4))
    for start in range(0, count, chunks.FK):
        rows = slice(start, start + chunks.FK)
        out[rows] = _chain(axis_dirs, axis_points, q[rows], prefix[rows]) @ home
    return out, prefix


def forward_pose(
    axis_dirs: np.ndarray, axis_points: np.ndarray, home: np.ndarray, q: np.ndarray
) -> np.ndarray:
    """The tool pose (N, 4, 4) of `product_of_exponentials`, without the prefix products
    (the kernel's arithmetic inside `compiled_forward`)."""
    q = np.asarray(q, dtype=float)
    count = q.shape[0]
    out = np.empty((count, 4, 4))
    if count >= _COMPILED_FROM and _COMPILED.get() and q.ndim == 2 \
            and np.ndim(axis_dirs) == 2:
        kernel = _kernel()
        if kernel is None:
            fk_columns.forward_poses(axis_dirs, axis_points, home, q, out)
        else:
            kernel.forward_poses(np.ascontiguousarray(axis_dirs, dtype=float),
                                 np.ascontiguousarray(axis_points, dtype=float),
                                 np.ascontiguousarray(home, dtype=float),
                                 np.ascontiguousarray(q), out)
        return out
    for start in range(0, count, chunks.FK):
        rows = slice(start, start + chunks.FK)
        out[rows] = _chain(axis_dirs, axis_points, q[rows], None) @ home
    return out


def current_axes(
    axis_dirs: np.ndarray, axis_points: np.ndarray, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Current axis directions and points (N, n, 3) of the joints for joints q (N, n):
    each home axis carried by the product of the joints before it."""
    q = np.asarray(q, dtype=float)
    count, n = q.shape[0], axis_dirs.shape[0]
    dirs = np.empty((count, n, 3))
    points = np.empty((count, n, 3))
    for start in range(0, count, chunks.FK):
        rows = slice(start, start + chunks.FK)
        _chain(axis_dirs, axis_points, q[rows], None, (dirs[rows], points[rows]))
    return dirs, points


def _chain(
    axis_dirs: np.ndarray, axis_points: np.ndarray, q: np.ndarray, prefix: np.ndarray | None,
    axes: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """e^[S1]θ1 … e^[Sn]θn (K, 4, 4) for one chunk, storing the prefixes (or only the
    current axis directions and points) when asked."""
    n = axis_dirs.shape[0]
    # every joint's exponential in one batch (K, n, 4, 4), then their product joint by joint
    exps = revolute_exp(axis_dirs, axis_points, q[:, :n])
    current = np.broadcast_to(np.eye(4), (q.shape[0], 4, 4)).copy()
    for i in range(n):  # loop over the joints, not over poses
        if prefix is not None:
            prefix[:, i] = current
        if axes is not None:
            rot = current[:, :3, :3]
            axes[0][:, i] = rot @ axis_dirs[i]
            axes[1][:, i] = rot @ axis_points[i] + current[:, :3, 3]
        current = current @ exps[:, i]
    return current


def rotate_vectors(w: np.ndarray, theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors v (..., 3) turned by θ (...) about unit axes w: Rodrigues without matrices.

    v + sin θ (w × v) + 2 sin²(θ/2) w × (w × v), exact for tiny angles too.
    """
    w = np.asarray(w, dtype=float)
    theta = np.asarray(theta, dtype=float)
    if w.ndim == 1:  # one axis (the IK's): its numbers as scalars, v by components
        return _rotate_about(w.tolist(), theta, np.asarray(v, dtype=float))
    s = np.sin(theta)[..., None]
    half = np.sin(0.5 * theta)[..., None]
    wxv = _cross(w, v)
    return v + s * wxv + (2.0 * half * half) * _cross(w, wxv)


def _rotate_about(w: list[float], theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    """`rotate_vectors` about one axis w: the same products and sums, in the same order,
    on v's components, so the same numbers without the (..., 3) temporaries."""
    x, y, z = w
    s = np.sin(theta)
    half = np.sin(0.5 * theta)
    k = 2.0 * half * half
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    a0, a1, a2 = y * v2 - z * v1, z * v0 - x * v2, x * v1 - y * v0
    b0, b1, b2 = y * a2 - z * a1, z * a0 - x * a2, x * a1 - y * a0
    return np.stack([v0 + s * a0 + k * b0, v1 + s * a1 + k * b1, v2 + s * a2 + k * b2],
                    axis=-1)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)
