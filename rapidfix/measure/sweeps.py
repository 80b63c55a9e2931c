"""Joint sweeps → actual joint angles: the per-joint motion error Δθ(θ) and its repeatability.

In a sweep one joint moves over its range while the others stay fixed; the target
ball draws a circle about the moving joint's axis, and where on the circle it is
tells the actual joint angle. All sweeps are solved together, with the tracker
pose, as one least-squares problem:

    unknowns  tracker pose (3 rotation + 3 translation) and one Δθ per distinct
              commanded value of every joint (the swept samples *and* the values the
              other joints were held at — a value shared by several sweeps is one
              unknown, since the per-joint error depends on the commanded angle only);
              plus, per joint, its backlash play b and the offset of the rows taken
              before the joint's first motion (whose side of the play is unknown);
    data      p_tracker,i = R · FK(θ_cmd,i + Δθ) · ball + t  for every row;
    backlash  a joint stops b/2 short of where it was sent, against the direction it
              last moved (from the row order: rows are in execution order, a joint
              that did not move keeps its last direction), so a row's actual angle is
              θ_cmd + Δθ(θ_cmd) − (b/2)·d. Δθ is the curve midway between the two
              directions, and samples approached from either side, in any order, all
              inform it; without backlash b fits to noise and the curves stay put
              (a joint never reached from both sides keeps b = 0);
    gauge     the joint-1 error is zero at θ1 = 0 (a constant joint-1 error is a
              tracker turned about axis 1; `registration` holds it);
    prior     a weak pull of every Δθ towards 0 (σ = `prior_deg`) that only decides
              the directions the data cannot see (e.g. a fixed joint seen by one sweep).

It starts from a robust rigid fit of the nominal positions (`register`), solves
with a robust (soft-L1) loss by Gauss–Newton on sparse normal equations with an
analytic Jacobian, then drops the rows whose residual lies far outside the bulk one
by one (reported as outliers), solving again after each. Nothing assumes a
particular fixed pose, step, range or number of repeats. Per sample it reports
the mean Δθ over the repeats, their spread (repeatability) and the standard error
of the estimate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial.transform import Rotation

from rapidfix.exceptions import MeasurementError
from rapidfix.kinematics import RobotModel
from rapidfix.measure.files import Setup, SweepTable
from rapidfix.measure.registration import (
    Registration,
    move_joint1_offset,
    outlier_mask,
    register,
)

MIN_RADIUS_MM = 5.0  # a ball closer than this to the swept axis draws no usable circle
MAX_AXIS_TILT_DEG = 2.0  # a circle tilted more than this from the joint's axis is wrong data
MAX_RIGID_RMS_MM = 10.0  # nominal positions that far from the data: wrong robot/ball/units
DEFAULT_SIGMA_MM = 0.01
ROBUST_SCALE = 3.0  # soft-L1 loss: residuals beyond this many σ count linearly
NOISE_FLOOR_SIGMAS = 6.0  # residuals below this many tracker σ are never outliers
MAX_OUTLIER_FRACTION = 0.01  # outliers are isolated: at most this share of the rows ...
MIN_OUTLIER_BUDGET = 5  # ... or this many


@dataclass(frozen=True)
class JointSweep:
    """Δθ of one joint at its swept commanded angles (ascending), all rad.

    `delta` is the mean over the repeats, `repeat_std` their standard deviation
    (NaN with one repeat), `delta_std` the standard error of `delta`, `n` the
    number of measurements used per sample. Empty arrays when the joint was not swept.
    """

    theta_cmd: np.ndarray
    delta: np.ndarray
    repeat_std: np.ndarray
    delta_std: np.ndarray
    n: np.ndarray

    @property
    def repeatability_rad(self) -> float:
        """RMS of the per-sample repeat spread (NaN without repeats)."""
        s = self.repeat_std[np.isfinite(self.repeat_std)]
        return float(np.sqrt(np.mean(s**2))) if len(s) else float("nan")


@dataclass(frozen=True)
class SweepCircle:
    """Diagnostics of one sweep: the circle its (registered) ball positions draw."""

    joint: int
    first_row: int
    last_row: int
    radius_mm: float
    axis_tilt_deg: float
    flatness_mm: float


@dataclass(frozen=True)
class SweepAnalysis:
    """Result of `analyse_sweeps`; `joints[j]` for j in 0..5 (see `JointSweep`).

    `joints` are the curves midway between the two approach directions; `play_rad[j]`
    (± `play_std_rad[j]`) is joint j's backlash, the difference between approaching from
    below and from above (an angle approached from below is reached b/2 short); 0 with
    a NaN std for a joint none of whose angles was reached from both sides.
    """

    registration: Registration
    joints: tuple[JointSweep, ...]
    fixed: list[dict[str, float]]
    circles: tuple[SweepCircle, ...]
    sigma_mm: float
    rms_mm: float
    robot: str
    gauge: str = "joint-1 error is zero at theta1 = 0; a constant joint-1 error is in R"
    residuals_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    notes: tuple[str, ...] = ()
    play_rad: np.ndarray = field(default_factory=lambda: np.zeros(6))
    play_std_rad: np.ndarray = field(default_factory=lambda: np.zeros(6))

    def report(self) -> dict[str, Any]:
        """JSON data in degrees and mm."""

        def nan_none(a: np.ndarray) -> list[float | None]:
            return [None if not np.isfinite(v) else float(v) for v in a]

        joints = []
        for j, js in enumerate(self.joints):
            joints.append({
                "joint": j + 1, "samples": len(js.theta_cmd),
                "theta_cmd_deg": np.degrees(js.theta_cmd).tolist(),
                "delta_deg": np.degrees(js.delta).tolist(),
                "repeat_std_deg": nan_none(np.degrees(js.repeat_std)),
                "delta_std_deg": np.degrees(js.delta_std).tolist(),
                "repeatability_deg": (None if not np.isfinite(js.repeatability_rad)
                                      else float(np.degrees(js.repeatability_rad))),
            })
        return {
            "robot": self.robot, "gauge": self.gauge,
            "registration": self.registration.report(),
            "residual_rms_mm": self.rms_mm, "noise_sigma_mm": self.sigma_mm,
            "notes": list(self.notes),
            "joints": joints,
            "backlash_play_deg": np.degrees(self.play_rad).tolist(),
            "backlash_play_std_deg": nan_none(np.degrees(self.play_std_rad)),
            "fixed_joint_deltas": self.fixed,
            "circles": [{"joint": c.joint + 1, "rows": [c.first_row, c.last_row],
                         "radius_mm": c.radius_mm, "axis_tilt_deg": c.axis_tilt_deg,
                         "flatness_mm": c.flatness_mm} for c in self.circles],
        }


# --------------------------------------------------------------------------- helpers


def _ball(robot: RobotModel, q: np.ndarray, smr: np.ndarray) -> np.ndarray:
    T = robot.fk(q)
    return T[:, :3, :3] @ smr + T[:, :3, 3]


def _skew(v: np.ndarray) -> np.ndarray:
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


@dataclass
class _Problem:
    """Index bookkeeping: which unknown Δθ each (row, joint) uses, which are free."""

    uid: np.ndarray  # (N, 6) unknown index per row and joint
    theta: np.ndarray  # (U,) commanded value of each unknown, rad
    joint: np.ndarray  # (U,) joint of each unknown
    swept: np.ndarray  # (U,) bool: a sample of a sweep of its own joint
    column: np.ndarray  # (U,) column in the parameter vector, -1 for the pinned one
    pinned: int  # the unknown fixed at 0 by the gauge, or -1
    direction: np.ndarray  # (N, 6) last motion per row and joint: ±1, 0 before the first
    play_col: np.ndarray  # (6,) column of each joint's backlash play b, -1 if not seen
    start_col: np.ndarray  # (6,) column of the offset of the rows before the first motion
    n_cols: int  # length of the parameter vector

    def extra(self, x: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Values (6,) of per-joint parameters at `cols` (0 where a column is -1)."""
        return np.where(cols >= 0, x[np.maximum(cols, 0)], 0.0)

    def joint_error(self, x: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, ...]:
        """Δθ (n, 6) of `rows` for parameters x, with ∂/∂b and ∂/∂start per joint."""
        delta = np.zeros(len(self.theta))
        free = self.column >= 0
        delta[free] = x[self.column[free]]
        d = self.direction[rows]
        d_play = -0.5 * d
        d_start = (d == 0).astype(float)
        play, start = self.extra(x, self.play_col), self.extra(x, self.start_col)
        return delta[self.uid[rows]] + d_play * play + d_start * start, d_play, d_start


