"""The full forward model: changed geometry per pose, Jacobian, ball prediction."""

from typing import ClassVar

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.error_model.compensate import solve_per_joint
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Effect, Geometry
from rapidfix.error_model.forward import flange_poses
from rapidfix.error_model.model import ErrorModel
from rapidfix.kinematics import load_robot

ROBOT = load_robot("IRB1600-10/1.45")


class Stretch(Effect):
    """Test effect: the upper arm (axes 4–6 points) moves along x with time (per-pose geometry)."""

    type_name: ClassVar[str] = "test_stretch"
    changes_geometry: ClassVar[bool] = True
    param_names = ("mm_per_s",)

    def __init__(self, name=None, *, free=True, rate=0.0):
        super().__init__(name, free=free)
        self.rate = rate

    def params(self):
        return np.array([self.rate])

    def set_fitted(self, p):
        self.rate = float(self._check_length(p)[0])

    def apply_geometry(self, geometry, q_cmd, ctx):
        n = q_cmd.shape[0]
        points = np.broadcast_to(geometry.axis_points, (n, 6, 3)).copy()
        home = np.broadcast_to(geometry.home, (n, 4, 4)).copy()
        shift = self.rate * ctx.time_s
        points[:, 3:, 0] += shift[:, None]
        home[:, 0, 3] += shift
        world = np.eye(4)
        world[:3, 3] = [1000.0, 0.0, 0.0]
        return geometry.replaced(axis_points=points, home=home, world=world)


def _q(n, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(ROBOT.limits[:, 0] * 0.8, ROBOT.limits[:, 1] * 0.8, (n, 6))


def test_per_pose_geometry_matches_the_kinematics_layer_pose_by_pose():
    q = _q(5, 0)
    ctx = Context(time_s=np.arange(5) * 100.0)
    model = ErrorModel(ROBOT.name, [Stretch(rate=0.001)])
    got = model.actual_flange(ROBOT, q, ctx)
    for i in range(5):  # independent truth: one kinematics-layer model per pose
        points = ROBOT.axis_points.copy()
        points[3:, 0] += 0.1 * i
        home = ROBOT.home.copy()
        home[0, 3] += 0.1 * i
        expected = ROBOT.with_screws(ROBOT.axis_dirs, points, home).fk(q[i])
        assert got[i] == pytest.approx(expected, abs=1e-9)
    ball = model.predict_ball(ROBOT, q, [0.0, 0.0, 50.0], ctx, frame="world")
    base = model.predict_ball(ROBOT, q, [0.0, 0.0, 50.0], ctx)
    assert ball - base == pytest.approx(np.tile([1000.0, 0, 0], (5, 1)))


def test_jacobian_of_changed_geometry_matches_finite_differences():
    q = _q(4, 1)
    shifted = ROBOT.axis_points + np.array([0.0, 0.3, -0.2])
    geom = Geometry.nominal(ROBOT).replaced(axis_points=shifted)
    T, jac = flange_poses(ROBOT, geom, q, with_jacobian=True)
    h = 1e-7
    for k in range(6):
        dq = np.zeros(6)
        dq[k] = h
        Tp, _ = flange_poses(ROBOT, geom, q + dq)
        dT = (Tp - T) / h @ np.linalg.inv(T)  # [V] of the space twist
        omega = np.stack([dT[:, 2, 1], dT[:, 0, 2], dT[:, 1, 0]], axis=1)
        assert jac[:, :3, k] == pytest.approx(omega, abs=1e-5)
        assert jac[:, 3:, k] == pytest.approx(dT[:, :3, 3], abs=1e-3)


class Wave(Effect):
    """Test effect: Δθ_j = a_j sin(k θ_j + φ) on every joint (separable)."""

    type_name: ClassVar[str] = "test_wave"
    separable: ClassVar[bool] = True
    adds_joint_delta: ClassVar[bool] = True
    param_names = ("a", "k", "phi")

    def __init__(self, name=None, *, free=True, a=0.0, k=1.0, phi=0.0):
        super().__init__(name, free=free)
        self.a, self.k, self.phi = a, k, phi

    def params(self):
        return np.array([self.a, self.k, self.phi])

    def set_fitted(self, p):
        self.a, self.k, self.phi = self._check_length(p)

    def joint_delta(self, q_cmd, ctx):
        return self.a * np.sin(self.k * q_cmd + self.phi)

    def joint_delta_derivative(self, q_cmd, ctx):
        return self.a * self.k * np.cos(self.k * q_cmd + self.phi)


@settings(max_examples=30, deadline=None)
@given(
    a_deg=st.floats(-1.0, 1.0),
    k=st.floats(0.5, 20.0),
    phi=st.floats(0.0, 6.3),
    seed=st.integers(0, 1000),
)
def test_per_joint_newton_solves_any_mild_error_to_1e_9_deg(a_deg, k, phi, seed):
    model = ErrorModel(ROBOT.name, [Wave(a=np.radians(a_deg), k=k, phi=phi)])
    target = _q(50, seed)
    res = solve_per_joint(model, target)
    assert res.converged.all()
    residual = res.q_cmd + model.delta(res.q_cmd) - target
    assert np.degrees(np.abs(residual)).max() <= 1e-9
