"""RobotModel: a six-axis arm as six revolute screws plus the tool0 home pose.

The same class holds a nominal model (loaded from a robot file) and an "actual"
model whose screws were perturbed by calibration (`with_screws`). Forward
kinematics, joint frames and the Jacobian come from the screws alone; inverse
kinematics is analytic for the nominal model and seeded Newton for an actual one.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from rapidfix import chunks
from rapidfix.exceptions import KinematicsError
from rapidfix.kinematics.batches import as_joint_batch, frozen
from rapidfix.kinematics.confdata import confdata as confdata_of
from rapidfix.kinematics.confdata import select_by_conf, select_nearest, slot_confdata
from rapidfix.kinematics.frames import Tool, WorkObject, tcp_pose
from rapidfix.kinematics.ik import WRIST_TOL, solve_all
from rapidfix.kinematics.ik_result import IKSolutions
from rapidfix.kinematics.screws import current_axes, forward_pose, screw_rows


class RobotModel:
    """Six revolute screws (axis directions and points, mm) and tool0's home pose.

    Attributes: `name`, `axis_dirs (6, 3)`, `axis_points (6, 3)` mm, `screws (6, 6)`
    rows (w, v = -w × q), `home (4, 4)` tool0 at θ = 0, `limits (6, 2)` rad,
    `source` (the robot file), `definition` (its content as plain data), `nominal`
    (the model the analytic IK is built on; the model itself unless made by
    `with_screws`). Joint values are the
    controller's: ABB's zero and sign conventions are built into the screws.
    """

    def __init__(
        self,
        name: str,
        axis_dirs: np.ndarray,
        axis_points: np.ndarray,
        home: np.ndarray,
        limits: np.ndarray,
        *,
        source: str | Path | None = None,
        nominal: RobotModel | None = None,
        definition: dict | None = None,
    ) -> None:
        dirs = np.asarray(axis_dirs, dtype=float)
        if dirs.shape != (6, 3) or np.asarray(axis_points).shape != (6, 3):
            raise KinematicsError("a robot model needs six axis directions and six axis points")
        if np.asarray(home).shape != (4, 4) or np.asarray(limits).shape != (6, 2):
            raise KinematicsError("a robot model needs a (4, 4) home pose and (6, 2) limits")
        norms = np.linalg.norm(dirs, axis=1)
        if np.any(norms < 1e-12):
            raise KinematicsError("an axis direction is zero")
        self.name = name
        self.axis_dirs = frozen(dirs / norms[:, None])
        self.axis_points = frozen(axis_points)
        self.home = frozen(home)
        self.limits = frozen(limits)
        self.screws = frozen(screw_rows(self.axis_dirs, self.axis_points))
        self.source = None if source is None else str(source)
        self.nominal = self if nominal is None else nominal
        #: the robot file's content as plain data (name, joints, tool0), for a nominal
        #: model read from one: what a model file stores to rebuild the robot
        self.definition = definition
        self._analytic = None

    def __repr__(self) -> str:
        kind = "nominal" if self.is_nominal else "actual"
        return f"RobotModel({self.name!r}, {kind})"

    @property
    def is_nominal(self) -> bool:
        """True for a model whose inverse kinematics is solved in closed form."""
        return self.nominal is self

    # ---- forward kinematics -------------------------------------------------------

    def fk(
        self,
        q: np.ndarray,
        tool: Tool | np.ndarray | None = None,
        wobj: WorkObject | np.ndarray | None = None,
    ) -> np.ndarray:
        """Pose (N, 4, 4) of tool0 in the base frame for joints q (N, 6) rad.

        With `tool` (a frames.Tool or the TCP (4, 4) in the flange frame) and/or
        `wobj` (a frames.WorkObject or (4, 4)) it returns the TCP pose in the
        work-object frame instead. A (6,) input gives a (4, 4) result.
        """
        qb, single = as_joint_batch(q)
        T = forward_pose(self.axis_dirs, self.axis_points, self.home, qb)
        if tool is not None or wobj is not None:
            T = tcp_pose(T, tool, wobj)
        return T[0] if single else T

    def joint_frames(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Current axis directions (N, 6, 3) and points on the axes (N, 6, 3) mm."""
        qb, single = as_joint_batch(q)
        dirs, points = current_axes(self.axis_dirs, self.axis_points, qb)
        return (dirs[0], points[0]) if single else (dirs, points)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Space Jacobian (N, 6, 6): column i is joint i's current screw (w; v = -w × q)."""
        qb, single = as_joint_batch(q)
        dirs, points = self.joint_frames(qb)
        J = np.concatenate([dirs, -np.cross(dirs, points)], axis=-1).transpose(0, 2, 1)
        return J[0] if single else J

    # ---- models derived from this one ---------------------------------------------

    def with_screws(
        self,
        axis_dirs: np.ndarray,
        axis_points: np.ndarray,
        home: np.ndarray | None = None,
        name: str | None = None,
    ) -> RobotModel:
        """An actual (calibrated) model: other screws, same limits, IK seeded by this model."""
        return RobotModel(
            self.name if name is None else name,
            axis_dirs,
            axis_points,
            self.home if home is None else home,
            self.limits,
            source=self.source,
            nominal=self.nominal,
        )

    def within_limits(self, q: np.ndarray, tol: float = 1e-9) -> np.ndarray:
        """Boolean (N,) (or (...)) mask: every joint inside its limits (± tol rad)."""
        q = np.asarray(q, dtype=float)
        lo, hi = self.limits[:, 0], self.limits[:, 1]
        return np.all((q >= lo - tol) & (q <= hi + tol), axis=-1)

    # ---- inverse kinematics -------------------------------------------------------

    def ik(
        self,
        T: np.ndarray,
        *,
        tool: Tool | np.ndarray | None = None,
        wobj: WorkObject | np.ndarray | None = None,
        q_prev: np.ndarray | None = None,
        wrist_tol: float | None = None,
    ) -> IKSolutions:
        """Every solution for tool0 poses T (N, 4, 4) in the base frame (see `kinematics.ik`).

        With `tool` / `wobj` (frames.Tool / frames.WorkObject or (4, 4)), T is the TCP
        pose in the work object. `q_prev` (N, 6) or (6,) gives θ4 at wrist singularities.
        """
        return solve_all(
            self,
            T,
            tool=tool,
            wobj=wobj,
            q_prev=q_prev,
            wrist_tol=WRIST_TOL if wrist_tol is None else wrist_tol,
        )

    def ik_conf(
        self, T: np.ndarray, conf: np.ndarray, **ik_options: object
    ) -> tuple[np.ndarray, np.ndarray]:
        """The solution each target's confdata [cf1, cf4, cf6, cfx] names: (q (N, 6), status).

        `ik_options` are passed to `ik` (tool, wobj, q_prev, wrist_tol).
        """
        T = np.asarray(T, dtype=float)
        if ik_options or T.ndim != 3 or T.shape[0] <= chunks.IK_CONF:
            return select_by_conf(self, self.ik(T, **ik_options), conf)  # type: ignore[arg-type]
        conf = np.broadcast_to(np.asarray(conf, dtype=int), (T.shape[0], 4))
        return _in_chunks(T, conf, lambda t, c: select_by_conf(self, self.ik(t), c))

    def ik_nearest(
        self, T: np.ndarray, q_prev: np.ndarray, **ik_options: object
    ) -> tuple[np.ndarray, np.ndarray]:
        """The valid solution nearest q_prev (N, 6) or (6,): (q (N, 6), status (N,))."""
        T = np.asarray(T, dtype=float)
        if ik_options or T.ndim != 3 or T.shape[0] <= chunks.IK_CONF:
            sols = self.ik(T, q_prev=q_prev, **ik_options)  # type: ignore[arg-type]
            return select_nearest(sols, q_prev)
        prev = np.broadcast_to(np.asarray(q_prev, dtype=float), (T.shape[0], 6))
        return _in_chunks(T, prev, lambda t, p: select_nearest(self.ik(t, q_prev=p), p))

    def confdata(self, q: np.ndarray) -> np.ndarray:
        """ABB confdata [cf1, cf4, cf6, cfx] (N, 4) int of joints q (N, 6) rad."""
        return confdata_of(self, q)

    def slot_confdata(self, sols: IKSolutions) -> np.ndarray:
        """confdata (N, S, 4) int of every valid slot of IK solutions (0 in the others)."""
        return slot_confdata(self, sols)


def _in_chunks(T: np.ndarray, per_row: np.ndarray,
               solve: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
               ) -> tuple[np.ndarray, np.ndarray]:
    """(q (N, 6), status (N,)) of `solve(T[rows], per_row[rows])` over chunks of
    chunks.IK_CONF poses: the IK's (poses × 8 branches × 6 axes) temporaries then stay
    small and are reused."""
    q = np.empty((T.shape[0], 6))
    status = np.empty(T.shape[0], dtype=np.int8)
    for start in range(0, T.shape[0], chunks.IK_CONF):
        rows = slice(start, start + chunks.IK_CONF)
        q[rows], status[rows] = solve(T[rows], per_row[rows])
    return q, status