def _directions(q: np.ndarray, approach: np.ndarray | None = None,
                approach_joints: np.ndarray | None = None) -> np.ndarray:
    """Sign (N, 6) of each joint's last motion over the rows in order; 0 before its first.

    `approach` (N,) ±1 where a move not in the table (a measurement program's approach
    move, `rapidfix plan`) came just before the row and turned the joints of the bit
    mask `approach_joints` (bit j for joint j + 1): those arrive moving that way.
    """
    step = np.diff(np.round(np.degrees(q), 5), axis=0, prepend=np.round(np.degrees(q[:1]), 5))
    sign = np.sign(step)
    if approach is not None and approach_joints is not None:
        turned = (approach_joints.astype(int)[:, None] >> np.arange(6)) & 1 == 1
        sign = np.where(turned & (approach[:, None] != 0), np.sign(approach)[:, None], sign)
    rows = np.arange(len(q))[:, None]
    moved_at = np.maximum.accumulate(np.where(sign != 0, rows, -1), axis=0)
    filled = np.take_along_axis(sign, np.maximum(moved_at, 0), axis=0)
    return np.where(moved_at >= 0, filled, 0.0)


def _index(sweeps: SweepTable) -> _Problem:
    key = np.round(np.degrees(sweeps.q), 5)
    uid = np.empty(key.shape, dtype=int)
    thetas, joints = [], []
    start = 0
    for k in range(6):
        values, inverse = np.unique(key[:, k], return_inverse=True)
        uid[:, k] = start + inverse.ravel()
        thetas.append(np.radians(values))
        joints.append(np.full(len(values), k))
        start += len(values)
    theta = np.concatenate(thetas)
    joint = np.concatenate(joints)
    swept = np.zeros(start, dtype=bool)
    swept[uid[np.arange(len(key)), sweeps.sweep_joint]] = True
    # Gauge: pin the joint-1 unknown nearest θ1 = 0 (preferring swept samples).
    cand = np.flatnonzero(joint == 0)
    order = np.lexsort((np.abs(theta[cand]), ~swept[cand]))
    pinned = int(cand[order[0]]) if len(cand) else -1
    column = np.full(start, -1)
    free = np.arange(start) != pinned
    n_free = int(free.sum())
    column[free] = 6 + np.arange(n_free)
    # A joint's play is seen only where one commanded value is reached from both sides,
    # the start offset only where a value is reached before and after the first motion;
    # elsewhere they would merely alias the Δθ unknowns, and stay 0.
    direction = _directions(sweeps.q, sweeps.extra.get("approach"),
                            sweeps.extra.get("approach_joints"))
    seen = np.zeros((3, start), dtype=bool)  # per unknown: reached with d = -1, 0, +1
    for k in range(6):
        seen[direction[:, k].astype(int) + 1, uid[:, k]] = True
    play_ok = np.bincount(joint, seen[0] & seen[2], minlength=6) > 0
    start_ok = np.bincount(joint, seen[1] & (seen[0] | seen[2]), minlength=6) > 0
    n = 6 + n_free
    play_col = np.where(play_ok, n + np.cumsum(play_ok) - 1, -1)
    n += int(play_ok.sum())
    start_col = np.where(start_ok, n + np.cumsum(start_ok) - 1, -1)
    n += int(start_ok.sum())
    return _Problem(uid, theta, joint, swept, column, pinned, direction, play_col, start_col, n)


