"""`confdata.select_by_conf` compiled with numba: one pass over the poses, no temporaries.

The numpy route builds (poses × 8 branches × 6 axes) arrays for the quadrant tests and
a forward kinematics of the arm's three axes for every candidate branch, about 4 µs a
pose; here each pose's eight branches are tested in registers. The tests are the
numpy route's, in the same order: the first whole turn of each axis that the limits
and the confdata's quadrant (axes 1, 4, 6) or sign (axis 5) allow, then the wrist
centre's side of axis 1 and of the lower arm on that joint vector, with the rounding
tolerances and the preference for an exact match. The joint angles returned are the
same numbers (a branch angle plus whole turns); only the wrist-centre distances are
computed in another order, so they agree to rounding (~1e-13 mm), which decides
nothing unless a centre lies that close to a tolerance's edge.

Used where the IK's compiled closed form is (`IKSolutions.backend == "numba"`). This
module imports numba; `confdata` imports it only when numba is installed.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_TWO_PI = 2.0 * np.pi
_QUADRANT = np.pi / 2


@njit(cache=True)
def _turn(w: np.ndarray, theta: float) -> tuple:
    """Rodrigues' rotation (rows) by theta about the unit axis w, as `screws.rotation_about`."""
    s = math.sin(theta)
    half = math.sin(0.5 * theta)
    vers = 2.0 * half * half
    x, y, z = w[0], w[1], w[2]
    return ((1.0 - vers * (y * y + z * z), vers * x * y - s * z, vers * x * z + s * y),
            (vers * x * y + s * z, 1.0 - vers * (x * x + z * z), vers * y * z - s * x),
            (vers * x * z - s * y, vers * y * z + s * x, 1.0 - vers * (x * x + y * y)))


@njit(cache=True)
def _apply(rot: tuple, v: tuple) -> tuple:
    return (rot[0][0] * v[0] + rot[0][1] * v[1] + rot[0][2] * v[2],
            rot[1][0] * v[0] + rot[1][1] * v[1] + rot[1][2] * v[2],
            rot[2][0] * v[0] + rot[2][1] * v[1] + rot[2][2] * v[2])


@njit(cache=True)
def _compose(a: tuple, b: tuple) -> tuple:
    """The rotation a·b (rows)."""
    cols = (_apply(a, (b[0][0], b[1][0], b[2][0])), _apply(a, (b[0][1], b[1][1], b[2][1])),
            _apply(a, (b[0][2], b[1][2], b[2][2])))
    return ((cols[0][0], cols[1][0], cols[2][0]), (cols[0][1], cols[1][1], cols[2][1]),
            (cols[0][2], cols[1][2], cols[2][2]))


@njit(cache=True)
def _sub(a: tuple, b: tuple) -> tuple:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def _add(a: tuple, b: tuple) -> tuple:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True)
def _dot(a: tuple, b: tuple) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _cross(a: tuple, b: tuple) -> tuple:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def _vec(m: np.ndarray, i: int) -> tuple:
    return (m[i, 0], m[i, 1], m[i, 2])


@njit(cache=True)
def _wrist_sides(q: np.ndarray, w: np.ndarray, r: np.ndarray, c0: tuple, fwd0: tuple,
                 side_sign: float) -> tuple:
    """(wrist centre ahead of axis 1, ahead of the lower arm) in mm for joints q, as
    `confdata.conf_quantities` measures them. `conf_columns._sides` forms the same sums
    in numpy columns, where numba is not installed: a change here belongs there too."""
    p0 = _vec(r, 0)
    p1 = _vec(r, 1)
    p2 = _vec(r, 2)
    rot1 = _turn(w[0], q[0])
    t1 = _sub(p0, _apply(rot1, p0))
    rot2 = _turn(w[1], q[1])
    t2 = _sub(p1, _apply(rot2, p1))
    rot3 = _turn(w[2], q[2])
    t3 = _sub(p2, _apply(rot3, p2))
    rot12 = _compose(rot1, rot2)
    t12 = _add(_apply(rot1, t2), t1)
    rot123 = _compose(rot12, rot3)
    t123 = _add(_apply(rot12, t3), t12)
    c = _add(_apply(rot123, c0), t123)
    ahead1 = _dot(_sub(c, p0), _apply(rot1, fwd0))
    a2 = _add(_apply(rot1, p1), t1)
    a3 = _add(_apply(rot12, p2), t12)
    w2 = _apply(rot1, _vec(w, 1))
    arm = _sub(a3, a2)
    arm_len = math.sqrt(_dot(arm, arm))
    side = _dot(_cross(arm, _sub(c, a2)), w2) / arm_len * side_sign
    return ahead1, side


