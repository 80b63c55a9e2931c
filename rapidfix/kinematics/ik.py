"""All-branch inverse kinematics: analytic branches, ±360° variants, limits, statuses.

`solve_all(model, T)` is what `RobotModel.ik` calls. For a nominal model the eight
branches come in closed form (ik_analytic, or its compiled twin ik_compiled when
numba is installed); for an actual model they are the nominal branches refined on
the actual screws (ik_numeric). Every branch is then checked against the limits
for each whole-turn shift the axis's range allows (axes 4 and 6 of most ABB arms
have more than one turn; axis 3's range may leave (-180°, 180°]). The result keeps
the eight branches and, per axis, a bit mask of the turn variants within the
limits; `IKSolutions` expands every combination only when a caller asks.
"""

from __future__ import annotations

import os
from contextlib import AbstractContextManager
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from rapidfix import chunks
from rapidfix.compiled import BACKEND_ENV, Switch, load_kernel
from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics.batches import as_joint_batch, as_pose_batch
from rapidfix.kinematics.frames import flange_target
from rapidfix.kinematics.ik_analytic import analytic_solver
from rapidfix.kinematics.ik_numeric import refine
from rapidfix.kinematics.ik_result import IKSolutions, IKStatus, mask_dtype
from rapidfix.kinematics.screws import invert_transform

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rapidfix.kinematics.frames import Tool, WorkObject
    from rapidfix.kinematics.robot_model import RobotModel

WRIST_TOL = 1e-7
"""|sin θ5| below which the wrist counts as singular (θ4 is then held)."""

LIMIT_TOL = 1e-7
"""rad by which an angle may pass a joint limit and still count as inside. Near a
stretched elbow the closed form is good to about √eps (~1e-8 rad), so a pose taught at
a limit must not be refused for that; 1e-7 rad is 0.1 µm at a metre."""
RIGID_TOL = 1e-6
"""Largest deviation from an orthonormal rotation and a [0, 0, 0, 1] last row."""
_FIXED_POINT_STEPS = 6
_AUTO_NUMPY = Switch("rapidfix_ik_auto_numpy")


def numpy_closed_form() -> AbstractContextManager[None]:
    """Inside the block, "auto" solves in numpy: for work too small to pay for loading
    the compiled kernel (numba reads its cached machine code on first use, about half a
    second, more than numpy takes for ten thousand poses)."""
    return _AUTO_NUMPY.on()


def turn_counts(limits: np.ndarray) -> tuple[int, ...]:
    """Number of whole-turn variants per axis: the turns its range spans, plus one.

    An angle is first wrapped into [lo, lo + 2π); variant k adds k turns. An axis
    with exactly ±180° gets two, so that both −180° and +180° are offered.
    """
    return tuple(
        int(np.floor((hi - lo + 2.0 * LIMIT_TOL) / (2.0 * np.pi))) + 1 for lo, hi in limits
    )