def _groups(sweeps: SweepTable) -> np.ndarray:
    """Sweep id per row: same moved joint and the same values of the other joints."""
    key = np.round(np.degrees(sweeps.q), 5)
    key[np.arange(len(key)), sweeps.sweep_joint] = 0.0
    _, gid = np.unique(np.column_stack([sweeps.sweep_joint, key]), axis=0,
                       return_inverse=True)
    return gid.ravel()


def _check_geometry(sweeps: SweepTable, gid: np.ndarray, robot: RobotModel,
                    smr: np.ndarray) -> None:
    """Refuse sweeps that cannot show a joint angle: too few angles, ball on the axis."""
    for g in np.unique(gid):
        rows = np.flatnonzero(gid == g)
        j = int(sweeps.sweep_joint[rows[0]])
        where = {"file": sweeps.path, "row": int(sweeps.rows[rows[0]]), "column": "sweep_joint"}
        span = f"rows {int(sweeps.rows[rows[0]])}–{int(sweeps.rows[rows[-1]])}"
        angles = np.unique(np.round(np.degrees(sweeps.q[rows, j]), 5))
        if len(angles) < 3:
            raise MeasurementError(
                f"the sweep of joint {j + 1} ({span}) has {len(angles)} different angle(s) "
                "with the other joints fixed; a circle needs at least 3", **where)
        dirs, points = robot.joint_frames(sweeps.q[rows[:1]])
        rel = _ball(robot, sweeps.q[rows[:1]], smr)[0] - points[0, j]
        radius = float(np.linalg.norm(rel - (rel @ dirs[0, j]) * dirs[0, j]))
        if radius < MIN_RADIUS_MM:
            raise MeasurementError(
                f"in the sweep of joint {j + 1} ({span}) the target ball is {radius:.2f} mm "
                "from the joint's axis, so it draws no usable circle", **where,
                hint="mount the ball off the axis or sweep the joint in another pose")