@njit(cache=True)
def wrist_sides_rows(q: np.ndarray, w: np.ndarray, r: np.ndarray, c0: np.ndarray,
                     fwd0: np.ndarray, side_sign: float, out: np.ndarray) -> None:
    """`_wrist_sides` of every joint vector of q (M, 6) into out (M, 2): what
    `confdata.conf_quantities` measures of the wrist centre, in one pass."""
    centre = (c0[0], c0[1], c0[2])
    forward = (fwd0[0], fwd0[1], fwd0[2])
    for i in range(q.shape[0]):
        ahead1, side = _wrist_sides(q[i], w, r, centre, forward, side_sign)
        out[i, 0] = ahead1
        out[i, 1] = side


@njit(cache=True)
def _matches(q: np.ndarray, ahead1: float, side: float, conf: np.ndarray, tol: float,
             tol_mm: float) -> bool:
    """`confdata._quantities_match` of one joint vector."""
    for j, k in ((0, q[0]), (1, q[3]), (2, q[5])):
        lo = math.floor((k - tol) / _QUADRANT)
        hi = math.floor((k + tol) / _QUADRANT)
        if not (lo <= conf[j] and conf[j] <= hi):
            return False
    cfx = conf[3]
    for bit, value, t in ((4, ahead1, tol_mm), (2, side, tol_mm), (1, q[4], tol)):
        if (cfx & bit) != 0:
            if not value < t:
                return False
        elif not value > -t:
            return False
    return (math.isfinite(q[0]) and math.isfinite(q[3]) and math.isfinite(q[5])
            and math.isfinite(ahead1) and math.isfinite(side) and math.isfinite(q[4]))


@njit(cache=True)
def select_on_conf(base_q: np.ndarray, reachable: np.ndarray, turn_ok: np.ndarray,
                   counts: np.ndarray, conf: np.ndarray, w: np.ndarray, r: np.ndarray,
                   c0: np.ndarray, fwd0: np.ndarray, side_sign: float, tol: float,
                   tol_mm: float, exact_tol: float, q_out: np.ndarray, found: np.ndarray,
                   chosen: np.ndarray, any_valid: np.ndarray, redo: np.ndarray) -> None:
    """Per pose: the joints (NaN: none) of the branch `select_by_conf` picks, whether one
    matched, which branch, whether any branch is valid at all, and whether the pose
    must be settled slot by slot (an axis with several turns that pass the tests)."""
    centre = (c0[0], c0[1], c0[2])
    forward = (fwd0[0], fwd0[1], fwd0[2])
    cand = np.empty(6)
    for i in range(base_q.shape[0]):
        first_match = -1
        first_exact = -1
        valid = False
        unsettled = np.zeros(8, dtype=np.bool_)
        wants_neg = (conf[i, 3] & 1) != 0
        for b in range(8):
            if not reachable[i, b]:
                continue
            every = True
            for j in range(6):
                if turn_ok[i, b, j] == 0:
                    every = False
            valid = valid or every
            several = False
            usable = True
            for j in range(6):
                pick = -1
                for k in range(counts[j]):
                    if ((turn_ok[i, b, j] >> k) & 1) == 0:
                        continue
                    angle = base_q[i, b, j] + _TWO_PI * k
                    ok = True
                    if j == 0 or j == 3 or j == 5:
                        want = conf[i, 0 if j == 0 else (1 if j == 3 else 2)]
                        lo = math.floor((angle - tol) / _QUADRANT)
                        hi = math.floor((angle + tol) / _QUADRANT)
                        ok = lo <= want and want <= hi
                    elif j == 4:
                        ok = angle < tol if wants_neg else angle > -tol
                    if ok:
                        if pick < 0:
                            pick = k
                        else:
                            several = True
                if pick < 0:
                    usable = False
                else:
                    cand[j] = base_q[i, b, j] + _TWO_PI * pick
            if not usable:
                continue
            ahead1, side = _wrist_sides(cand, w, r, centre, forward, side_sign)
            match = _matches(cand, ahead1, side, conf[i], tol, tol_mm)
            if match:
                if first_match < 0:
                    first_match = b
                    q_out[i, :] = cand
                if first_exact < 0 and _matches(cand, ahead1, side, conf[i], exact_tol,
                                                exact_tol):
                    first_exact = b
                    q_out[i, :] = cand
            elif several:
                unsettled[b] = True
        any_valid[i] = valid
        found[i] = first_match >= 0
        pick = first_exact if first_exact >= 0 else max(first_match, 0)
        chosen[i] = pick
        if first_match < 0:
            q_out[i, :] = np.nan
        stop = pick if first_match >= 0 else 8
        flag = False
        for b in range(stop):
            flag = flag or unsettled[b]
        redo[i] = flag


__all__ = ["select_on_conf"]
