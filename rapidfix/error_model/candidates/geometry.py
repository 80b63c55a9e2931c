"""Link geometry: errors of the joint screws themselves (a PoE kinematic calibration).

Full error vector (26 numbers, mm and rad): for joints 2–6 each axis tilts by two
angles and shifts by two distances across itself (moving a point along its own
axis or turning an axis about itself changes nothing); tool0's home pose moves by
three distances and three angles. Joint 1's axis is the base frame's z: its
errors are a move of the whole robot, carried by the tracker registration.

Not all 26 can be told apart from measured ball positions: some only move the
robot rigidly (registration), some equal a joint's zero offset (the per-joint
model), some (home rotation against home translation) are seen only through the
ball's lever. `identifiable_modes` keeps the combinations a data set does
determine: project the identification Jacobian off the directions of the
nuisance (registration and offsets), scale its columns, and keep the singular
directions above a relative threshold. The effect's parameters are the
amplitudes of those modes; `errors()` returns the 26 physical errors they make.
The per-joint model re-referenced with it (`joint_reference`) takes out what
the sweeps absorbed of these errors.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Geometry
from rapidfix.kinematics import RobotModel, load_robot

N_ERRORS = 26
#: keep modes whose scaled singular value is above this fraction of the largest
RCOND = 1e-3
#: ... and whose point motion is at least this fraction distinct from the nuisance's
MIN_DISTINCT = 0.05


def error_names() -> tuple[str, ...]:
    """Names of the 26 physical errors, units in the names."""
    names: list[str] = []
    for j in range(2, 7):
        names += [f"j{j}_tilt_u_rad", f"j{j}_tilt_v_rad", f"j{j}_shift_u_mm", f"j{j}_shift_v_mm"]
    names += ["home_x_mm", "home_y_mm", "home_z_mm", "home_rx_rad", "home_ry_rad", "home_rz_rad"]
    return tuple(names)


@lru_cache(maxsize=8)
def _cross_axes(name: str) -> tuple[RobotModel, np.ndarray, np.ndarray]:
    """The nominal robot and, per joint, two unit vectors across its axis (6, 3) each."""
    robot = load_robot(name)
    w = np.asarray(robot.axis_dirs, dtype=float)
    helper = np.where(np.abs(w[:, [0]]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    u = np.cross(w, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(w, u)
    return robot, u, v


def perturb(geometry: Geometry, robot: str, e: np.ndarray) -> Geometry:
    """The geometry with the 26 physical errors `e` applied (works on per-pose arrays too)."""
    _, u, v = _cross_axes(robot)
    e = np.asarray(e, dtype=float)
    joint = e[:20].reshape(5, 4)
    d_dir = np.zeros((6, 3))
    d_point = np.zeros((6, 3))
    d_dir[1:] = joint[:, [0]] * u[1:] + joint[:, [1]] * v[1:]
    d_point[1:] = joint[:, [2]] * u[1:] + joint[:, [3]] * v[1:]
    dirs = geometry.axis_dirs + d_dir
    dirs = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
    points = geometry.axis_points + d_point
    home = np.array(geometry.home, dtype=float, copy=True)
    home[..., :3, 3] += e[20:23]
    from scipy.spatial.transform import Rotation  # when used: start-up time

    home[..., :3, :3] = Rotation.from_rotvec(e[23:26]).as_matrix() @ home[..., :3, :3]
    return geometry.replaced(axis_dirs=dirs, axis_points=points, home=home)


def identifiable_modes(jac_errors: np.ndarray, jac_nuisance: np.ndarray, *,
                       rcond: float = RCOND, min_distinct: float = MIN_DISTINCT
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Modes (26, k) of the errors that the data determine, and their singular values.

    `jac_errors` (M, 26) and `jac_nuisance` (M, K) are derivatives of the measured
    coordinates. The error Jacobian's columns are scaled to unit norm, projected
    off the nuisance's column space, and the SVD of the rest truncated at `rcond` × the largest
    singular value. A mode is kept only if at least `min_distinct` of the point
    motion it causes cannot be produced by the nuisance (else fitting it would
    only trade places with the registration or the offsets). Each mode is scaled
    so that amplitude 1 moves the measured points by 1 mm RMS.
    """
    m = jac_errors.shape[0]
    qn, _ = np.linalg.qr(jac_nuisance)
    rest = jac_errors - qn @ (qn.T @ jac_errors)
    norms = np.linalg.norm(jac_errors, axis=0)
    scale = np.where(norms > 0, 1.0 / np.maximum(norms, 1e-300), 0.0)
    _, s, vt = np.linalg.svd(rest * scale, full_matrices=False)
    keep = s > rcond * s[0]
    modes = scale[:, None] * vt[keep].T  # back to physical units
    full = np.linalg.norm(jac_errors @ modes, axis=0)
    distinct = np.linalg.norm(rest @ modes, axis=0) / np.maximum(full, 1e-300)
    ok = distinct >= min_distinct
    modes = modes[:, ok] * (np.sqrt(m / 3.0) / full[ok])
    return modes, s[keep][ok]