def _circles(sweeps: SweepTable, gid: np.ndarray, keep: np.ndarray, robot: RobotModel,
             reg: Registration) -> tuple[SweepCircle, ...]:
    """Plane and circle of each sweep in the robot frame; refuse tilted (mislabelled) ones."""
    p = reg.to_robot(sweeps.xyz)
    out = []
    for g in np.unique(gid):
        rows = np.flatnonzero((gid == g) & keep)
        if len(rows) < 3:  # (nearly) every row of this sweep was an outlier
            continue
        j = int(sweeps.sweep_joint[rows[0]])
        pts = p[rows]
        centre = pts.mean(axis=0)
        _, sv, vt = np.linalg.svd(pts - centre, full_matrices=False)
        normal = vt[2]
        axis = robot.joint_frames(sweeps.q[rows[:1]])[0][0, j]
        tilt = float(np.degrees(np.arccos(min(1.0, abs(float(normal @ axis))))))
        uv = (pts - centre) @ vt[:2].T
        A = np.column_stack([2.0 * uv, np.ones(len(uv))])
        sol, *_ = np.linalg.lstsq(A, np.sum(uv**2, axis=1), rcond=None)
        radius = float(np.sqrt(max(sol[2] + sol[0] ** 2 + sol[1] ** 2, 0.0)))
        span = np.ptp(np.unique(sweeps.q[rows, j]))
        if span > np.radians(20.0) and tilt > MAX_AXIS_TILT_DEG:
            raise MeasurementError(
                f"the ball in the sweep of joint {j + 1} (rows {int(sweeps.rows[rows[0]])}–"
                f"{int(sweeps.rows[rows[-1]])}) turns about an axis {tilt:.1f}° away from "
                f"joint {j + 1}'s axis", file=sweeps.path, row=int(sweeps.rows[rows[0]]),
                column="sweep_joint",
                hint="check sweep_joint, the joint column order and the robot model")
        out.append(SweepCircle(j, int(sweeps.rows[rows[0]]), int(sweeps.rows[rows[-1]]),
                               radius, tilt, float(sv[2] / np.sqrt(len(rows)))))
    return tuple(out)


# --------------------------------------------------------------------------- solve


