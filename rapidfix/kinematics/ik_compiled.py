"""The closed-form IK of `ik_analytic` compiled with numba, for speed on large batches.

The same subproblems on the same geometry, written per pose with 3-vectors held
in registers: no temporaries and one pass over the batch. Every angle of the
result is an atan2 of two numbers that the geometry pass stores; numpy's
vectorised arctan2 (SIMD, several times faster than a scalar libm call) then
turns them all into angles at once, and a second compiled pass assembles the
eight branches, the limit masks and the status, as `ik` does for the numpy path.
Differences from the numpy code, all at the rounding level (angles agree to
~1e-14 rad; to ~1e-9 rad near the fully stretched arm, where θ3 is fixed only
to ~√ε and every rounding is amplified):

- a rotation by a solved angle uses the sine and cosine the subproblem already
  has (the normalised projections), not sin() of the angle;
- θ3 = θ0 ± φ is turned by the angle-sum rule from the triangle's cos φ, sin φ;
- for an ABB-type wrist the flipped solution is (θ4 + π, −θ5, θ6 + π) directly;
- a·b + c may be fused into one multiply-add (numba's fastmath "contract" only:
  no reassociation, NaN and infinity keep their IEEE meaning).

This module imports numba; `ik.py` imports it only when numba is installed
(`pip install rapidfix[fast]`) and otherwise uses the numpy path.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rapidfix import chunks
from rapidfix.kinematics.ik_analytic import AnalyticIK

_TWO_PI = 2.0 * math.pi
_REACH_TOL = 1e-9  # subproblem 3's tolerance in ik_analytic (mm)
_SHOULDER_TOL2 = 1e-12  # ik_analytic._DISTANCE_TOL² (mm²)
_FMA = {"contract"}  # only fused multiply-add: shorter dependency chains, no other licence


def solve_nominal(
    solver: AnalyticIK,
    T: np.ndarray,
    q_prev: np.ndarray,
    wrist_tol: float,
    limits: np.ndarray,
    counts: tuple[int, ...],
    limit_tol: float,
    rigid_tol: float,
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """Fill `out` = (base_q (N, 8, 6), reachable (N, 8), turn_ok (N, 8, 6), base_singular
    (N, 8), status (N,)) for poses T (N, 4, 4) of a nominal model, as `ik.solve_all`."""
    T = np.ascontiguousarray(T, dtype=float)
    q_prev = np.ascontiguousarray(q_prev, dtype=float)
    lo = np.ascontiguousarray(limits[:, 0], dtype=float)
    hi = np.ascontiguousarray(limits[:, 1], dtype=float)
    counts_arr = np.asarray(counts, dtype=np.int64)
    w, r, c = solver.w, solver.r, solver.c
    theta0 = _angle(_row(w, 2), _sub(_row2(c), _row(r, 2)), _sub(_row(r, 1), _row(r, 2)))[0]
    # +1 / −1 when axis 3 points along / against axis 2 exactly (all ABB arms), else 0.
    same23 = 1.0 if np.array_equal(w[1], w[2]) else -1.0 if np.array_equal(w[1], -w[2]) else 0.0
    k = _N_ARM_ANGLES + 12 * (1 if solver.flip_identity else 2)
    size = min(chunks.IK_COMPILED, T.shape[0])
    y, x, angles = np.empty((size, k)), np.empty((size, k)), np.empty((size, k))
    rigid, shoulder = np.empty(size, dtype=np.bool_), np.empty(size, dtype=np.bool_)
    reach, sing = np.empty((size, 2), dtype=np.bool_), np.empty((size, 4), dtype=np.bool_)
    for start in range(0, T.shape[0], chunks.IK_COMPILED):
        stop = min(start + chunks.IK_COMPILED, T.shape[0])
        m = stop - start
        _geometry(
            T[start:stop], q_prev[start:stop], float(wrist_tol), w, r, c, solver.home_inv,
            solver.u_side, solver.flip_identity, same23, float(rigid_tol),
            y[:m], x[:m], rigid[:m], shoulder[:m], reach[:m], sing[:m],
        )  # fmt: skip
        np.arctan2(y[:m], x[:m], out=angles[:m])
        _assemble(
            angles[:m], q_prev[start:stop], solver.flip_identity, theta0,
            rigid[:m], shoulder[:m], reach[:m], sing[:m], lo, hi, counts_arr, float(limit_tol),
            *(a[start:stop] for a in out),
        )  # fmt: skip


# Columns of the atan2 tables: θ1, φ per θ1 branch, θ2 per arm branch, then per wrist
# solution θ4, θ5, θ6 per arm branch (arm branch a = 2·(θ1 + 180°) + elbow).
_N_ARM_ANGLES = 7


@njit(cache=True, fastmath=_FMA)
def _col(angle: int, s: int, a: int) -> int:
    """Column of θ4 (angle 0), θ5 (1) or θ6 (2) of wrist solution s in arm branch a."""
    return _N_ARM_ANGLES + 12 * s + 4 * angle + a


@njit(cache=True, fastmath=_FMA)
def _dot(a: tuple, b: tuple) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, fastmath=_FMA)
def _cross(a: tuple, b: tuple) -> tuple:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, fastmath=_FMA)
def _sub(a: tuple, b: tuple) -> tuple:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, fastmath=_FMA)
def _add(a: tuple, b: tuple) -> tuple:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True, fastmath=_FMA)
def _perp(v: tuple, w: tuple) -> tuple:
    """Component of v perpendicular to the unit vector w."""
    d = _dot(v, w)
    return (v[0] - d * w[0], v[1] - d * w[1], v[2] - d * w[2])


@njit(cache=True, fastmath=_FMA)
def _row(m: np.ndarray, i: int) -> tuple:
    return (m[i, 0], m[i, 1], m[i, 2])


@njit(cache=True, fastmath=_FMA)
def _row2(v: np.ndarray) -> tuple:
    return (v[0], v[1], v[2])


@njit(cache=True, fastmath=_FMA)
def _row3(T: np.ndarray, i: int, a: int) -> tuple:
    return (T[i, a, 0], T[i, a, 1], T[i, a, 2])


@njit(cache=True, fastmath=_FMA)
def _turn(s: float, c: float) -> tuple:
    """(sin θ, 1 − cos θ) from sin and cos. 1 − cos θ loses relative digits for tiny θ,
    but it multiplies w × (w × v), so the rotated vector keeps full absolute accuracy."""
    return (s, 1.0 - c)


@njit(cache=True, fastmath=_FMA)
def _turn_of(theta: float) -> tuple:
    """(sin θ, 1 − cos θ) of an angle given as a number (as screws.rotate_vectors)."""
    half = math.sin(0.5 * theta)
    return (math.sin(theta), 2.0 * half * half)


@njit(cache=True, fastmath=_FMA)
def _rotate(w: tuple, sk: tuple, v: tuple, sign: float) -> tuple:
    """v turned about the unit axis w by ±θ (sign), sk = (sin θ, 1 − cos θ): Rodrigues."""
    s, k = sign * sk[0], sk[1]
    a = _cross(w, v)
    b = _cross(w, a)
    return (v[0] + s * a[0] + k * b[0], v[1] + s * a[1] + k * b[1], v[2] + s * a[2] + k * b[2])


@njit(cache=True, fastmath=_FMA)
def _angle_yx(w: tuple, u: tuple, v: tuple) -> tuple:
    """Subproblem 1 for vectors u, v from a point on the axis w: (y, x, sin θ, cos θ)
    with θ = atan2(y, x); (0, 1, 0, 1) when a projection vanishes."""
    up, vp = _perp(u, w), _perp(v, w)
    y = _dot(w, _cross(up, vp))
    x = _dot(up, vp)
    n = math.sqrt(x * x + y * y)
    if n == 0.0:
        return (0.0, 1.0, 0.0, 1.0)
    inv = 1.0 / n
    return (y, x, y * inv, x * inv)


@njit(cache=True, fastmath=_FMA)
def _angle(w: tuple, u: tuple, v: tuple) -> tuple:
    """Subproblem 1: (θ, sin θ, cos θ)."""
    y, x, s, c = _angle_yx(w, u, v)
    return (math.atan2(y, x), s, c)


@njit(cache=True, fastmath=_FMA)
def _mod_turn(d: float) -> float:
    """d mod 2π in [0, 2π) as numpy's mod gives it; a single exact add or subtract
    in the usual cases instead of the general remainder."""
    if d < 0.0:
        return d + _TWO_PI if d >= -_TWO_PI else d % _TWO_PI
    if d >= _TWO_PI:
        return d - _TWO_PI if d < 2.0 * _TWO_PI else d % _TWO_PI
    return d


@njit(cache=True, fastmath=_FMA)
def _wrap(a: float) -> float:
    """Angle to (-π, π]."""
    return math.pi - _mod_turn(math.pi - a)


@njit(cache=True, fastmath=_FMA)
def _place(x: float, lo: float, hi: float, count: int, tol: float) -> tuple:
    """x wrapped into [lo − tol, lo − tol + 2π) and the bit mask of its whole-turn
    variants x + 2πk (k < count) inside [lo − tol, hi + tol] (as ik.limit_masks).
    Every variant is above the lower bound, so the mask is the first few bits."""
    start = lo - tol
    x = start + _mod_turn(x - start)
    top = hi + tol
    n = 0
    while n < count and x + _TWO_PI * n <= top:
        n += 1
    return x, (1 << n) - 1


@njit(cache=True, fastmath=_FMA)
def _g_row(T: np.ndarray, i: int, home_inv: np.ndarray, a: int) -> tuple:
    """Row a of G = T[i]·M⁻¹ (rotation part, then translation)."""
    t0, t1, t2 = T[i, a, 0], T[i, a, 1], T[i, a, 2]
    return (
        t0 * home_inv[0, 0] + t1 * home_inv[1, 0] + t2 * home_inv[2, 0],
        t0 * home_inv[0, 1] + t1 * home_inv[1, 1] + t2 * home_inv[2, 1],
        t0 * home_inv[0, 2] + t1 * home_inv[1, 2] + t2 * home_inv[2, 2],
        t0 * home_inv[0, 3] + t1 * home_inv[1, 3] + t2 * home_inv[2, 3] + T[i, a, 3],
    )


@njit(cache=True, fastmath=_FMA)
def _is_rigid(T: np.ndarray, i: int, tol: float) -> bool:
    """Finite, orthonormal rotation with det +1 and last row [0, 0, 0, 1] (as ik._rigid)."""
    for a in range(4):
        for b in range(4):
            if not math.isfinite(T[i, a, b]):
                return False
    worst = 0.0
    for a in range(3):
        for b in range(3):
            e = T[i, a, 0] * T[i, b, 0] + T[i, a, 1] * T[i, b, 1] + T[i, a, 2] * T[i, b, 2]
            worst = max(worst, abs(e - (1.0 if a == b else 0.0)))
    x, y, z = _row3(T, i, 0), _row3(T, i, 1), _row3(T, i, 2)
    det = _dot(x, _cross(y, z))
    bottom = max(abs(T[i, 3, 0]), abs(T[i, 3, 1]), abs(T[i, 3, 2]), abs(T[i, 3, 3] - 1.0))
    return worst < tol and det > 0.0 and bottom < tol


@njit(cache=True, nogil=True, fastmath=_FMA)
def _geometry(
    T: np.ndarray,
    q_prev: np.ndarray,
    wrist_tol: float,
    w: np.ndarray,
    r: np.ndarray,
    c_arr: np.ndarray,
    home_inv: np.ndarray,
    u_arr: np.ndarray,
    flip: bool,
    same23: float,
    rigid_tol: float,
    Y: np.ndarray,
    X: np.ndarray,
    rigid: np.ndarray,
    shoulder: np.ndarray,
    reach_out: np.ndarray,
    sing_out: np.ndarray,
) -> None:
    """The closed form up to the atan2 arguments (Y, X) of every angle, per pose."""
    w0, w1, w2, w3, w4, w5 = _row(w, 0), _row(w, 1), _row(w, 2), _row(w, 3), _row(w, 4), _row(w, 5)
    r0, r1, r2 = _row(r, 0), _row(r, 1), _row(r, 2)
    c = _row2(c_arr)
    u_side = _row2(u_arr)
    c0 = _sub(c, r0)
    # Subproblem 3 (θ3 from the distance axis 2 → wrist centre): the pose-independent part.
    u3, v3 = _sub(c, r2), _sub(r1, r2)
    _, s0, cos0 = _angle(w2, u3, v3)
    up3, vp3 = _perp(u3, w2), _perp(v3, w2)
    a3, b3 = math.sqrt(_dot(up3, up3)), math.sqrt(_dot(vp3, vp3))
    h3 = _dot(w2, _sub(u3, v3))
    # Subproblem 2 (θ4, θ5 bring axis 6 into place): the pose-independent part.
    k45 = _dot(w3, w4)
    cr45 = _cross(w3, w4)
    inv_cross2 = 1.0 / _dot(cr45, cr45)
    inv_denom = 1.0 / (k45 * k45 - 1.0)
    wrist_tol2 = wrist_tol * wrist_tol
    w4u = _dot(w4, w5)
    n_sol = 1 if flip else 2
    sk4, sk5 = np.empty((2, 2)), np.empty((2, 2))  # (sin, 1 − cos) of θ4, θ5 per solution
    for i in range(T.shape[0]):
        rigid[i] = _is_rigid(T, i, rigid_tol)
        if not rigid[i]:
            for j in range(Y.shape[1]):  # defined numbers for the atan2 pass
                Y[i, j], X[i, j] = 0.0, 1.0
            continue
        # G = T·M⁻¹: where the home pose must go. Its rotation acts on three vectors:
        # the wrist centre, the axis-6 direction and a vector across axis 6.
        g0, g1, g2 = _g_row(T, i, home_inv, 0), _g_row(T, i, home_inv, 1), _g_row(T, i, home_inv, 2)
        p = (_dot(g0, c) + g0[3], _dot(g1, c) + g1[3], _dot(g2, c) + g2[3])
        g6 = (_dot(g0, w5), _dot(g1, w5), _dot(g2, w5))
        gside = (_dot(g0, u_side), _dot(g1, u_side), _dot(g2, u_side))
        # θ1 turns the home wrist centre's direction onto the target's, or that + 180°.
        p0 = _sub(p, r0)
        Y[i, 0], X[i, 0], s1, cs1 = _angle_yx(w0, c0, p0)
        d1 = _perp(p0, w0)
        shoulder[i] = _dot(d1, d1) < _SHOULDER_TOL2
        if shoulder[i]:  # wrist centre on axis 1: θ1 keeps its previous value
            s1, cs1 = math.sin(q_prev[i, 0]), math.cos(q_prev[i, 0])
        for b1 in range(2):
            if b1 == 1:
                s1, cs1 = -s1, -cs1
            sk1 = _turn(s1, cs1)
            pa = _add(_rotate(w0, sk1, p0, -1.0), r0)  # the target wrist centre, arm plane
            da = _sub(pa, r1)
            # Subproblem 3: the elbow angle φ of the triangle axis 2 – axis 3 – wrist.
            d2 = _dot(da, da) - h3 * h3
            d = math.sqrt(max(d2, 0.0))
            f1, f2, f3 = d - a3 + b3, d + a3 - b3, a3 + b3 - d
            feasible = (
                d2 >= -2.0 * _REACH_TOL * max(d, 1.0)
                and f1 >= -_REACH_TOL
                and f2 >= -_REACH_TOL
                and f3 >= -_REACH_TOL
            )
            reach_out[i, b1] = feasible and a3 > _REACH_TOL and b3 > _REACH_TOL
            heron = max(f1, 0.0) * max(f2, 0.0) * max(f3, 0.0) * (a3 + b3 + d)
            sin_phi = math.sqrt(heron)
            cos_phi = a3 * a3 + b3 * b3 - d * d
            n_phi = math.sqrt(sin_phi * sin_phi + cos_phi * cos_phi)
            if not (feasible and a3 > 0.0 and b3 > 0.0 and n_phi > 0.0):
                sin_phi, cos_phi, n_phi = 0.0, 1.0, 1.0
            Y[i, 1 + b1], X[i, 1 + b1] = sin_phi, cos_phi
            sin_phi, cos_phi = sin_phi / n_phi, cos_phi / n_phi
            v6_1 = _rotate(w0, sk1, g6, -1.0)
            side_1 = _rotate(w0, sk1, gside, -1.0)
            for elbow in range(2):
                a = 2 * b1 + elbow
                sign = 1.0 - 2.0 * elbow  # θ3 = θ0 ± φ
                s3 = s0 * cos_phi + sign * cos0 * sin_phi
                cs3 = cos0 * cos_phi - sign * s0 * sin_phi
                sk3 = _turn(s3, cs3)
                c3 = _add(_rotate(w2, sk3, u3, 1.0), r2)
                Y[i, 3 + a], X[i, 3 + a], s2, cs2 = _angle_yx(w1, _sub(c3, r1), da)
                # Axis 6's direction and a vector across it, seen from the forearm.
                if same23 != 0.0:  # axes 2, 3 along one direction: one turn by θ2 ± θ3
                    sk23 = _turn(s2 * cs3 + same23 * cs2 * s3, cs2 * cs3 - same23 * s2 * s3)
                    v6 = _rotate(w1, sk23, v6_1, -1.0)
                    side = _rotate(w1, sk23, side_1, -1.0)
                else:
                    sk2 = _turn(s2, cs2)
                    v6 = _rotate(w2, sk3, _rotate(w1, sk2, v6_1, -1.0), -1.0)
                    side = _rotate(w2, sk3, _rotate(w1, sk2, side_1, -1.0), -1.0)
                # Subproblem 2: e^{S4θ4} e^{S5θ5} w6 = v6, two solutions (±γ).
                aa = (k45 * w4u - _dot(w3, v6)) * inv_denom
                bb = (k45 * _dot(w3, v6) - w4u) * inv_denom
                vq = _perp(v6, w3)
                gamma2 = (_dot(vq, vq) - bb * bb * (1.0 - k45 * k45)) * inv_cross2
                g = math.sqrt(max(gamma2, 0.0))
                sing = _dot(vq, vq) < wrist_tol2  # axis 6 along axis 4
                sing_out[i, a] = sing
                for s in range(n_sol):
                    gs = g * (1.0 - 2.0 * s)
                    cs = (
                        aa * w3[0] + bb * w4[0] + gs * cr45[0],
                        aa * w3[1] + bb * w4[1] + gs * cr45[1],
                        aa * w3[2] + bb * w4[2] + gs * cr45[2],
                    )
                    y5, x5, sin5, cos5 = _angle_yx(w4, w5, cs)
                    y4, x4, sin4, cos4 = _angle_yx(w3, cs, v6)
                    if sing:  # only θ4 + θ6 is determined: θ4 keeps its previous value
                        half = math.sin(0.5 * q_prev[i, 3])
                        sin4, cos4 = math.sin(q_prev[i, 3]), 1.0 - 2.0 * half * half
                        held = _rotate(w3, _turn(sin4, cos4), v6, -1.0)
                        y5, x5, sin5, cos5 = _angle_yx(w4, w5, held)
                    Y[i, _col(0, s, a)], X[i, _col(0, s, a)] = y4, x4
                    Y[i, _col(1, s, a)], X[i, _col(1, s, a)] = y5, x5
                    sk4[s, 0], sk4[s, 1] = _turn(sin4, cos4)
                    sk5[s, 0], sk5[s, 1] = _turn(sin5, cos5)
                for s in range(n_sol):
                    turned = _rotate(w3, (sk4[s, 0], sk4[s, 1]), side, -1.0)
                    turned = _rotate(w4, (sk5[s, 0], sk5[s, 1]), turned, -1.0)
                    Y[i, _col(2, s, a)], X[i, _col(2, s, a)], _, _ = _angle_yx(w5, u_side, turned)


@njit(cache=True, nogil=True, fastmath=_FMA)
def _assemble(
    A: np.ndarray,
    q_prev: np.ndarray,
    flip: bool,
    theta0: float,
    rigid: np.ndarray,
    shoulder: np.ndarray,
    reach_in: np.ndarray,
    sing_in: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    counts: np.ndarray,
    limit_tol: float,
    base_q: np.ndarray,
    reachable: np.ndarray,
    turn_ok: np.ndarray,
    singular: np.ndarray,
    status: np.ndarray,
) -> None:
    """The eight branches from the angles A, wrapped into the limits with their
    whole-turn masks, and the status of each pose."""
    q = np.empty(6)
    m = np.zeros(6, dtype=turn_ok.dtype)
    for i in range(A.shape[0]):
        if not rigid[i]:
            for slot in range(8):
                reachable[i, slot] = False
                singular[i, slot] = False
                for j in range(6):
                    base_q[i, slot, j] = np.nan
                    turn_ok[i, slot, j] = 0
            status[i] = 5  # INVALID_POSE
            continue
        th1 = q_prev[i, 0] if shoulder[i] else A[i, 0]
        any_ok = False
        any_valid = False
        any_singular = False
        for b1 in range(2):
            if b1 == 1:
                th1 = _wrap(th1 + math.pi)
            x1, bits1 = _place(th1, lo[0], hi[0], counts[0], limit_tol)
            reach = reach_in[i, b1]
            for elbow in range(2):
                a = 2 * b1 + elbow
                sing = sing_in[i, a]
                th3 = _wrap(theta0 + (1.0 - 2.0 * elbow) * A[i, 1 + b1])
                x2, bits2 = _place(A[i, 3 + a], lo[1], hi[1], counts[1], limit_tol)
                x3, bits3 = _place(th3, lo[2], hi[2], counts[2], limit_tol)
                arm_inside = reach and bits1 != 0 and bits2 != 0 and bits3 != 0
                for s in range(2):
                    src = 0 if flip else s
                    t4 = q_prev[i, 3] if sing else A[i, _col(0, src, a)]
                    t5, t6 = A[i, _col(1, src, a)], A[i, _col(2, src, a)]
                    if flip and s == 1 and not sing:  # the flipped wrist, same rotation
                        t4, t5, t6 = _wrap(t4 + math.pi), -t5, _wrap(t6 + math.pi)
                    x4, bits4 = _place(t4, lo[3], hi[3], counts[3], limit_tol)
                    x5, bits5 = _place(t5, lo[4], hi[4], counts[4], limit_tol)
                    x6, bits6 = _place(t6, lo[5], hi[5], counts[5], limit_tol)
                    slot = 4 * b1 + 2 * elbow + s
                    reachable[i, slot] = reach
                    singular[i, slot] = sing and reach
                    if reach:
                        q[0], q[1], q[2], q[3], q[4], q[5] = x1, x2, x3, x4, x5, x6
                        m[0], m[1], m[2], m[3], m[4], m[5] = (
                            bits1,
                            bits2,
                            bits3,
                            bits4,
                            bits5,
                            bits6,
                        )
                    else:
                        for j in range(6):
                            q[j], m[j] = np.nan, 0
                    for j in range(6):  # element by element: no array views in the loop
                        base_q[i, slot, j] = q[j]
                        turn_ok[i, slot, j] = m[j]
                    inside = arm_inside and bits4 != 0 and bits5 != 0 and bits6 != 0
                    any_ok = any_ok or reach
                    any_valid = any_valid or inside
                    any_singular = any_singular or (inside and sing)
        if any_singular:
            status[i] = 1  # WRIST_SINGULAR
        elif any_valid:
            status[i] = 0  # OK
        elif any_ok:
            status[i] = 2  # BEYOND_LIMITS
        else:
            status[i] = 3  # UNREACHABLE
