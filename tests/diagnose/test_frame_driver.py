"""Effects on frames (the tool, the base, a link) against the simulator's own physics;
model file round trip; compensation by the general solve; the screen on a known cause."""

import numpy as np
import pytest

from rapidfix.diagnose.features import exposing_feature
from rapidfix.diagnose.structured import ranking_records, screen, variants
from rapidfix.error_model.candidates.frame_driver import FRAMES, FrameDriver
from rapidfix.error_model.compensate import compensate
from rapidfix.error_model.context import Context
from rapidfix.error_model.fit_effects import MeasuredPoints, predict
from rapidfix.error_model.model import ErrorModel
from rapidfix.error_model.model_file import load_model, save_model
from rapidfix.kinematics import load_robot
from rapidfix.sim import VirtualRobot
from rapidfix.sim.true_errors import GRAVITY, LINK_MASSES_KG
from rapidfix.sim.virtual_robot import RunConditions

ROBOT = load_robot("IRB1600-10/1.45")
BALL = np.array([60.0, 80.0, 90.0])


def _poses(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(np.radians(-80), np.radians(80), (n, 6))


def _model_of_the_truth(effect, truth, vr):
    """The frame effect with the simulator's true values, in the model's parameters."""
    if effect == "tool_bending":
        eff = FrameDriver("tool", robot=ROBOT.name, payload_point_mm=vr.smr_offset_mm)
        lever = (truth["tool_cog_mm"] - truth["hinge_mm"]) * 1e-3
        own = truth["k_rad_per_nm"] * truth["tool_kg"] * abs(GRAVITY[2]) * lever
        eff.set_fitted(np.array([own, truth["k_rad_per_nm"], truth["hinge_mm"]]))
    elif effect == "base_tilt":
        eff = FrameDriver("base", robot=ROBOT.name, payload_point_mm=vr.smr_offset_mm)
        k = truth["k_rad_per_nm"]
        points = np.asarray(ROBOT.axis_points) * 1e-3  # home pose, m
        # the simulator's lumped bodies: the lower arm halfway along link 2 (0-based 1),
        # the upper arm 40 % along link 3 and the wrist at its centre (both on link 2)
        lower = LINK_MASSES_KG["lower_arm"], 0.5 * (points[1] + points[2])
        upper = LINK_MASSES_KG["upper_arm"], points[2] + 0.4 * (points[4] - points[2])
        wrist = LINK_MASSES_KG["wrist"], points[4]
        p = np.zeros(len(eff.param_names))
        p[0] = k
        p[1:4], p[4] = k * lower[0] * lower[1], k * lower[0]
        p[5:8] = k * (upper[0] * upper[1] + wrist[0] * wrist[1])
        p[8] = k * (upper[0] + wrist[0])
        p[-1] = truth["pivot_depth_mm"]
        eff.set_fitted(p)
    else:
        eff = FrameDriver("link", robot=ROBOT.name, link=truth["link"],
                          reference=truth["t_ref_c"])
        eff.set_fitted(np.array([0.0, 1e6 * truth["alpha_per_k"]]))
    return eff


@pytest.mark.parametrize("effect", ["tool_bending", "base_tilt", "link_thermal"])
def test_each_frame_effect_matches_the_simulator(effect):
    # the simulator (rapidfix.sim) computes each physics its own way; with the true
    # values the structured effect moves the ball as the simulator does
    q = _poses(40, seed=1)
    payload = np.linspace(0.0, 10.0, 40)
    temp = np.linspace(20.0, 36.0, 40)
    vr = VirtualRobot.create(seed=5, effects=(effect,))
    plain = VirtualRobot.create(seed=5, effects=())
    run = RunConditions(payload_kg=payload, temp_c=temp, q_prev=q)
    moved = vr.ball_positions(q, run) - plain.ball_positions(q, run)
    truth = getattr(vr.errors, effect)
    model = ErrorModel(ROBOT.name, [_model_of_the_truth(effect, truth, vr)])
    T = ROBOT.fk(q)
    ours = (model.predict_ball(ROBOT, q, vr.smr_offset_mm, Context(payload_kg=payload,
                                                                   temp_c=temp))
            - (T[:, :3, :3] @ vr.smr_offset_mm + T[:, :3, 3]))
    assert np.linalg.norm(moved, axis=1).mean() > 0.02  # the effect is there
    # the simulator turns its actual joints (per-joint errors on), the model the commanded
    np.testing.assert_allclose(ours, moved, atol=2e-4)


def _examples():
    tool = FrameDriver("tool", robot=ROBOT.name, payload_point_mm=BALL, default_payload_kg=2.0)
    tool.set_fitted(np.array([4e-4, 1.5e-4, 20.0]))
    base = FrameDriver("base", robot=ROBOT.name, payload_point_mm=BALL)
    base.set_fitted(np.r_[3e-7, np.full(len(base.param_names) - 2, 1e-7), 150.0])
    link = FrameDriver("link", robot=ROBOT.name, link=3, reference=25.0)
    link.set_fitted(np.array([5.0, 11.5]))
    return [tool, base, link]


def _context(n):
    return Context(payload_kg=np.linspace(0.0, 9.0, n), temp_c=np.linspace(21.0, 33.0, n),
                   payload_cog_mm=np.tile([0.0, 10.0, 70.0], (n, 1)))


def test_frame_effects_round_trip_through_the_model_file(tmp_path):
    assert {e.frame for e in _examples()} == set(FRAMES)
    q = _poses(25, seed=2)
    ctx = _context(25)
    model = ErrorModel(ROBOT.name, _examples())
    loaded = load_model(save_model(model, tmp_path / "m.json"), ROBOT.name)
    np.testing.assert_array_equal(loaded.actual_flange(ROBOT, q, ctx),
                                  model.actual_flange(ROBOT, q, ctx))
    assert [e.describe() for e in loaded.effects] == [e.describe() for e in model.effects]
    assert loaded.context_fields() == {"payload_kg", "payload_cog_mm", "temp_c"}


def test_each_frame_moves_what_it_should():
    q = _poses(20, seed=3)
    ctx = _context(20)
    nominal = ROBOT.fk(q)
    tool, base, link = _examples()
    # the tool's bend turns the flange about axes perpendicular to the tool axis
    T = ErrorModel(ROBOT.name, [tool]).actual_flange(ROBOT, q, ctx)
    turn = np.einsum("nji,njk->nik", nominal[:, :3, :3], T[:, :3, :3])  # in the flange frame
    axis = np.stack([turn[:, 2, 1] - turn[:, 1, 2], turn[:, 0, 2] - turn[:, 2, 0],
                     turn[:, 1, 0] - turn[:, 0, 1]], axis=1) / 2
    assert np.all(np.linalg.norm(axis[:, :2], axis=1) > 1e-5)
    np.testing.assert_allclose(axis[:, 2], 0.0, atol=1e-12)
    # the base tilts about horizontal axes only: vertical axis-1 angle unchanged
    geom = ErrorModel(ROBOT.name, [base]).geometry(ROBOT, q, ctx)
    tilt = geom.axis_dirs[:, 0]
    assert np.all(np.linalg.norm(tilt[:, :2], axis=1) > 1e-7)
    np.testing.assert_allclose(np.linalg.norm(tilt, axis=1), 1.0)
    # a link grows along itself: 1e-6 (c0 + c1 ΔT) times its length, joints before it
    # untouched
    geom = ErrorModel(ROBOT.name, [link]).geometry(ROBOT, q, ctx)
    shift = geom.axis_points[:, 3] - np.asarray(ROBOT.axis_points)[3]
    length = np.asarray(ROBOT.axis_points)[3] - np.asarray(ROBOT.axis_points)[2]
    expected = 1e-6 * (5.0 + 11.5 * (ctx.temp_c - 25.0))[:, None] * length
    np.testing.assert_allclose(shift, expected, atol=1e-12)
    np.testing.assert_array_equal(geom.axis_points[:, :3], np.broadcast_to(
        ROBOT.axis_points, (20, 6, 3))[:, :3])


def test_a_frame_model_is_compensated_by_the_general_solve():
    q_ideal = _poses(12, seed=4)
    ctx = _context(12)
    model = ErrorModel(ROBOT.name, _examples())
    assert not model.separable
    q_cmd = compensate(model, ROBOT, q_ideal, ctx)
    reached = model.actual_flange(ROBOT, q_cmd, ctx)
    np.testing.assert_allclose(reached[:, :3, 3], ROBOT.fk(q_ideal)[:, :3, 3], atol=1e-6)
    np.testing.assert_allclose(reached[:, :3, :3], ROBOT.fk(q_ideal)[:, :3, :3], atol=1e-9)


@pytest.mark.parametrize("frame", ["tool", "base", "link"])
def test_the_screen_ranks_the_hidden_frame_first(frame):
    # points generated by the model itself with one frame effect on top: the screen finds
    # it among every joint × driver and frame × driver variant
    q = _poses(60, seed=6)
    ctx = _context(60)
    truth = ErrorModel(ROBOT.name, [e for e in _examples() if e.frame == frame])
    data = MeasuredPoints(q, np.zeros((60, 3)), ctx, BALL)
    xyz = predict(truth, ROBOT, data) + np.random.default_rng(0).normal(0, 0.005, (60, 3))
    data = MeasuredPoints(q, xyz, ctx, BALL)
    assert frame in {getattr(v, "frame", None) for v in variants(ROBOT.name, data, 0.0)}
    ranked = screen(ErrorModel(ROBOT.name), ROBOT, data, 0.0)
    assert getattr(ranked[0].effect, "frame", None) == frame, ranked[0].label
    assert ranked[0].share > 0.8
    record = ranking_records(ranked, 1)[0]
    assert record["frame"] == frame and record["joint"] is None


def test_frame_effects_say_where_and_what_drives_them():
    tool, base, link = _examples()
    tool.uncertainty = np.array([5e-5, 1e-5, 3.0])
    text = tool.sentence()
    assert text.startswith("the tool bends under its own weight and the payload's, "
                           "perpendicular to its axis")
    assert "150.0 ± 10.0 µrad/N·m" in text and "400 ± 50 µrad under its own weight" in text
    assert "µm/N" in text
    tool.set_fitted(np.array([4e-4, 0.0, 0.0]))
    tool.uncertainty = np.array([5e-5, 0.0, 3.0])
    assert tool.sentence().endswith(": 400 ± 50 µrad with the tool held horizontal (54 µm at "
                                    "the target ball); the payload did not vary")
    assert base.sentence().startswith("the base tilts with the overturning moment")
    assert "0.300 µrad/N·m" in base.sentence()
    assert link.sentence() == ("link 3 (joint 3 to joint 4) grows with the temperature (along "
                               "the link): 11.5 ppm/K of its length")
    data = MeasuredPoints(_poses(5), np.zeros((5, 3)), _context(5), BALL)
    assert exposing_feature(base, data).label == "payload (kg)"
    assert exposing_feature(link, data).label == "temperature (°C)"


def test_frame_effects_leave_every_other_draw_of_the_simulator_unchanged():
    # their parameters come from a stream of their own: a session with them switched on
    # has the same per-joint errors, other effects and tracker pose as without
    others = ("joint_compliance", "backlash", "wrist_compliance", "encoder_thermal")
    for seed in (1, 7):
        plain = VirtualRobot.create(seed=seed, effects=others)
        more = VirtualRobot.create(seed=seed, effects=(*others, "tool_bending", "base_tilt",
                                                       "link_thermal"))
        a, b = plain.truth(), more.truth()
        for key in ("tool_bending", "base_tilt", "link_thermal"):
            assert key in b["errors"] and key not in a["errors"]
            del b["errors"][key]
        b["errors"]["effects"] = [e for e in b["errors"]["effects"] if e in others]
        assert a == b
        round_trip = VirtualRobot.from_truth(more.truth())
        q = _poses(5, seed)
        run = RunConditions(payload_kg=np.full(5, 4.0), temp_c=np.full(5, 30.0))
        np.testing.assert_array_equal(round_trip.ball_positions(q, run),
                                      more.ball_positions(q, run))
