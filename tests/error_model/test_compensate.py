"""Compensation: per-joint Newton and the general solve on the full forward model."""

from typing import ClassVar

import numpy as np
import pytest

from rapidfix.error_model.compensate import (
    compensate,
    solve_compensation,
    solve_general,
    solve_per_joint,
)
from rapidfix.error_model.context import Context
from rapidfix.error_model.effect import Effect, Geometry
from rapidfix.error_model.joint_rbf import JointRBF, fit_network
from rapidfix.error_model.model import ErrorModel
from rapidfix.exceptions import ModelError
from rapidfix.kinematics import load_robot

ROBOT = load_robot("IRB1600-10/1.45")
TOL = np.radians(1e-9)


def _true_error(j, x):
    return np.radians(0.01 * (j + 1) / 3 + 0.02 * np.sin(3 * x + j) + 0.008 * np.cos(7 * x))


@pytest.fixture(scope="module")
def joint_model():
    nets = []
    for j in range(6):
        lo, hi = ROBOT.limits[j]
        x = np.arange(lo, hi + 1e-12, np.radians(5.0))
        nets.append(fit_network(x, _true_error(j, x))[0])
    return ErrorModel(ROBOT.name, [JointRBF(nets)])


def _poses(n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = ROBOT.limits[:, 0], ROBOT.limits[:, 1]
    q = rng.uniform(lo, hi, (n, 6))
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.05, 0.3, q[:, 4])  # keep off the wrist singularity
    return q


class AxisTilt(Effect):
    """Test effect: joint 2's axis tilted about x by a small angle (a geometry change)."""

    type_name: ClassVar[str] = "test_axis_tilt"
    changes_geometry: ClassVar[bool] = True

    def __init__(self, name=None, *, free=True, tilt=0.0):
        super().__init__(name, free=free)
        self.tilt = tilt

    @property
    def param_names(self):
        return ("tilt_rad",)

    def params(self):
        return np.array([self.tilt])

    def set_fitted(self, p):
        self.tilt = float(self._check_length(p)[0])

    def apply_geometry(self, geometry: Geometry, q_cmd, ctx):
        dirs = geometry.axis_dirs.copy()
        dirs[1] = [0.0, np.cos(self.tilt), np.sin(self.tilt)]
        return geometry.replaced(axis_dirs=dirs)


def test_per_joint_solution_satisfies_the_equation_to_1e_9_deg(joint_model):
    model = joint_model
    q_ideal = _poses(500, 0)
    res = solve_compensation(model, ROBOT, q_ideal)
    assert res.method == "per-joint"
    assert res.converged.all()
    # independent check: evaluate the defining equation, not the solver's own residual
    assert np.abs(res.q_cmd + model.delta(res.q_cmd) - q_ideal).max() <= TOL
    # and the real work was done: the answer differs from θ_ideal − Δθ(θ_ideal)
    naive = q_ideal - model.delta(q_ideal)
    assert np.abs(res.q_cmd - naive).max() > 100 * TOL


def test_general_solve_agrees_with_the_per_joint_solve(joint_model):
    model = joint_model
    q_ideal = _poses(200, 1)
    per_joint = compensate(model, ROBOT, q_ideal)
    general = solve_general(model, ROBOT, q_ideal)
    assert general.converged.all()
    assert np.degrees(np.abs(general.q_cmd - per_joint)).max() < 1e-8


def test_general_solve_compensates_a_geometry_effect_it_has_no_code_for(joint_model):
    tilt = np.radians(0.05)
    model = ErrorModel(ROBOT.name, [*joint_model.effects, AxisTilt(tilt=tilt)])
    assert not model.separable
    q_ideal = _poses(200, 2)
    tool = np.eye(4)
    tool[:3, 3] = [50.0, 0.0, 120.0]
    res = solve_compensation(model, ROBOT, q_ideal)
    assert res.method == "general" and res.converged.all()
    # independent truth: the kinematics layer's own model of the tilted robot
    dirs = ROBOT.axis_dirs.copy()
    dirs[1] = [0.0, np.cos(tilt), np.sin(tilt)]
    actual = ROBOT.with_screws(dirs, ROBOT.axis_points)
    reached = actual.fk(res.q_cmd + model.delta(res.q_cmd)) @ tool
    target = ROBOT.fk(q_ideal) @ tool
    assert np.abs(reached[:, :3, 3] - target[:, :3, 3]).max() < 1e-7
    assert np.abs(reached[:, :3, :3] - target[:, :3, :3]).max() < 1e-10
    # without compensation the tilt alone moves the TCP by tenths of a mm
    uncompensated = actual.fk(q_ideal + model.delta(q_ideal)) @ tool
    assert np.abs(uncompensated[:, :3, 3] - target[:, :3, 3]).max() > 0.1


class _JointEffect(Effect):
    """A parameterless test effect that adds a joint error."""

    separable: ClassVar[bool] = True
    adds_joint_delta: ClassVar[bool] = True
    param_names = ()

    def params(self):
        return np.zeros(0)

    def set_fitted(self, p):
        self._check_length(p)


