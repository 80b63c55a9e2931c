"""Structured effects (a joint and its driver) against independent formulations; model file
round trip; compensation by the general solve; the structured search on a known cause."""

import numpy as np
import pytest

from rapidfix.diagnose.features import exposing_feature
from rapidfix.diagnose.structured import screen, variants
from rapidfix.error_model.candidates.gravity import body_torque_regressors, payload_torques
from rapidfix.error_model.candidates.joint_driver import DRIVERS, JointDriver
from rapidfix.error_model.compensate import compensate
from rapidfix.error_model.context import Context
from rapidfix.error_model.fit_effects import MeasuredPoints, predict
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model
from rapidfix.kinematics import load_robot
from rapidfix.sim.true_errors import torque_about

ROBOT = load_robot("IRB1600-10/1.45")
BALL = np.array([60.0, 80.0, 90.0])


def _poses(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(np.radians(-80), np.radians(80), (n, 6))


def _points(T, local):
    return np.einsum("nij,j->ni", T[:, :3, :3], local) + T[:, :3, 3]


def test_payload_torque_about_every_joint_matches_the_simulator():
    q = _poses(40)
    mass = np.linspace(0.5, 10.0, 40)
    T = ROBOT.fk(q)
    dirs, points = ROBOT.joint_frames(q)
    ours = payload_torques(ROBOT, q, BALL, mass)
    for j in range(6):
        truth = torque_about(dirs[:, j], points[:, j], _points(T, BALL)[:, None, :],
                             mass[:, None])
        np.testing.assert_allclose(ours[:, j], truth, atol=1e-9)
    np.testing.assert_allclose(ours[:, 0], 0.0, atol=1e-9)  # axis 1 is vertical


@pytest.mark.parametrize("joint", [1, 2, 3, 4])
def test_a_body_on_the_flange_loads_a_joint_through_its_mass_moment(joint):
    # a 2.5 kg tool body at c in the flange frame: its torque is the regressors · m (c − a_j)
    q = _poses(30, seed=joint)
    cog, mass = np.array([10.0, -20.0, 110.0]), 2.5
    T = ROBOT.fk(q)
    dirs, points = ROBOT.joint_frames(q)
    truth = torque_about(dirs[:, joint], points[:, joint], _points(T, cog)[:, None, :],
                         np.full((30, 1), mass))
    home_point = ROBOT.home[:3, :3] @ cog + ROBOT.home[:3, 3]
    moment = mass * home_point * 1e-3  # kg·m about the base origin, home pose
    ours = body_torque_regressors(ROBOT, q, joint, 5) @ np.append(moment, mass)
    np.testing.assert_allclose(ours, truth, atol=1e-9)


def _driver_examples():
    return [
        JointDriver(3, "gravity", robot=ROBOT.name, payload_point_mm=BALL,
                    default_payload_kg=2.0),
        JointDriver(1, "temperature", reference=24.0),
        JointDriver(2, "time", reference=600.0),
        JointDriver(0, "payload", reference=3.0),
        JointDriver(4, "direction", source=3),
        JointDriver(2, "angle", source=1),
        JointDriver(5, "own_angle"),
    ]


def _context(q):
    n = len(q)
    return Context.from_rows(q, payload_kg=np.linspace(0, 9, n),
                             time_s=np.linspace(0, 1200, n), temp_c=np.linspace(21, 27, n))


def test_every_driver_round_trips_through_the_model_file(tmp_path):
    assert {e.driver for e in _driver_examples()} == set(DRIVERS)
    q = _poses(25, seed=3)
    ctx = _context(q)
    rng = np.random.default_rng(1)
    model = ErrorModel(ROBOT.name)
    for eff in _driver_examples():
        eff.set_fitted(rng.normal(size=len(eff.param_names)) * np.asarray(eff.steps) * 50)
        model.effects.append(eff)
    loaded = load_model(save_model(model, tmp_path / "m.json"), ROBOT.name)
    np.testing.assert_array_equal(loaded.delta(q, ctx), model.delta(q, ctx))
    assert [e.describe() for e in loaded.effects] == [e.describe() for e in model.effects]
    assert loaded.context_fields() == {"payload_kg", "payload_cog_mm", "temp_c", "time_s",
                                       "last_direction"}


def test_each_driver_acts_on_its_joint_only_and_follows_its_driver():
    q = _poses(25, seed=4)
    ctx = _context(q)
    for eff in _driver_examples():
        eff.set_fitted(np.ones(len(eff.param_names)) * 1e-4)
        delta = eff.joint_delta(q, ctx)
        acts = {eff.joint} | ({eff.source} if eff.driver == "angle" else set())
        assert set(np.flatnonzero(np.ptp(delta, axis=0) > 0)) == acts, eff.driver
        assert np.all(np.delete(delta, sorted(acts), axis=1) == 0.0)
    # a direction driver flips with the source joint's last motion, not the joint's own
    eff = JointDriver(4, "direction", source=3)
    eff.set_fitted(np.array([1e-4]))
    d = Context(last_direction=np.array([[1.0, 1, 1, 1, -1, 1], [-1, -1, -1, -1, -1, -1]]))
    np.testing.assert_allclose(eff.joint_delta(np.zeros((2, 6)), d)[:, 4], [1e-4, -1e-4])


def test_a_structured_model_is_compensated_by_the_general_solve():
    q_ideal = _poses(12, seed=5)
    ctx = Context(payload_kg=np.full(12, 5.0), temp_c=np.full(12, 26.0),
                  last_direction=np.where(np.arange(72).reshape(12, 6) % 2, 1.0, -1.0))
    model = ErrorModel(ROBOT.name, [e for e in _driver_examples() if e.driver != "time"])
    for eff in model.effects:
        eff.set_fitted(np.full(len(eff.param_names), 3e-4) * np.asarray(eff.steps) / 2e-6)
    assert not model.separable
    q_cmd = compensate(model, ROBOT, q_ideal, ctx)
    reached = model.actual_flange(ROBOT, q_cmd, ctx)
    np.testing.assert_allclose(reached[:, :3, 3], ROBOT.fk(q_ideal)[:, :3, 3], atol=1e-6)


def test_the_screen_ranks_the_hidden_joint_and_driver_first():
    # points generated by the model itself with one driver on top: the screen finds it
    q = _poses(60, seed=6)
    ctx = _context(q)
    truth = ErrorModel(ROBOT.name, [JointDriver(2, "direction", source=4)])
    truth.effects[0].set_fitted(np.array([np.radians(0.03)]))
    data = MeasuredPoints(q, np.zeros((60, 3)), ctx, BALL)
    xyz = predict(truth, ROBOT, data) + np.random.default_rng(0).normal(0, 0.01, (60, 3))
    data = MeasuredPoints(q, xyz, ctx, BALL)
    names = {(v.joint, v.driver, v.source) for v in variants(ROBOT.name, data, 0.0)}
    assert (2, "direction", 4) in names and (3, "gravity", None) in names
    ranked = screen(ErrorModel(ROBOT.name), ROBOT, data, 0.0)
    best = ranked[0].effect
    assert (best.joint, best.driver, best.source) == (2, "direction", 4)
    assert ranked[0].share > 0.9


def test_the_report_shows_a_structured_effect_against_its_driver():
    q = _poses(20, seed=7)
    data = MeasuredPoints(q, np.zeros((20, 3)), _context(q), BALL)
    shift = exposing_feature(JointDriver(2, "direction", source=4), data)
    assert shift.discrete and "joint 5" in shift.label
    np.testing.assert_array_equal(shift.values, data.ctx.direction(q)[:, 4])
    warm = exposing_feature(JointDriver(1, "temperature", reference=24.0), data)
    np.testing.assert_array_equal(warm.values, data.ctx.temp_c)
    angle = exposing_feature(JointDriver(2, "angle", source=1), data)
    np.testing.assert_allclose(angle.values, np.degrees(q[:, 1]))


def test_a_gravity_effect_says_in_words_what_it_was_fitted_from():
    eff = JointDriver(3, "gravity", robot=ROBOT.name)
    eff.set_fitted(np.array([3.7e-5, 1e-4, 0, 0, 0, 0, 0, 0]))
    eff.uncertainty = np.full(8, 4e-6)
    assert eff.sentence() == ("joint 4's error grows with the gravity torque about joint 4 "
                              "(payload and carried links): 0.00212 ± 0.00023°/N·m of "
                              "payload torque")
    eff.set_fitted(np.array([0.0, 1e-4, 0, 0, 0, 0, 0, 0]))
    eff.uncertainty = np.zeros(8)
    assert "payload did not vary" in eff.sentence()
