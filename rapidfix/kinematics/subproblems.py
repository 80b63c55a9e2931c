"""Paden–Kahan subproblems 1, 2 and 3, vectorised over batches.

Each works on points/vectors of shape (..., 3) that broadcast against each other
and returns angles of the broadcast shape plus a feasibility mask, never raising
and never warning: infeasible entries are reported by the mask (their angle is
the least-squares best fit where one exists).

Conventions: e^[ξθ] is the rotation by θ about the line through r along the unit
vector w, right-handed.
"""

from __future__ import annotations

import numpy as np


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products over the last axis (written out: faster than a reduction over 3)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products over the last axis of broadcasting arrays."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(_dot(a, a))


def _perp(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Component of v perpendicular to the unit vector w."""
    return v - _dot(v, w)[..., None] * w


def subproblem1(
    w: np.ndarray, r: np.ndarray, p: np.ndarray, q: np.ndarray, tol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray]:
    """θ with e^[ξθ] p = q (rotation about the line r + s·w).

    Returns (θ, feasible). Feasible means p and q are equally far from the axis and
    at the same height along it (within `tol` mm) and not on the axis; otherwise θ
    is the angle between their projections (0 when a projection vanishes).
    `tol=np.inf` skips the checks (all feasible) where the caller already knows.
    """
    w = np.asarray(w, dtype=float)
    u = np.asarray(p, dtype=float) - r
    v = np.asarray(q, dtype=float) - r
    if tol == np.inf:  # caller knows the points correspond: skip the checks
        theta = _angle_about(w, u, v) if w.size == 3 else _angle(w, u, v)
        return theta, np.ones(theta.shape, dtype=bool)
    up, vp = _perp(u, w), _perp(v, w)
    theta = np.arctan2(_dot(w, _cross(up, vp)), _dot(up, vp))
    nu, nv = _norm(up), _norm(vp)
    same = (np.abs(_dot(w, u - v)) <= tol) & (np.abs(nu - nv) <= tol)
    return theta, same & (nu > tol) & (nv > tol)


def _angle(w: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Subproblem 1's angle turning u onto v about the unit axes w (from the axis)."""
    up, vp = _perp(u, w), _perp(v, w)
    return np.arctan2(_dot(w, _cross(up, vp)), _dot(up, vp))


def _angle_about(w: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """`_angle` about one axis: its numbers as scalars, u and v by components, the same
    products and sums in the same order, without the (..., 3) temporaries."""
    x, y, z = w.ravel().tolist()
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    du = u0 * x + u1 * y + u2 * z
    dv = v0 * x + v1 * y + v2 * z
    a0, a1, a2 = u0 - du * x, u1 - du * y, u2 - du * z
    b0, b1, b2 = v0 - dv * x, v1 - dv * y, v2 - dv * z
    cross = x * (a1 * b2 - a2 * b1) + y * (a2 * b0 - a0 * b2) + z * (a0 * b1 - a1 * b0)
    return np.arctan2(cross, a0 * b0 + a1 * b1 + a2 * b2)


def subproblem2(
    w1: np.ndarray,
    w2: np.ndarray,
    r: np.ndarray,
    p: np.ndarray,
    q: np.ndarray,
    tol: float = 1e-9,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ1, θ2) with e^[ξ1θ1] e^[ξ2θ2] p = q for two axes crossing at r.

    Returns (theta1 (..., 2), theta2 (..., 2), feasible (...)): the two solutions
    along the last axis (the intersection point c = αw1 + βw2 ± γ(w1×w2), + first).
    The axes must not be parallel. When the solutions coincide (γ = 0) both
    columns are equal; when ‖p − r‖ ≠ ‖q − r‖ or γ² < 0 the pose is infeasible.
    `tol=np.inf` skips that check (all feasible) where the caller already knows.
    """
    w1 = np.asarray(w1, dtype=float)
    w2 = np.asarray(w2, dtype=float)
    u = np.asarray(p, dtype=float) - r
    v = np.asarray(q, dtype=float) - r
    k = _dot(w1, w2)
    cross = _cross(w1, w2)
    cross2 = _dot(cross, cross)
    denom = k * k - 1.0
    a = (k * _dot(w2, u) - _dot(w1, v)) / denom
    b = (k * _dot(w1, v) - _dot(w2, u)) / denom
    # γ² from the part of v perpendicular to w1, ‖v⊥‖² = β²(1 − k²) + γ²‖w1 × w2‖²:
    # no cancellation when γ is small (the usual ‖u‖² − α² − … loses half the digits
    # there, which near a wrist singularity costs 1e-8 mm at the flange).
    v_perp = _perp(v, w1)
    g2 = (_dot(v_perp, v_perp) - b * b * (1.0 - k * k)) / cross2
    if tol == np.inf:  # the caller knows a solution exists: skip the checks
        feasible = np.ones(g2.shape, dtype=bool)
    else:
        scale = np.maximum(_dot(u, u), 1.0)
        same_norm = np.abs(_norm(u) - _norm(v)) <= tol
        feasible = (g2 >= -tol * scale) & same_norm
    g = np.sqrt(np.maximum(g2, 0.0))
    base = a[..., None] * w1 + b[..., None] * w2
    sign = np.array([1.0, -1.0])
    c = base[..., None, :] + (g[..., None] * sign)[..., None] * cross[..., None, :]
    origin = np.zeros(3)
    # the angles only: the points correspond by construction
    t2, _ = subproblem1(w2[..., None, :], origin, u[..., None, :], c, tol=np.inf)
    t1, _ = subproblem1(w1[..., None, :], origin, c, v[..., None, :], tol=np.inf)
    return t1, t2, feasible


def subproblem3(
    w: np.ndarray,
    r: np.ndarray,
    p: np.ndarray,
    q: np.ndarray,
    delta: np.ndarray,
    tol: float = 1e-9,
) -> tuple[np.ndarray, np.ndarray]:
    """θ with ‖e^[ξθ] p − q‖ = δ: returns (theta (..., 2), feasible (...)).

    The two solutions are θ0 + φ and θ0 − φ. φ comes from the triangle of the
    projected distances by atan2 of Heron's product, which stays accurate at the
    edge of reach where an arccos would lose half the digits. Infeasible entries
    (δ too long or too short within `tol` mm) get φ = 0.
    """
    w = np.asarray(w, dtype=float)
    u = np.asarray(p, dtype=float) - r
    v = np.asarray(q, dtype=float) - r
    up, vp = _perp(u, w), _perp(v, w)
    theta0 = np.arctan2(_dot(w, _cross(up, vp)), _dot(up, vp))
    a = _norm(up)
    b = _norm(vp)
    h = _dot(w, u - v)
    d2 = np.asarray(delta, dtype=float) ** 2 - h * h
    d = np.sqrt(np.maximum(d2, 0.0))
    f1, f2, f3 = d - a + b, d + a - b, a + b - d
    feasible = (d2 >= -2.0 * tol * np.maximum(d, 1.0)) & (f1 >= -tol) & (f2 >= -tol) & (f3 >= -tol)
    heron = np.maximum(f1, 0.0) * np.maximum(f2, 0.0) * np.maximum(f3, 0.0) * (a + b + d)
    phi = np.arctan2(np.sqrt(heron), a * a + b * b - d * d)
    phi = np.where(feasible & (a > 0) & (b > 0), phi, 0.0)
    theta = theta0[..., None] + phi[..., None] * np.array([1.0, -1.0])
    return theta, feasible & (a > tol) & (b > tol)