class Flat(_JointEffect):
    """Test effect with Δθ = −θ: θ + Δθ is constant, so no θc reaches another target."""

    type_name: ClassVar[str] = "test_flat"

    def joint_delta(self, q_cmd, ctx):
        out = np.zeros_like(q_cmd)
        out[:, 0] = -q_cmd[:, 0]
        return out


def test_unsolvable_poses_are_reported_per_pose_not_returned_as_nan():
    model = ErrorModel(ROBOT.name, [Flat()])
    q_ideal = np.zeros((3, 6))
    q_ideal[1, 0] = 0.5  # only this target is unreachable
    res = solve_compensation(model, ROBOT, q_ideal)
    assert res.converged.tolist() == [True, False, True]
    assert np.isfinite(res.q_cmd).all()
    with pytest.raises(ModelError, match=r"1 pose\(s\), rows \[1\]"):
        compensate(model, ROBOT, q_ideal)


def test_a_model_for_another_robot_is_refused():
    model = ErrorModel("IRB120-3/0.58", [])
    with pytest.raises(ModelError, match="made for robot"):
        compensate(model, ROBOT, np.zeros((1, 6)))


def test_context_subsets_follow_the_active_poses():
    ctx = Context.from_rows(np.arange(12.0).reshape(2, 6), payload_kg=3.0)
    sub = ctx.take(np.array([1]))
    assert sub.payload_kg.tolist() == [3.0]
    assert sub.q_prev.tolist() == [list(np.arange(6.0))]
    assert ctx.direction(np.arange(12.0).reshape(2, 6))[1].tolist() == [1.0] * 6


class Play(_JointEffect):
    """Test effect: each joint lags by 0.02° against its direction of motion (uses ctx)."""

    type_name: ClassVar[str] = "test_play"

    def joint_delta(self, q_cmd, ctx):
        return -np.radians(0.02) * ctx.direction(q_cmd)


def test_chunks_of_poses_give_what_one_pass_gives(joint_model):
    model = ErrorModel(ROBOT.name, [*joint_model.effects, Play()])
    q_ideal = _poses(50, 3)
    # half the joints approached from above, half from below: each row needs its own context
    ctx = Context.from_rows(q_ideal).with_q_prev(q_ideal + np.where(q_ideal > 0, 0.01, -0.01))
    whole = solve_per_joint(model, q_ideal, ctx, chunk=1000)
    parts = solve_per_joint(model, q_ideal, ctx, chunk=7)
    # the same answers up to rounding (vector kernels treat the last rows of an array
    # with other instructions, so chunk ends can differ in the last bit)
    assert np.abs(parts.q_cmd - whole.q_cmd).max() < 1e-14
    assert np.array_equal(parts.converged, whole.converged)
    assert parts.iterations == whole.iterations and parts.converged.all()
    # each pose solved with its own context row: the defining equation holds
    residual = parts.q_cmd + model.delta(parts.q_cmd, ctx) - q_ideal
    assert np.abs(residual).max() <= TOL
    shared = solve_per_joint(model, q_ideal, Context.from_rows(q_ideal), chunk=7)
    assert np.abs(shared.q_cmd - parts.q_cmd).max() > np.radians(0.01)  # the context matters


class ShortForearm(AxisTilt):
    """Test effect: joints 4-6 and tool0 sit `short` mm nearer joint 3 (a geometry change)."""

    type_name: ClassVar[str] = "test_short_forearm"

    def apply_geometry(self, geometry: Geometry, q_cmd, ctx):
        points = geometry.axis_points.copy()
        points[3:, 0] -= self.tilt
        home = geometry.home.copy()
        home[:3, 3] -= [self.tilt, 0.0, 0.0]
        return geometry.replaced(axis_points=points, home=home)


def test_general_solve_does_not_run_away_at_a_stretched_elbow(joint_model):
    # Joint 3 at -90° stretches the arm (the elbow singularity): a target there lies
    # beyond the reach of a forearm 0.3 mm short. The solve cannot match it, but it
    # must stay near (its best iterate), not wander off along the singular direction.
    model = ErrorModel(ROBOT.name, [*joint_model.effects, ShortForearm(tilt=0.3)])
    q_ideal = np.radians([[-52.0, -3.5, -90.2, -125.7, -98.8, -42.4],
                          [20.0, 10.0, -90.0, 30.0, 40.0, 10.0]])
    res = solve_compensation(model, ROBOT, q_ideal)
    seed = q_ideal - model.delta(q_ideal)
    assert np.degrees(np.abs(res.q_cmd - q_ideal)).max() < 1.0
    target = ROBOT.fk(q_ideal)[:, :3, 3]
    reached = model.actual_flange(ROBOT, res.q_cmd)[:, :3, 3]
    from_seed = model.actual_flange(ROBOT, seed)[:, :3, 3]
    # the pose error it minimises weighs the turn too: the position stays as close
    assert np.all(np.linalg.norm(reached - target, axis=1)
                  <= np.linalg.norm(from_seed - target, axis=1) + 0.05)