def _rigid(T: np.ndarray) -> np.ndarray:
    """(N,) mask: finite, orthonormal rotation with det +1 and last row [0, 0, 0, 1]."""
    finite = np.all(np.isfinite(T), axis=(1, 2))
    Ts = np.where(finite[:, None, None], T, np.eye(4))
    R = Ts[:, :3, :3]
    ortho = np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max(axis=(1, 2)) < RIGID_TOL
    det = np.einsum("ni,ni->n", R[:, 0], np.cross(R[:, 1], R[:, 2])) > 0
    row = np.abs(Ts[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1) < RIGID_TOL
    return finite & ortho & det & row


def _prev_batch(q_prev: np.ndarray | None, n: int) -> np.ndarray:
    if q_prev is None:
        return np.zeros((n, 6))
    qp, _ = as_joint_batch(q_prev)
    if qp.shape[0] == 1:
        return np.broadcast_to(qp, (n, 6))
    if qp.shape[0] != n:
        raise KinematicsError(f"q_prev has {qp.shape[0]} rows for {n} poses")
    if not np.all(np.isfinite(qp)):
        raise KinematicsError("q_prev contains NaN or infinite values")
    return qp


def _base_branches(
    model: RobotModel, T: np.ndarray, q_prev: np.ndarray, wrist_tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    solver = analytic_solver(model.nominal)
    q8, ok8, sing8 = solver.base_branches(T, q_prev, wrist_tol)
    if model.is_nominal:
        return q8, ok8, sing8
    # Actual model. Branch-preserving fixed point first: solve the nominal model for
    # the target corrected by the current model difference, T' = F_n(q) F_a(q)⁻¹ T,
    # keeping each branch's own closed-form solution (the perturbation is small, so
    # this contracts fast and never hops between elbow or wrist branches). Newton on
    # the actual model then finishes to 1e-10 mm.
    n = T.shape[0]
    goals = np.repeat(T, 8, axis=0)
    prev = np.repeat(q_prev, 8, axis=0)
    pick = np.tile(np.arange(8), n)
    q = q8.reshape(-1, 6)
    for _ in range(_FIXED_POINT_STEPS):
        corrected = model.nominal.fk(q) @ invert_transform(model.fk(q)) @ goals
        q_all, _, _ = solver.base_branches(corrected, prev, wrist_tol)
        q = q_all[np.arange(q.shape[0]), pick]
    q_ref, conv = refine(model, goals, q)
    return q_ref.reshape(q8.shape), conv.reshape(ok8.shape), sing8


def limit_masks(
    q8: np.ndarray,
    ok8: np.ndarray,
    limits: np.ndarray,
    counts: tuple[int, ...],
    out_q: np.ndarray,
    out_turn_ok: np.ndarray,
) -> None:
    """Wrap branch angles q8 (n, 8, 6) into [lo, lo + 2π) per axis (NaN where not ok8)
    into out_q, and set bit k of out_turn_ok (n, 8, 6) when angle + k turns is within
    the limits. The wrap starts a hair below lo, so that an angle at a limit is
    offered at both ends of a range of a whole number of turns.

    Every variant is then at or above the lower limit, so only the upper one is
    checked, and the variants inside are the first few: the mask is 2^m − 1."""
    lo, hi = limits[:, 0], limits[:, 1]
    start = lo - LIMIT_TOL
    np.subtract(q8, start, out=out_q)
    _mod_turn(out_q)
    out_q += start
    out_q[~ok8] = np.nan
    top = hi + LIMIT_TOL
    inside = (out_q <= top).astype(out_turn_ok.dtype)  # m: the variants inside
    for k in range(1, max(counts)):
        for j in np.flatnonzero(np.asarray(counts) > k):
            inside[:, :, j] += out_q[:, :, j] + 2.0 * np.pi * k <= top[j]
    np.left_shift(1, inside, out=out_turn_ok, dtype=out_turn_ok.dtype)
    out_turn_ok -= 1


def _mod_turn(d: np.ndarray) -> None:
    """d mod 2π in place, the very values np.mod gives, but one exact add or subtract
    for the usual d in [−2π, 4π) (np.mod's general remainder is ~10× slower)."""
    two_pi = 2.0 * np.pi
    far = (d < -two_pi) | (d >= 2.0 * two_pi)
    rare = d[far]  # e.g. a held θ4 of many turns
    low, high = d < 0.0, d >= two_pi
    np.add(d, two_pi, out=d, where=low)
    np.subtract(d, two_pi, out=d, where=high)
    d[far] = np.mod(rare, two_pi)


def _statuses(
    rigid: np.ndarray, ok8: np.ndarray, turn_ok: np.ndarray, sing8: np.ndarray
) -> np.ndarray:
    valid = ok8 & np.all(turn_ok != 0, axis=2)
    status = np.full(ok8.shape[0], IKStatus.UNREACHABLE, dtype=np.int8)
    status[ok8.any(axis=1)] = IKStatus.BEYOND_LIMITS
    status[valid.any(axis=1)] = IKStatus.OK
    status[(valid & sing8).any(axis=1)] = IKStatus.WRIST_SINGULAR
    status[~rigid] = IKStatus.INVALID_POSE
    return status


def _solve_chunk(
    model: RobotModel,
    T: np.ndarray,
    q_prev: np.ndarray,
    wrist_tol: float,
    counts: tuple[int, ...],
    out: Sequence[np.ndarray],
) -> None:
    """Solve one chunk with numpy into the given output views (compact form)."""
    out_q, out_ok, out_turn_ok, out_singular, out_status = out
    rigid = _rigid(T)
    Ts = np.where(rigid[:, None, None], T, np.eye(4))
    q8, ok8, sing8 = _base_branches(model, Ts, q_prev, wrist_tol)
    ok8 &= rigid[:, None]
    limit_masks(q8, ok8, np.asarray(model.limits), counts, out_q, out_turn_ok)
    out_ok[...] = ok8
    np.logical_and(sing8, ok8, out=out_singular)
    out_status[...] = _statuses(rigid, ok8, out_turn_ok, out_singular)


def _compiled() -> ModuleType | None:
    """The numba kernel module, or None when numba is not installed (or fails to import)."""
    return load_kernel("rapidfix.kinematics.ik_compiled")


def accelerated() -> bool:
    """True when the compiled (numba) closed form is available."""
    return _compiled() is not None


def backend_for(model: RobotModel, backend: str | None = None) -> str:
    """The code that will solve `model`'s closed form: "numba" or "numpy".

    `backend` None reads the environment variable RAPIDFIX_IK_BACKEND (default
    "auto"). "auto" takes the compiled kernel when numba is importable and the
    model is nominal (an actual model's refinement is numpy), except inside
    `numpy_closed_form`. Asking for "numba"
    without numba installed raises KinematicsError.
    """
    if backend is None:
        backend = os.environ.get(BACKEND_ENV, "auto").strip().lower() or "auto"
    if backend not in ("auto", "numpy", "numba"):
        raise KinematicsError(f"unknown IK backend {backend!r} (auto, numpy, numba)")
    if backend == "numba" and not accelerated():
        raise KinematicsError("the numba IK backend needs numba: pip install 'rapidfix[fast]'")
    if backend == "numpy" or not model.is_nominal or (backend == "auto" and _AUTO_NUMPY.get()):
        return "numpy"
    return "numba" if accelerated() else "numpy"


def prepare(model: RobotModel) -> None:
    """Load the compiled closed form for `model` now, if it is the one that will be used.

    numba reads its cached machine code on a kernel's first call (about 0.4 s);
    a tool that loads a robot once and then solves many batches (every file of
    a batch run) pays that here, once, instead of inside its first batch.
    """
    if backend_for(model) == "numba":
        solve_all(model, np.array(model.home)[None])  # writable, as in real use


def solve_all(
    model: RobotModel,
    T: np.ndarray,
    *,
    tool: Tool | np.ndarray | None = None,
    wobj: WorkObject | np.ndarray | None = None,
    q_prev: np.ndarray | None = None,
    wrist_tol: float = WRIST_TOL,
    chunk: int = chunks.IK_SOLVE,
    backend: str | None = None,
) -> IKSolutions:
    """Every solution for poses T (N, 4, 4) (or (4, 4)), tool0 in the base frame.

    With `tool` and/or `wobj`, T is the TCP pose in the work-object frame (a
    robtarget) and is first turned into the flange pose. `q_prev` (N, 6) or (6,)
    supplies θ4 at wrist singularities (default 0). Never raises for a bad pose:
    it gets its status (INVALID_POSE, UNREACHABLE, BEYOND_LIMITS). `backend` picks
    the closed-form code (see `backend_for`); the numpy path works in chunks of
    `chunk` poses to keep its temporaries in cache and memory bounded.
    """
    Tb, _ = as_pose_batch(T)
    if tool is not None or wobj is not None:
        Tb = flange_target(Tb, tool, wobj)
    n = Tb.shape[0]
    prev = _prev_batch(q_prev, n)
    limits = np.asarray(model.limits)
    counts = turn_counts(limits)
    out = (
        np.empty((n, 8, 6)),
        np.empty((n, 8), dtype=bool),
        np.empty((n, 8, 6), dtype=mask_dtype(counts)),
        np.empty((n, 8), dtype=bool),
        np.empty(n, dtype=np.int8),
    )
    used = backend_for(model, backend)
    if used == "numba":
        solver = analytic_solver(model)
        kernel = _compiled()
        kernel.solve_nominal(solver, Tb, prev, wrist_tol, limits, counts, LIMIT_TOL, RIGID_TOL, out)
    else:
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for start in range(0, n, max(1, chunk)):  # bounded temporaries; each vectorised
                sl = slice(start, start + chunk)
                _solve_chunk(model, Tb[sl], prev[sl], wrist_tol, counts, [a[sl] for a in out])
    base_q, reachable, turn_ok, singular, status = out
    return IKSolutions(
        base_q=base_q,
        reachable=reachable,
        turn_ok=turn_ok,
        base_singular=singular,
        status=status,
        counts=counts,
        backend=used,
    )