class LinkGeometry(VectorEffect):
    """Screw errors e = modes · amplitudes applied to the joint axes and home pose."""

    type_name: ClassVar[str] = "link_geometry"
    changes_geometry: ClassVar[bool] = True

    def __init__(self, robot: str, modes: np.ndarray, name: str | None = None, *,
                 free: bool = True) -> None:
        modes = np.asarray(modes, dtype=float).reshape(N_ERRORS, -1)
        k = modes.shape[1]
        super().__init__([f"mode{i + 1}_mm" for i in range(k)], name, steps=[1e-3] * k,
                         free=free)
        self.robot = str(robot)
        self.modes = modes

    def add_modes(self, columns: np.ndarray, amplitudes: np.ndarray,
                  std: np.ndarray | None = None) -> None:
        """Append modes (26, m) with their amplitudes (and standard deviations)."""
        columns = np.asarray(columns, dtype=float).reshape(N_ERRORS, -1)
        m, k = columns.shape[1], self.modes.shape[1]
        self.modes = np.hstack([self.modes, columns])
        self._names = (*self._names, *(f"mode{k + i + 1}_mm" for i in range(m)))
        self.steps = np.concatenate([self.steps, np.full(m, 1e-3)])
        self._p = np.concatenate([self._p, np.asarray(amplitudes, dtype=float)])
        if self.uncertainty is not None:
            extra = np.zeros(m) if std is None else np.asarray(std, dtype=float)
            self.uncertainty = np.concatenate([np.asarray(self.uncertainty, float), extra])

    def errors(self) -> np.ndarray:
        """The 26 physical errors (see `error_names`) of the current amplitudes."""
        return self.modes @ self._p

    def errors_uncertainty(self) -> np.ndarray | None:
        """Standard deviations of the 26 errors, if the amplitudes have uncertainties.

        Treats the amplitudes' standard deviations as independent (the modes are
        close to orthogonal directions of the data).
        """
        if self.uncertainty is None:
            return None
        return np.sqrt((self.modes**2) @ (np.asarray(self.uncertainty) ** 2))

    def apply_geometry(self, geometry: Geometry, q_cmd: np.ndarray, ctx: Context) -> Geometry:
        """Perturb the axes and home pose."""
        return perturb(geometry, self.robot, self.errors())

    def describe(self) -> str:
        """One line with the number of identifiable modes."""
        return f"{self.name} (link_geometry, {self.modes.shape[1]} identifiable modes of 26)"

    def _state(self) -> dict[str, Any]:
        return {"robot": self.robot, "error_names": list(error_names()),
                "modes": self.modes.tolist()}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> LinkGeometry:
        return cls(str(state["robot"]), np.asarray(state["modes"], dtype=float), name)
