"""The virtual robot against formulations written here: FK, potential energy, statistics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rapidfix.sim import RunConditions, VirtualRobot
from rapidfix.sim.true_errors import LINK_MASSES_KG
from rapidfix.sim.virtual_robot import motion_direction

RNG = np.random.default_rng(0)
Q = np.radians(RNG.uniform(-60, 60, (25, 6)))


def fk_ball(model, q, ball):
    T = model.fk(q)
    return T[:, :3, :3] @ ball + T[:, :3, 3]


def test_per_joint_errors_move_the_ball_like_fk_of_the_actual_joints():
    vr = VirtualRobot.create(seed=3)
    delta = vr.true_joint_error(Q)
    sizes = np.degrees(np.abs(delta)).max(axis=0)
    assert np.all(sizes > 0.002) and np.all(sizes < 0.05)
    assert np.allclose(vr.ball_positions(Q), fk_ball(vr.robot, Q + delta, vr.smr_offset_mm))
    assert np.allclose(vr.ideal_positions(Q), fk_ball(vr.robot, Q, vr.smr_offset_mm))
    # noise-free tracker readings are the rigid transform of the true positions
    p = vr.measure(Q, noise=False, frame="tracker")
    assert np.allclose(p, vr.ball_positions(Q) @ vr.tracker.R.T + vr.tracker.t)


def test_tracker_stands_two_to_four_metres_away_slightly_tilted():
    for seed in range(10):
        tr = VirtualRobot.create(seed=seed).tracker
        assert 2000 <= np.linalg.norm(tr.origin_mm[:2]) <= 4000
        assert np.allclose(tr.R @ tr.R.T, np.eye(3)) and np.isclose(np.linalg.det(tr.R), 1)
        tilt = np.degrees(np.arccos(tr.R[2, 2]))
        assert 0.0 < tilt < 0.6


def test_noise_matches_the_stated_model_and_floor():
    vr = VirtualRobot.create(seed=4)
    q = np.repeat(Q[:5], 400, axis=0)
    exact = vr.ball_positions(q)
    measured = vr.measure(q, seed=9)
    err = (measured - exact).reshape(5, 400, 3)
    sigma_tracker = vr.tracker.sigma_mm(exact[::400])
    assert np.all((sigma_tracker > 0.009) & (sigma_tracker < 0.017))
    observed = err.std(axis=1).mean(axis=1)
    # per axis: tracker noise plus the jitter of joint repeatability, 0.01–0.03 mm at the TCP
    jitter = np.linalg.norm(vr.measure(q, seed=3, frame="base") - exact, axis=1)
    assert np.all(observed > sigma_tracker) and np.all(observed < 2.5 * sigma_tracker)
    assert 0.005 < np.mean(jitter) < 0.04
    floor = vr.noise_floor(Q)["mean_tcp_error_mm"]
    direct = np.mean(np.linalg.norm(vr.measure(np.tile(Q, (200, 1)), seed=5)
                                    - np.tile(vr.ball_positions(Q), (200, 1)), axis=1))
    assert floor == pytest.approx(direct, rel=0.05)


def test_truth_round_trip_and_seeds():
    effects = ("joint_compliance", "link_geometry", "backlash", "thermal_drift", "tool_offset",
               "joint_coupling", "registration_scale")
    vr = VirtualRobot.create(seed=8, effects=effects)
    ctx = RunConditions(payload_kg=np.full(len(Q), 5.0), time_s=np.arange(len(Q)) * 60.0)
    again = VirtualRobot.from_truth(vr.truth())
    assert again.errors.effects == list(effects)
    assert np.array_equal(again.ball_positions(Q, ctx), vr.ball_positions(Q, ctx))
    other = VirtualRobot.create(seed=9, effects=effects)
    assert not np.allclose(other.ball_positions(Q, ctx), vr.ball_positions(Q, ctx))
    assert np.array_equal(VirtualRobot.create(seed=8).ball_positions(Q),
                          VirtualRobot.create(seed=8).ball_positions(Q))


def test_compliance_deflects_joints_2_and_3_by_the_gravity_torque():
    """Torque from the potential energy V = Σ m g z (finite differences), written here."""
    vr = VirtualRobot.create(seed=2, effects=("joint_compliance",))
    base = VirtualRobot.create(seed=2)
    q = Q[:6]
    payload = 8.0
    dq = (vr.actual_joints(q, {"payload_kg": payload}) - base.actual_joints(q))[:, 1:3]
    q_act = base.actual_joints(q)

    def potential(qa):
        _, pts = vr.robot.joint_frames(qa)
        ball = fk_ball(vr.robot, qa, vr.smr_offset_mm)
        z = {"lower_arm": 0.5 * (pts[:, 1, 2] + pts[:, 2, 2]),
             "upper_arm": pts[:, 2, 2] + 0.4 * (pts[:, 4, 2] - pts[:, 2, 2]),
             "wrist": pts[:, 4, 2]}
        v = sum(LINK_MASSES_KG[k] * z[k] for k in z) + payload * ball[:, 2]
        return 9.81 * v * 1e-3  # J

    h = 1e-6
    torque = np.empty((len(q), 2))
    for k, j in enumerate((1, 2)):
        step = np.zeros(6)
        step[j] = h
        torque[:, k] = -(potential(q_act + step) - potential(q_act - step)) / (2 * h)
    assert np.allclose(dq, vr.errors.compliance * torque, rtol=1e-4, atol=1e-10)


def test_backlash_flips_with_the_direction_of_motion():
    vr = VirtualRobot.create(seed=5, effects=("backlash",))
    target = np.radians([10, 20, -10, 5, 30, 0])
    up = vr.actual_joints(target, {"q_prev": (target - 0.1)[None]})
    down = vr.actual_joints(target, {"q_prev": (target + 0.1)[None]})
    assert np.allclose(down - up, vr.errors.backlash)
    assert np.all(vr.errors.backlash[:3] > 0) and np.all(vr.errors.backlash[3:] == 0)
    # in row order without q_prev: a joint that stops keeps its last direction
    rows = np.array([target - 0.1, target, target])
    rows[2, 0] = target[0]
    got = vr.actual_joints(rows)
    assert np.allclose(got[2], got[1])


def test_thermal_drift_grows_the_arm_with_temperature():
    vr = VirtualRobot.create(seed=6, effects=("thermal_drift",))
    cold = vr.ball_positions(Q, {"time_s": np.zeros(len(Q))})
    warm = vr.ball_positions(Q, {"time_s": np.full(len(Q), 7200.0)})
    th = vr.errors.thermal
    rise = th["rise_k"] * (1 - np.exp(-7200.0 / th["tau_s"]))
    T = vr.robot.fk(vr.actual_joints(Q))
    assert np.allclose(warm - cold, th["alpha_per_k"] * rise * T[:, :3, 3])
    by_temp = vr.ball_positions(Q, {"temp_c": np.full(len(Q), th["t_ref_c"] + rise)})
    assert np.allclose(by_temp, warm)


def test_tool_offset_geometry_coupling_and_scale():
    plain = VirtualRobot.create(seed=7)
    tool = VirtualRobot.create(seed=7, effects=("tool_offset",))
    R = plain.robot.fk(plain.actual_joints(Q))[:, :3, :3]
    assert np.allclose(tool.ball_positions(Q) - plain.ball_positions(Q),
                       R @ tool.errors.tool_offset)
    assert 0.2 <= np.linalg.norm(tool.errors.tool_offset) <= 0.6
    geo = VirtualRobot.create(seed=7, effects=("link_geometry",))
    moved = np.linalg.norm(geo.ball_positions(Q) - plain.ball_positions(Q), axis=1)
    assert 0.02 < moved.mean() < 2.0
    coup = VirtualRobot.create(seed=7, effects=("joint_coupling",))
    c = coup.errors.coupling
    extra = coup.true_joint_error(Q) - plain.true_joint_error(Q)
    expected = c["amp_rad"] * np.sin(Q[:, c["source"]] + c["phase_rad"])
    assert np.allclose(extra[:, c["target"]], expected)
    assert np.allclose(np.delete(extra, c["target"], axis=1), 0)
    scale = VirtualRobot.create(seed=7, effects=("registration_scale",))
    a, b = scale.measure(Q[:2], noise=False, frame="tracker")
    true = np.linalg.norm(np.subtract(*scale.ball_positions(Q[:2])))
    assert np.linalg.norm(a - b) / true - 1 == pytest.approx(scale.errors.scale_ppm * 1e-6,
                                                             rel=1e-6)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.lists(st.sampled_from([-1.0, 0.0, 0.5, 2.0]), min_size=6, max_size=6),
                min_size=1, max_size=12))
def test_motion_direction_matches_a_row_by_row_walk(rows):
    """The vectorised direction equals a plain walk through the rows in order."""
    q = np.asarray(rows, dtype=float)
    state = np.ones(6)
    expected = np.empty_like(q)
    for i in range(len(q)):
        if i:
            moved = q[i] != q[i - 1]
            state = np.where(moved, np.sign(q[i] - q[i - 1]), state)
        expected[i] = state
    assert np.array_equal(motion_direction(q, None), expected)
