"""Joint compliance: joints 2 and 3 deflect under the gravity torque of the arm and payload.

A gear train is a torsion spring: the joint turns by Δθ = k · τ under the torque τ
it holds (the second source paper's joint deformation). Gravity loads joints 2
and 3 of a floor-mounted arm (axes horizontal). Their torque has two parts:

- the payload m (kg, per pose from the context, else the model's default) at its
  centre of gravity p (per pose from the context, else the payload point of the
  calibration): τ_j = ((p − a_j) × m g) · w_j, taken exactly from the nominal
  kinematics of the commanded pose — so stiffnesses fitted with a test weight
  predict a program's tool and gripped part wherever their centre of gravity is;
- the arm's own links, lumped: the upper arm (and wrist) turns with the angle
  u = θ2 ± θ3, so its torque about either axis is A cos u + B sin u; the lower
  arm and the upper arm's mass at the elbow add a first harmonic of θ2 to joint 2.

Δθ2 = k2 τ2,payload + a2 cos u + b2 sin u
Δθ3 = k3 τ3,payload + a3 cos u + b3 sin u

The link terms are the products k · (upper-arm moment), linear in the parameters.
The lower arm's own torque about joint 2 (a first harmonic of θ2) and the
deflection each joint's sweep already held (a first harmonic of the swept angle)
are carried by the re-referenced per-joint model (`joint_reference`).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, ClassVar

import numpy as np

from rapidfix.error_model.candidates.vector import VectorEffect
from rapidfix.error_model.context import Context
from rapidfix.kinematics import RobotModel, load_robot

GRAVITY_MS2 = 9.81
NAMES = ("k2_rad_per_nm", "k3_rad_per_nm",
         "j2_arm_cos_rad", "j2_arm_sin_rad", "j3_arm_cos_rad", "j3_arm_sin_rad")


@lru_cache(maxsize=8)
def _robot(name: str) -> RobotModel:
    return load_robot(name)


def payload_torque_per_kg(robot: RobotModel, q: np.ndarray, point_mm: np.ndarray,
                          gravity_dir: np.ndarray) -> np.ndarray:
    """Gravity torque (N, 2) N·m per kg of payload about joints 2 and 3.

    `point_mm` is the payload's centre of gravity in the flange frame, (3,) or (N, 3).
    """
    T = robot.fk(np.atleast_2d(q))
    point = np.broadcast_to(np.asarray(point_mm, dtype=float), (T.shape[0], 3))
    p = np.einsum("nij,nj->ni", T[:, :3, :3], point) + T[:, :3, 3]
    dirs, points = robot.joint_frames(np.atleast_2d(q))
    force = GRAVITY_MS2 * np.asarray(gravity_dir, dtype=float)
    lever = (p[:, None, :] - points[:, 1:3]) * 1e-3  # (N, 2, 3) m
    return np.einsum("nki,nki->nk", np.cross(lever, force), dirs[:, 1:3])


class JointCompliance(VectorEffect):
    """Deflection of joints 2 and 3 under gravity (see the module docstring)."""

    type_name: ClassVar[str] = "joint_compliance"
    adds_joint_delta: ClassVar[bool] = True

    def __init__(self, robot: str, payload_point_mm: np.ndarray | tuple = (0.0, 0.0, 0.0),
                 default_payload_kg: float = 0.0, name: str | None = None, *,
                 gravity_dir: tuple[float, float, float] = (0.0, 0.0, -1.0),
                 free: bool = True) -> None:
        super().__init__(NAMES, name, steps=[1e-8, 1e-8] + [1e-6] * 4, free=free)
        self.robot = str(robot)
        self.payload_point_mm = np.asarray(payload_point_mm, dtype=float).reshape(3)
        self.default_payload_kg = float(default_payload_kg)
        self.gravity_dir = np.asarray(gravity_dir, dtype=float).reshape(3)
        nominal = _robot(self.robot)
        self._elbow_sign = float(np.sign(nominal.axis_dirs[1] @ nominal.axis_dirs[2]) or 1.0)
        self._cache: tuple[tuple, np.ndarray] | None = None  # the last poses' regressors

    def payload(self, ctx: Context, n: int) -> np.ndarray:
        """Payload (N,) kg from the context, else the default."""
        m = self.default_payload_kg if ctx.payload_kg is None else ctx.payload_kg
        return np.broadcast_to(np.asarray(m, dtype=float), (n,))

    def features(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Per pose (N, 2, 3): for joints 2 and 3 the regressors of their three parameters."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        payload = self.payload(ctx, q.shape[0])
        point = (self.payload_point_mm if ctx.payload_cog_mm is None
                 else np.asarray(ctx.payload_cog_mm, dtype=float))
        key = (q.shape, hash(q.tobytes()), hash(np.ascontiguousarray(payload).tobytes()),
               hash(np.ascontiguousarray(point).tobytes()))
        if self._cache is not None and self._cache[0] == key:  # fitters ask again and again
            return self._cache[1]
        tau = payload_torque_per_kg(_robot(self.robot), q, point,
                                    self.gravity_dir) * payload[:, None]
        u = q[:, 1] + self._elbow_sign * q[:, 2]
        arm = np.stack([np.cos(u), np.sin(u)], axis=1)
        j2 = np.column_stack([tau[:, 0], arm])
        j3 = np.column_stack([tau[:, 1], arm])
        features = np.stack([j2, j3], axis=1)
        self._cache = (key, features)
        return features

    def joint_delta(self, q_cmd: np.ndarray, ctx: Context) -> np.ndarray:
        """Deflections of joints 2 and 3 (rad)."""
        q = np.atleast_2d(np.asarray(q_cmd, dtype=float))
        f = self.features(q, ctx)
        p = self._p
        coef = np.array([[p[0], p[2], p[3]], [p[1], p[4], p[5]]])  # (2, 3)
        out = np.zeros_like(q)
        out[:, 1:3] = np.einsum("nkf,kf->nk", f, coef)
        return out

    def context_fields(self) -> frozenset[str]:
        """What this effect reads from the context."""
        return frozenset({"payload_kg", "payload_cog_mm"})

    def _state(self) -> dict[str, Any]:
        return {"robot": self.robot, "payload_point_mm": self.payload_point_mm.tolist(),
                "default_payload_kg": self.default_payload_kg,
                "gravity_dir": self.gravity_dir.tolist()}

    @classmethod
    def _from_state(cls, name: str, state: dict[str, Any]) -> JointCompliance:
        return cls(str(state["robot"]), np.asarray(state["payload_point_mm"], dtype=float),
                   float(state.get("default_payload_kg", 0.0)), name,
                   gravity_dir=tuple(state.get("gravity_dir", (0.0, 0.0, -1.0))))
