"""Simulated sessions: the plans, the written set, the truth file and `rapidfix simulate`."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rapidfix.cli import main
from rapidfix.exceptions import OutputExistsError
from rapidfix.measure.files import read_points, read_setup, read_sweeps
from rapidfix.sim import EFFECTS, simulate_cell, simulate_set
from rapidfix.sim.plans import ballbar_plan, point_plan, sweep_plan
from rapidfix.sim.virtual_robot import VirtualRobot


@pytest.fixture(scope="module")
def robot():
    return VirtualRobot.create(seed=0).robot


def ball(model, q, smr):
    T = model.fk(q)
    return T[:, :3, :3] @ smr + T[:, :3, 3]


def test_sweep_plan_is_the_papers(robot):
    plan = sweep_plan(robot, np.array([60.0, 80.0, 90.0]))
    deg = np.degrees(plan.q)
    for j in range(6):
        rows = plan.sweep_joint == j
        others = np.delete(deg[rows], j, axis=1)
        assert np.allclose(others, others[0])  # the other joints stay fixed
        assert set(plan.repeat[rows]) == {1, 2, 3}
        angles = np.unique(deg[rows, j])
        assert np.allclose(np.diff(angles), 5.0)  # 5° steps, no gaps
        lo, hi = np.degrees(robot.limits[j])
        assert angles.min() >= max(lo, -180) and angles.max() <= min(hi, 180)
        assert np.ptp(angles) >= 100.0  # a real range, not a token one
    assert np.all(ball(robot, plan.q, np.array([60.0, 80.0, 90.0]))[:, 2] >= 100.0)


def test_point_plan_is_spread_plausible_and_seeded(robot):
    smr = np.array([60.0, 80.0, 90.0])
    q = point_plan(robot, smr, 40, seed=3)
    assert q.shape == (40, 6) and np.all(robot.within_limits(q))
    assert np.all(np.abs(np.degrees(q[:, 4])) >= 15.0)
    assert np.all(ball(robot, q, smr)[:, 2] >= 100.0)
    assert np.all(np.ptp(np.degrees(q), axis=0) > 60.0)
    assert np.array_equal(q, point_plan(robot, smr, 40, seed=3))
    assert not np.allclose(q, point_plan(robot, smr, 40, seed=4))


def test_ballbar_plan_is_a_semicircle_in_a_45_degree_plane(robot):
    smr = np.array([60.0, 80.0, 90.0])
    plan = ballbar_plan(robot, smr)
    p = ball(robot, plan.q, smr)  # nominal FK of the commanded joints: the ideal points
    assert np.allclose(p, plan.ideal_mm, atol=1e-6)
    assert np.allclose(np.linalg.norm(p - plan.centre_mm, axis=1), plan.radius_mm, atol=1e-6)
    assert np.allclose((p - plan.centre_mm) @ plan.normal, 0.0, atol=1e-6)
    assert np.degrees(np.arccos(plan.normal[2])) == pytest.approx(45.0)
    assert np.degrees(np.ptp(plan.angles)) == pytest.approx(180.0)
    assert np.all(np.abs(np.diff(plan.q, axis=0)) < np.radians(10))  # one branch, no flips


def test_simulate_cell_writes_a_readable_set_and_the_truth(tmp_path):
    out = simulate_cell(tmp_path / "set", seed=5, effects=("joint_compliance", "thermal_drift"),
                        n_calibration=12, n_validation=8, n_outliers=2)
    setup = read_setup(out / "setup.toml")
    sweeps = read_sweeps(out / "sweeps.csv")
    cal, val = read_points(out / "calibration.csv"), read_points(out / "validation.csv")
    bb = read_points(out / "ballbar.csv")
    assert setup.robot == "IRB1600-10/1.45" and len(cal) == 12 and len(val) == 8
    assert cal.payload_kg is not None and np.ptp(cal.payload_kg) > 0
    assert np.all(np.diff(np.concatenate([sweeps.time_s, cal.time_s, val.time_s,
                                          bb.time_s])) > 0)
    assert "length_mm" in bb.extra
    truth = json.loads((out / "truth.json").read_text())
    assert truth["errors"]["effects"] == ["joint_compliance", "thermal_drift"]
    assert 0.01 < truth["noise_floor"]["mean_tcp_error_mm"] < 0.05
    assert len(truth["outlier_rows"]["sweeps.csv"]) == 2
    # the data are the truth's robot, measured: rebuild it and compare
    vr = VirtualRobot.from_truth(truth)
    exact = vr.measure(cal.q, {"payload_kg": cal.payload_kg, "time_s": cal.time_s},
                       noise=False, frame="tracker", ball=cal.ball)
    assert np.abs(exact - cal.xyz).max() < 0.15
    # the points turn through the two nests the setup declares; the sweeps use nest 0
    assert cal.ball.tolist() == [0, 1] * 6 and setup.ball_offsets_mm.shape == (2, 3)
    np.testing.assert_allclose(setup.ball_offsets_mm, vr.smr_offsets_mm)
    on_first = vr.measure(cal.q, {"payload_kg": cal.payload_kg, "time_s": cal.time_s},
                          noise=False, frame="tracker")
    apart = np.linalg.norm(on_first - cal.xyz, axis=1)
    assert np.all(apart[cal.ball == 0] < 0.15) and np.all(apart[cal.ball == 1] > 100.0)
    with pytest.raises(OutputExistsError):
        simulate_cell(out, seed=5)


def test_effects_change_only_what_they_name():
    base = simulate_set(4, n_calibration=5, n_validation=5)
    with_tool = simulate_set(4, ("tool_offset",), n_calibration=5, n_validation=5)
    assert np.array_equal(base.calibration.q, with_tool.calibration.q)
    assert with_tool.truth["errors"]["joint_errors"] == base.truth["errors"]["joint_errors"]
    shift = np.linalg.norm(with_tool.calibration.xyz - base.calibration.xyz, axis=1)
    assert 0.1 < shift.mean() < 0.8
    # the same noise realisation: data minus the noise-free truth agree
    heavy = simulate_set(4, ("joint_compliance",), n_calibration=5, n_validation=5)
    for data in (with_tool, heavy):
        t = data.sweeps
        exact = data.robot.measure(t.q, {"payload_kg": t.payload_kg}, noise=False,
                                   frame="tracker")
        base_exact = base.robot.measure(t.q, noise=False, frame="tracker")
        assert np.allclose(t.xyz - exact, base.sweeps.xyz - base_exact, atol=1e-4)
    with pytest.raises(ValueError, match="unknown effect"):
        simulate_set(4, ("gremlins",))


def test_simulate_command(tmp_path, capsys):
    out = tmp_path / "cli"
    args = ["simulate", str(out), "--seed", "2", "--effect", "backlash",
            "--calibration-points", "6", "--validation-points", "5"]
    assert main(args) == 0
    said = capsys.readouterr().out
    assert str(out) in said and "backlash" in said and "noise floor" in said
    assert len(read_points(out / "validation.csv")) == 5
    assert main(args) == 1  # refuses to overwrite
    assert "already holds" in capsys.readouterr().err
    assert main([*args, "--force"]) == 0
    with pytest.raises(SystemExit):
        main(["simulate", str(out), "--effect", "gremlins"])
    assert set(EFFECTS) >= {"backlash", "joint_compliance"}
    # --balls 1: one ball, written in the single-ball format
    assert main([*args, "--force", "--balls", "1"]) == 0
    assert read_points(out / "validation.csv").ball is None
    assert "smr_offsets_mm" not in (out / "setup.toml").read_text()


def test_one_ball_sessions_are_the_two_ball_sessions_on_nest_0():
    """The second nest changes only the rows measured on it: same poses, conditions and
    noise; with `balls=1` every point is on nest 0, and the truth says which nests."""
    two = simulate_set(6, ("link_geometry",), n_calibration=8, n_validation=6)
    one = simulate_set(6, ("link_geometry",), n_calibration=8, n_validation=6, balls=1)
    assert one.calibration.ball is None and one.setup.smr_offsets_mm is None
    assert "declared_smr_offsets_mm" not in one.truth
    np.testing.assert_allclose(two.truth["declared_smr_offsets_mm"],
                               two.setup.ball_offsets_mm)
    for a, b in ((two.calibration, one.calibration), (two.validation, one.validation)):
        assert np.array_equal(a.q, b.q)
        same = a.ball == 0
        assert np.array_equal(a.xyz[same], b.xyz[same])
        # a nest 100 mm off the flange axis on the other side: far from the first
        assert np.all(np.linalg.norm(a.xyz[~same] - b.xyz[~same], axis=1) > 100.0)
    assert np.array_equal(two.sweeps.xyz, one.sweeps.xyz)
    # the rows on nest 1 are that nest measured: noise-free truth within the noise
    t = two.validation
    exact = two.robot.measure(t.q, noise=False, frame="tracker", ball=t.ball)
    assert np.abs(exact - t.xyz).max() < 0.15