class _Solver:
    """Residuals and sparse Jacobian of the joint problem for a subset of rows."""

    def __init__(self, sweeps: SweepTable, robot: RobotModel, smr: np.ndarray,
                 prob: _Problem, R0: np.ndarray, sigma: float, prior: float) -> None:
        self.q, self.xyz, self.robot, self.smr = sweeps.q, sweeps.xyz, robot, smr
        self.prob, self.R0, self.sigma, self.prior = prob, R0, sigma, prior
        self.n_free = prob.n_cols - 6

    def unpack(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        R = Rotation.from_rotvec(x[:3]).as_matrix() @ self.R0
        delta = np.zeros(len(self.prob.theta))
        free = self.prob.column >= 0
        delta[free] = x[self.prob.column[free]]
        return R, x[3:6], delta

    def predict(self, x: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, ...]:
        R, t, _ = self.unpack(x)
        q_act = self.q[rows] + self.prob.joint_error(x, rows)[0]
        p = _ball(self.robot, q_act, self.smr)
        return p @ R.T + t, p, q_act, R

    def residuals(self, x: np.ndarray, rows: np.ndarray) -> np.ndarray:
        pred, *_ = self.predict(x, rows)
        data = ((pred - self.xyz[rows]) / self.sigma).ravel()
        return np.concatenate([data, x[6:] / self.prior])

    def jacobian(self, x: np.ndarray, rows: np.ndarray) -> sp.csr_matrix:
        pred, p, q_act, R = self.predict(x, rows)
        n = len(rows)
        dirs, points = self.robot.joint_frames(q_act)
        dp = np.cross(dirs, p[:, None, :] - points)  # (n, 6, 3) dp/dθ_k, robot frame
        _, d_play, d_start = self.prob.joint_error(x, rows)
        dq = np.einsum("ij,nkj->nik", R, dp)  # (n, 3, 6) tracker motion per joint
        block = np.empty((n, 3, 24))
        block[:, :, :3] = -_skew(pred - x[3:6])
        block[:, :, 3:6] = np.eye(3)
        block[:, :, 6:12] = dq
        block[:, :, 12:18] = dq * d_play[:, None, :]
        block[:, :, 18:] = dq * d_start[:, None, :]
        cols = np.empty((n, 3, 24), dtype=int)
        cols[:, :, :6] = np.arange(6)
        cols[:, :, 6:12] = self.prob.column[self.prob.uid[rows]][:, None, :]
        cols[:, :, 12:18] = self.prob.play_col
        cols[:, :, 18:] = self.prob.start_col
        rr = np.broadcast_to(np.arange(3 * n).reshape(n, 3, 1), cols.shape)
        ok = (cols >= 0) & (block != 0.0)
        m = 6 + self.n_free
        data = sp.csr_matrix((block[ok] / self.sigma, (rr[ok], cols[ok])), shape=(3 * n, m))
        prior = sp.csr_matrix((np.full(self.n_free, 1.0 / self.prior),
                               (np.arange(self.n_free), 6 + np.arange(self.n_free))),
                              shape=(self.n_free, m))
        return sp.vstack([data, prior], format="csr")

    def cost(self, r: np.ndarray, robust: bool) -> float:
        """Half the sum of squares, or of the soft-L1 loss 2(√(1 + (r/f)²) − 1)·f²."""
        if not robust:
            return 0.5 * float(r @ r)
        return float(np.sum(np.sqrt(1.0 + (r / ROBUST_SCALE) ** 2) - 1.0)) * ROBUST_SCALE**2

    def solve(self, x0: np.ndarray, rows: np.ndarray, robust: bool,
              max_iter: int = 50) -> np.ndarray:
        """Gauss–Newton on sparse normal equations (IRLS weights for the robust loss).

        The problem is small-residual and starts close, so exact sparse steps converge
        in a handful of iterations. The rotation is re-based after every step
        (R0 ← Rot(φ)·R0, φ ← 0), which keeps its Jacobian exact.
        """
        x = x0.copy()
        r = self.residuals(x, rows)
        cost = self.cost(r, robust)
        for _ in range(max_iter):
            J = self.jacobian(x, rows)
            w = 1.0 / np.sqrt(1.0 + (r / ROBUST_SCALE) ** 2) if robust else np.ones_like(r)
            Jw = sp.diags(w) @ J
            A = (J.T @ Jw).tocsc()
            step = spla.spsolve(A, -(Jw.T @ r))
            if np.max(np.abs(step[6:]), initial=0.0) < 1e-13 and np.max(np.abs(step[:6])) < 1e-10:
                break
            for _halving in range(8):  # halve a step that does not lower the cost
                trial = x + step
                r_trial = self.residuals(trial, rows)
                cost_trial = self.cost(r_trial, robust)
                if cost_trial <= cost:
                    break
                step = 0.5 * step
            else:
                break
            x, r, converged = trial, r_trial, cost - cost_trial <= 1e-14 * max(cost, 1.0)
            cost = cost_trial
            self.R0 = Rotation.from_rotvec(x[:3]).as_matrix() @ self.R0
            x[:3] = 0.0
            if converged:
                break
        return x


#: share of rows, the best fitting ones, whose RMS the rigid-fit check judges
RIGID_CHECK_SHARE = 0.75


def _trimmed_rms(residuals_mm: np.ndarray, share: float = RIGID_CHECK_SHARE) -> float:
    """RMS of the smallest `share` of the residuals (gross outliers left aside)."""
    r = np.sort(np.asarray(residuals_mm, dtype=float))
    k = max(1, int(np.ceil(share * r.shape[0])))
    return float(np.sqrt(np.mean(r[:k] ** 2)))


def _check_rigid_rms(rms_mm: float, sweeps: SweepTable, robot: RobotModel) -> None:
    """Refuse data the robot model cannot explain (wrong robot, ball offset or units)."""
    if not rms_mm <= MAX_RIGID_RMS_MM:
        raise MeasurementError(
            f"the measured positions are {rms_mm:.1f} mm RMS from what the robot model "
            f"{robot.name!r} predicts, even after the best rigid fit (the limit is "
            f"{MAX_RIGID_RMS_MM:g} mm)", file=sweeps.path,
            hint="check robot, smr_offset_mm, that x, y, z are mm and j1..j6 degrees")


def analyse_sweeps(setup: Setup, sweeps: SweepTable, robot: RobotModel, *,
                   prior_deg: float = 5.0, max_rounds: int = 20) -> SweepAnalysis:
    """Recover Δθ at every swept commanded angle and the tracker pose (see module doc).

    `robot` is the nominal model; positions are predicted for the ball at
    `setup.smr_offset_mm` in the flange frame.
    """
    smr = np.asarray(setup.smr_offset_mm, dtype=float)
    gid = _groups(sweeps)
    _check_geometry(sweeps, gid, robot, smr)
    prob = _index(sweeps)

    initial = register(_ball(robot, sweeps.q, smr), sweeps.xyz, rows=sweeps.rows)
    # The robust fit may leave out up to half the rows, so its own RMS can look fine on
    # data of another robot: judge the best three quarters of all rows instead.
    _check_rigid_rms(_trimmed_rms(initial.residuals_mm), sweeps, robot)
    sigma = setup.tracker_sigma_mm or DEFAULT_SIGMA_MM
    solver = _Solver(sweeps, robot, smr, prob, initial.R, sigma, np.radians(prior_deg))
    x = np.zeros(6 + solver.n_free)
    x[3:6] = initial.t
    all_rows = np.arange(len(sweeps))
    # The rigid fit's outliers are only provisional (it ignores the joint errors): the
    # first, robust solve sees every row.
    x = solver.solve(x, all_rows, robust=True)
    x, keep, notes = _trim_outliers(solver, x, sweeps, prob, NOISE_FLOOR_SIGMAS * sigma,
                                    max_rounds)
    # The robust loss only serves to find the outliers; the answer is plain least squares
    # on the rows kept (the soft-L1 weights would bias Δθ where the residual has structure).
    x = solver.solve(x, all_rows[keep], robust=False)
    pred, p, q_act, R_fit = solver.predict(x, all_rows)
    resid = np.linalg.norm(pred - sweeps.xyz, axis=1)

    _, t, delta = solver.unpack(x)
    R, t, delta = _apply_gauge(R_fit, t, delta, prob, robot)
    reg = Registration(R=R, t=t, rms_mm=float(np.sqrt(np.mean(resid[keep] ** 2))),
                       outlier_rows=sweeps.rows[~keep], residuals_mm=resid, inliers=keep)
    # Free joint errors can absorb much of a wrong model; what they cannot is refused.
    _check_rigid_rms(reg.rms_mm, sweeps, robot)
    std, cov_diag = _standard_errors(solver, x, all_rows[keep], prob)
    play = prob.extra(x, prob.play_col)
    play_std = np.where(prob.play_col >= 0, np.sqrt(prob.extra(cov_diag, prob.play_col)),
                        np.nan)
    joints = _per_joint(sweeps, prob, delta, std, pred, p, q_act, R_fit, keep, robot)
    fixed = [{"joint": int(prob.joint[u]) + 1, "theta_cmd_deg": float(np.degrees(prob.theta[u])),
              "delta_deg": float(np.degrees(delta[u])), "delta_std_deg": float(np.degrees(std[u]))}
             for u in np.flatnonzero(~prob.swept)]
    d = (pred - sweeps.xyz)[keep]
    sigma_hat = float(1.4826 * np.median(np.abs(d - np.median(d, axis=0))))
    return SweepAnalysis(registration=reg, joints=joints, fixed=fixed,
                         circles=_circles(sweeps, gid, keep, robot, reg), sigma_mm=sigma_hat,
                         rms_mm=reg.rms_mm, robot=robot.name, residuals_mm=resid,
                         notes=tuple(notes), play_rad=play, play_std_rad=play_std)


def _swept_motion(robot: RobotModel, sweeps: SweepTable, q_act: np.ndarray, p: np.ndarray,
                  R: np.ndarray) -> np.ndarray:
    """Tracker-frame motion of the ball per radian of each row's swept joint (N, 3)."""
    n = len(sweeps)
    dirs, points = robot.joint_frames(q_act)
    j = sweeps.sweep_joint
    return np.cross(dirs[np.arange(n), j], p - points[np.arange(n), j]) @ R.T


def _trim_outliers(solver: _Solver, x: np.ndarray, sweeps: SweepTable, prob: _Problem,
                   floor: float, max_rounds: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Drop gross outliers: per round the worst suspect of each sample, then solve again.

    One per sample, because an outlier pulls the Δθ of its sample along the circle and
    can make a good repeat look bad. The part of a residual across the circle cannot be
    pulled that way, so within a sample a row that is off *across* the circle goes
    first; only then the largest residual. Outliers are isolated gross errors: at most
    `MAX_OUTLIER_FRACTION` of the rows (at least `MIN_OUTLIER_BUDGET`) are dropped;
    more suspects than that mean the residual has structure (an effect the per-joint
    model lacks), which is reported in the notes rather than trimmed away.
    """
    all_rows = np.arange(len(sweeps))
    sample = prob.uid[all_rows, sweeps.sweep_joint]
    keep = np.ones(len(sweeps), dtype=bool)
    budget = max(MIN_OUTLIER_BUDGET, int(MAX_OUTLIER_FRACTION * len(sweeps)))
    notes: list[str] = []
    for _ in range(max_rounds):
        pred, p, q_act, R = solver.predict(x, all_rows)
        r = pred - sweeps.xyz
        u = _swept_motion(solver.robot, sweeps, q_act, p, R)
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        full = np.linalg.norm(r, axis=1)
        across = np.linalg.norm(r - np.einsum("ni,ni->n", r, u)[:, None] * u, axis=1)
        off_across = outlier_mask(across, floor) & keep
        suspect = np.flatnonzero((outlier_mask(full, floor) & keep) | off_across)
        if len(suspect) == 0:
            break
        score = np.where(off_across, 1e6 + across, full)[suspect]
        suspect = suspect[np.argsort(-score)]
        _, first = np.unique(sample[suspect], return_index=True)
        worst = suspect[np.sort(first)]  # the worst suspect of each sample, worst first
        room = budget - int((~keep).sum())
        if len(worst) > room:
            notes.append(f"{len(suspect)} rows lie beyond the outlier threshold, more than "
                         "isolated gross errors would: the residual has structure the "
                         "per-joint model does not explain; only the worst were dropped")
            worst = worst[:max(room, 0)]
        if len(worst) == 0:
            break
        keep[worst] = False
        x = solver.solve(x, all_rows[keep], robust=False)
        if notes:
            break
    pred, *_ = solver.predict(x, all_rows)
    back = ~keep & ~outlier_mask(np.linalg.norm(pred - sweeps.xyz, axis=1), floor)
    if back.any():  # dropped rows that fit after all
        keep |= back
        x = solver.solve(x, all_rows[keep], robust=False)
    return x, keep, notes


def _apply_gauge(R: np.ndarray, t: np.ndarray, delta: np.ndarray, prob: _Problem,
                 robot: RobotModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shift the joint-1 errors so Δθ1(0) = 0 (interpolated) and move the shift into R, t.

    Without a joint-1 sweep the gauge stays where the solve pinned it: Δθ1 = 0 at the
    held joint-1 value nearest 0°.
    """
    j1 = np.flatnonzero((prob.joint == 0) & prob.swept)
    if len(j1) < 2:
        return R, t, delta
    c = float(np.interp(0.0, prob.theta[j1], delta[j1]))
    delta = delta.copy()
    delta[prob.joint == 0] -= c
    R, t = move_joint1_offset(R, t, c, robot.axis_dirs[0], robot.axis_points[0])
    return R, t, delta


def _standard_errors(solver: _Solver, x: np.ndarray, rows: np.ndarray,
                     prob: _Problem) -> tuple[np.ndarray, np.ndarray]:
    """Standard error of every Δθ unknown (rad), and the covariance diagonal of x."""
    J = solver.jacobian(x, rows)
    r = solver.residuals(x, rows)
    dof = max(J.shape[0] - J.shape[1], 1)
    scale = float(r @ r) / dof
    JtJ = (J.T @ J).toarray()
    cov_diag = np.maximum(np.diag(np.linalg.inv(JtJ)) * scale, 0.0)  # prior: JtJ is p.d.
    std = np.zeros(len(prob.theta))
    free = prob.column >= 0
    std[free] = np.sqrt(cov_diag[prob.column[free]])
    return std, cov_diag


def _per_joint(sweeps: SweepTable, prob: _Problem, delta: np.ndarray, std: np.ndarray,
               pred: np.ndarray, p: np.ndarray, q_act: np.ndarray, R: np.ndarray,
               keep: np.ndarray, robot: RobotModel) -> tuple[JointSweep, ...]:
    """Per joint: the swept samples' Δθ, and the spread of single-measurement angles."""
    n = len(sweeps)
    j = sweeps.sweep_joint
    u = _swept_motion(robot, sweeps, q_act, p, R)
    single = np.einsum("ni,ni->n", u, sweeps.xyz - pred) / np.einsum("ni,ni->n", u, u)
    sample = prob.uid[np.arange(n), j]
    angle = delta[sample] + single
    U = len(prob.theta)
    cnt = np.bincount(sample[keep], minlength=U).astype(float)
    mean = np.bincount(sample[keep], angle[keep], minlength=U) / np.maximum(cnt, 1)
    sq = np.bincount(sample[keep], (angle[keep] - mean[sample[keep]]) ** 2, minlength=U)
    with np.errstate(invalid="ignore", divide="ignore"):
        rep = np.where(cnt > 1, np.sqrt(sq / (cnt - 1)), np.nan)
    out = []
    for k in range(6):
        us = np.flatnonzero((prob.joint == k) & prob.swept)
        us = us[np.argsort(prob.theta[us])]
        us = us[cnt[us] > 0]  # samples whose every repeat was an outlier say nothing
        out.append(JointSweep(theta_cmd=prob.theta[us], delta=delta[us], repeat_std=rep[us],
                              delta_std=std[us], n=cnt[us].astype(int)))
    return tuple(out)
