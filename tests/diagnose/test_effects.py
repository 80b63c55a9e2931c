"""The candidate effects against independent formulations, and their model-file round trip."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rapidfix.error_model.candidates.backlash import Backlash, last_motion_direction
from rapidfix.error_model.candidates.compliance import JointCompliance, payload_torque_per_kg
from rapidfix.error_model.candidates.coupling import JointCoupling
from rapidfix.error_model.candidates.geometry import LinkGeometry, identifiable_modes
from rapidfix.error_model.candidates.joint_reference import JointReference
from rapidfix.error_model.candidates.registration import TrackerFrame, TrackerScale, world_to_base
from rapidfix.error_model.candidates.thermal import ThermalDrift
from rapidfix.error_model.candidates.tool_offset import ToolOffset
from rapidfix.error_model.context import Context
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model
from rapidfix.error_model.registry import effect_from_dict
from rapidfix.kinematics import load_robot

ROBOT = load_robot("IRB1600-10/1.45")
BALL = np.array([60.0, 80.0, 90.0])


def _poses(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(np.radians(-60), np.radians(60), (n, 6))


def _ball(T):
    return T[:, :3, :3] @ BALL + T[:, :3, 3]


def test_payload_torque_matches_lever_arm_at_home():
    # at θ = 0 axis 2 is along +y through (150, 0, 486.5): τ = m g (x_ball − 150 mm)
    q = np.zeros((1, 6))
    x = _ball(ROBOT.fk(q))[0, 0]
    tau = payload_torque_per_kg(ROBOT, q, BALL, np.array([0.0, 0.0, -1.0]))
    assert tau[0, 0] == pytest.approx(9.81 * (x - 150.0) / 1000.0, rel=1e-12)
    assert tau[0, 1] == pytest.approx(9.81 * (x - 150.0) / 1000.0, rel=1e-12)  # axis 3 too


def test_compliance_deflects_joints_2_and_3_with_the_payload_only():
    eff = JointCompliance(ROBOT.name, BALL, default_payload_kg=2.0)
    eff.set_fitted(np.array([1e-6, 2e-6, 0, 0, 0, 0]))
    q = _poses(5)
    light = eff.joint_delta(q, Context(payload_kg=np.zeros(5)))
    heavy = eff.joint_delta(q, Context(payload_kg=np.full(5, 10.0)))
    default = eff.joint_delta(q, Context())
    tau = payload_torque_per_kg(ROBOT, q, BALL, np.array([0.0, 0.0, -1.0]))
    np.testing.assert_allclose(heavy[:, 1:3] - light[:, 1:3], 10.0 * tau * [1e-6, 2e-6])
    np.testing.assert_allclose(default[:, 1:3], 2.0 * tau * [1e-6, 2e-6])
    assert not heavy[:, [0, 3, 4, 5]].any()


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(-3, 3), min_size=2, max_size=30))
def test_motion_direction_is_the_sign_of_the_last_move(steps):
    q = np.zeros((len(steps), 6))
    q[:, 2] = np.cumsum(np.asarray(steps, dtype=float)) * 0.1
    q_prev = np.vstack([q[:1], q[:-1]])
    got = last_motion_direction(q, q_prev)[:, 2]
    last = 0.0  # a loop written independently: remember the last non-zero move
    for i in range(len(steps)):
        move = q[i, 2] - q_prev[i, 2]
        if abs(move) > 1e-12:
            last = np.sign(move)
        assert got[i] == last


def test_backlash_is_half_the_play_against_the_motion():
    eff = Backlash()
    play = np.radians([0.02, 0.01, 0.03, 0, 0, 0])
    eff.set_fitted(play)
    q = np.array([[0.0] * 6, [0.1] * 6, [0.05] * 6])
    delta = eff.joint_delta(q, Context.from_rows(q))
    np.testing.assert_allclose(delta[1], -play / 2)
    np.testing.assert_allclose(delta[2], play / 2)
    assert not delta[0].any()  # first row: direction unknown


def test_thermal_drift_scales_the_arm_about_the_base():
    eff = ThermalDrift("temp_c", reference=20.0)
    eff.set_fitted(np.array([5.0, 20.0]))  # 5 ppm at 20 °C, 20 ppm/K
    q = _poses(4)
    temp = np.array([20.0, 22.0, 25.0, 30.0])
    model = ErrorModel(ROBOT.name, [eff])
    flange = model.actual_flange(ROBOT, q, Context(temp_c=temp))
    s = 1 + 1e-6 * (5.0 + 20.0 * (temp - 20.0))
    np.testing.assert_allclose(flange[:, :3, 3], ROBOT.fk(q)[:, :3, 3] * s[:, None], atol=1e-9)
    np.testing.assert_allclose(flange[:, :3, :3], ROBOT.fk(q)[:, :3, :3], atol=1e-12)


def test_thermal_drift_without_temperature_follows_time_in_hours():
    eff = ThermalDrift("time_s", reference=1800.0)
    eff.set_fitted(np.array([0.0, 10.0]))  # 10 ppm per hour
    q = _poses(3)
    s = eff.scale(q, Context(time_s=np.array([1800.0, 5400.0, 9000.0])))
    np.testing.assert_allclose(s, 1 + 1e-6 * np.array([0.0, 10.0, 20.0]))
    np.testing.assert_allclose(eff.scale(q, Context()), 1.0)  # no time: the reference


def test_tool_offset_moves_the_ball_with_the_flange():
    eff = ToolOffset()
    eff.set_fitted(np.array([0.3, -0.2, 0.1]))
    q = _poses(6)
    model = ErrorModel(ROBOT.name, [eff])
    moved = model.predict_ball(ROBOT, q, BALL)
    R = ROBOT.fk(q)[:, :3, :3]
    np.testing.assert_allclose(moved - _ball(ROBOT.fk(q)), R @ [0.3, -0.2, 0.1], atol=1e-9)


def test_registration_maps_into_the_tracker_and_back():
    R = Rotation.from_euler("zyx", [40, 0.3, -0.2], degrees=True).as_matrix()
    t = np.array([2500.0, -1200.0, 300.0])
    scale = TrackerScale()
    scale.set_fitted(np.array([60.0]))
    model = ErrorModel(ROBOT.name, [TrackerFrame.from_pose(R, t), scale])
    q = _poses(5)
    p = model.predict_ball(ROBOT, q, BALL)
    seen = model.predict_ball(ROBOT, q, BALL, frame="world")
    np.testing.assert_allclose(seen, (1 + 60e-6) * p @ R.T + t, atol=1e-9)
    world = model.geometry(ROBOT, q).world
    np.testing.assert_allclose(world_to_base(world, seen), p, atol=1e-9)


def test_coupling_moves_only_the_target_joint():
    eff = JointCoupling(source=1, target=2)
    eff.set_fitted(np.array([1e-4, -2e-4]))
    q = _poses(7)
    delta = eff.joint_delta(q, Context())
    np.testing.assert_allclose(delta[:, 2], 1e-4 * np.sin(q[:, 1]) - 2e-4 * np.cos(q[:, 1]))
    assert not np.delete(delta, 2, axis=1).any()


def test_identifiable_modes_drop_what_the_nuisance_explains():
    rng = np.random.default_rng(3)
    nuisance = rng.normal(size=(90, 4))
    own = rng.normal(size=(90, 2))
    errors = np.column_stack([own, nuisance[:, 0] * 2.0, own[:, 0] + nuisance[:, 1]])
    modes, _ = identifiable_modes(np.pad(errors, ((0, 0), (0, 22))), nuisance)
    assert modes.shape[1] == 2  # the duplicate of the nuisance and the combination are gone
    assert np.allclose(modes[2], 0.0, atol=1e-9)


def test_every_new_effect_survives_the_model_file(tmp_path):
    geometry = LinkGeometry(ROBOT.name, np.random.default_rng(1).normal(size=(26, 4)))
    effects = [
        JointCompliance(ROBOT.name, BALL, 3.5),
        geometry,
        ToolOffset(),
        Backlash(),
        ThermalDrift("time_s", 1234.5),
        JointCoupling(4, 5),
        TrackerScale(),
        TrackerFrame(),
        JointReference(),
    ]
    rng = np.random.default_rng(2)
    for eff in effects:
        eff.set_fitted(rng.normal(size=len(eff.param_names)) * 1e-3)
        eff.uncertainty = np.abs(rng.normal(size=len(eff.param_names)))
    model = ErrorModel(ROBOT.name, effects)
    loaded = load_model(save_model(model, tmp_path / "m.json"), ROBOT.name)
    q = _poses(5)
    ctx = Context.from_rows(q, payload_kg=2.0, time_s=np.arange(5) * 60.0)
    np.testing.assert_array_equal(
        loaded.predict_ball(ROBOT, q, BALL, ctx, frame="world"),
        model.predict_ball(ROBOT, q, BALL, ctx, frame="world"),
    )
    for a, b in zip(model.effects, loaded.effects):
        assert type(a) is type(b)
        np.testing.assert_array_equal(a.params(), b.params())
        np.testing.assert_array_equal(a.uncertainty, b.uncertainty)
    assert effect_from_dict(effects[5].to_dict()).describe() == effects[5].describe()
