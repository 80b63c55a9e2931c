"""`rapidfix plan`: the program parses with our grammar, the poses obey every rule."""

from __future__ import annotations

import numpy as np
import pytest

from rapidfix.campaign.envelope import Box, Envelope
from rapidfix.campaign.plan import PlanSettings, make_plan, write_plan
from rapidfix.campaign.pose_table import read_pose_table
from rapidfix.campaign.poses import ball_positions, iso_points
from rapidfix.campaign.program import ProgramOptions
from rapidfix.campaign.sight import TrackerView
from rapidfix.cli import main
from rapidfix.exceptions import RapidfixError
from rapidfix.kinematics import load_robot
from rapidfix.postprocess.execute import commanded_motions
from rapidfix.rapid import parse_program

ROBOT = load_robot("IRB1600-10/1.45")
SMR = np.array([60.0, 80.0, 90.0])


def small(**kw) -> PlanSettings:
    base = dict(sweep_joints=(2, 5), repeats=2, step_deg=10.0, n_calibration=12,
                n_validation=8, seed=1)
    base.update(kw)
    return PlanSettings(**base)


def test_sweeps_follow_the_protocol_and_the_program_runs_them_in_table_order():
    plan = make_plan(ROBOT, small(program=ProgramOptions(trigger="tpwrite")))
    t = plan.table
    sw = t.set_name == "sweep"
    for j in (2, 5):
        rows = sw & (t.ints["sweep_joint"] == j)
        q = np.degrees(t.q[rows])
        others = np.delete(q, j - 1, axis=1)
        assert np.allclose(others, others[0])  # the other joints are held
        first = q[t.ints["repeat"][rows] == 1, j - 1]
        assert np.allclose(np.diff(first), 10.0)  # 10° steps, ascending
        assert np.array_equal(q[t.ints["repeat"][rows] == 2, j - 1], first)
    program = parse_program(plan.program, "measure.mod")  # our own grammar
    ex = commanded_motions(program, ROBOT)
    fine = [program.motions[m].zone.text == "fine" for m in ex.motion]
    q_fine = ex.q_cmd[np.array(fine)]
    assert np.allclose(q_fine, t.q, atol=1e-5)  # one fine stop per table row, same order
    assert plan.program.count("WaitTime nRfSettle;") == len(t)
    tp = [line.strip() for line in plan.program.splitlines()
          if line.strip().startswith('TPWrite "')]
    ids = [line.split('"')[1] for line in tp if not line.split('"')[1].startswith("rapidfix:")]
    assert ids == list(t.point_id)


def test_points_stay_in_the_box_above_the_floor_outside_keep_outs_and_in_view():
    keep = Box(np.array([500.0, -100.0, 0.0]), np.array([800.0, 100.0, 600.0]))
    env = Envelope(box=Box(np.array([300.0, -600.0, 300.0]), np.array([1100.0, 600.0, 1300.0])),
                   floor_z_mm=250.0, keep_out=(keep,))
    view = TrackerView(np.array([3000.0, 500.0, 900.0]), SMR, 45.0)
    plan = make_plan(ROBOT, small(envelope=env, tracker=view, payloads_kg=(0.0, 5.0)))
    t = plan.table
    ball = ball_positions(ROBOT, t.q, SMR)
    pts = np.isin(t.set_name, ("calibration", "validation"))
    assert np.all(env.box.contains(ball[pts]))
    assert np.all(ball[:, 2] >= 250.0)
    assert not np.any(keep.contains(ball))
    assert np.all(view.angles_deg(ROBOT, t.q, SMR) <= 45.0)
    assert np.all(ROBOT.within_limits(t.q))
    assert np.all(np.abs(np.degrees(t.q[pts, 4])) >= 15.0)
    # payloads dealt in turn, grouped, with one Stop per change
    assert set(t.payload_kg[pts]) == {0.0, 5.0}
    assert plan.program.count("Stop;") == int(t.ints["pause_before"].sum()) >= 1
    # points spread: each one's nearest neighbour is far on the scale of the box
    cal = ball[t.set_name == "calibration"]
    d = np.linalg.norm(cal[:, None] - cal[None], axis=2) + np.eye(len(cal)) * 1e9
    assert np.median(d.min(axis=1)) > 150.0


def test_approach_same_side_makes_every_joint_arrive_moving_up():
    plan = make_plan(ROBOT, small())
    ex = commanded_motions(parse_program(plan.program, "m.mod"), ROBOT)
    q = ex.q_cmd
    step = np.diff(np.vstack([np.zeros(6), q]), axis=0)
    fine = np.array([parse_program(plan.program, "m.mod").motions[m].zone.text == "fine"
                     for m in ex.motion])
    last = np.zeros(6)
    arrivals = []
    for k in range(len(q)):  # direction each joint last moved in, per fine stop
        last = np.where(np.abs(step[k]) > 1e-9, np.sign(step[k]), last)
        if fine[k]:
            arrivals.append(last.copy())
    arr = np.array(arrivals)
    moved = arr != 0
    joint_at_limit = np.isclose(plan.table.q, ROBOT.limits[:, 0])
    assert np.all((arr == 1) | ~moved | joint_at_limit)


def test_approach_both_sides_measures_each_point_from_above_and_below():
    plan = make_plan(ROBOT, small(approach="both", sweep_joints=(2,)))
    t = plan.table
    cal = t.set_name == "calibration"
    ids = t.point_id[cal]
    assert all(pid.endswith("ud"[k % 2]) for k, pid in enumerate(ids))
    down = np.char.endswith(ids.astype(str), "d")
    assert np.all(t.ints["approach"][cal][down] == -1)  # re-approached from above
    assert np.all(t.ints["approach_joints"][cal][down] == 63)  # every joint turned
    assert np.all(t.ints["approach"][cal][~down] >= 0)
    sw = t.set_name == "sweep"
    down = t.ints["repeat"][sw] == 2
    assert np.all(np.diff(np.degrees(t.q[sw][down, 1])) < 0)


def test_iso_cube_poses_are_on_the_diagonal_plane_and_reached_on_their_confdata():
    plan = make_plan(ROBOT, small(sweep_joints=(), iso=True, iso_cycles=3))
    cube = plan.cube
    p = iso_points(cube.centre_mm, cube.side_mm, cube.axes)
    L = cube.side_mm * np.sqrt(3)
    assert np.allclose(np.linalg.norm(p[3] - p[1]), 0.8 * L)  # 10 % in from each corner
    assert np.allclose(p[0], cube.centre_mm)
    assert np.allclose(ball_positions(ROBOT, cube.q, SMR), p, atol=1e-6)
    iso = plan.table.set_name == "iso9283"
    assert list(plan.table.ints["iso_pose"][iso][:5]) == [1, 5, 4, 3, 2]
    assert iso.sum() == 15
    ex = commanded_motions(parse_program(plan.program, "m.mod"), ROBOT)
    assert np.allclose(ex.q_cmd[-1], cube.q[1], atol=1e-6)  # last pose P2, via its robtarget


def test_unreachable_iso_cube_and_hidden_points_are_refused():
    with pytest.raises(RapidfixError, match="P"):
        make_plan(ROBOT, small(sweep_joints=(), iso=True, iso_side_mm=3000.0))
    view = TrackerView(np.array([0.0, 0.0, 5000.0]), np.array([0.0, 0.0, -1.0]), 5.0)
    with pytest.raises(RapidfixError):
        make_plan(ROBOT, small(tracker=view))


def test_command_writes_program_table_and_plan(tmp_path, capsys):
    out = tmp_path / "plan"
    assert main(["plan", str(out), "--joints", "3", "--step", "10", "--repeats", "1",
                 "--calibration-points", "5", "--validation-points", "5",
                 "--trigger", "pulse", "--signal", "doMeas"]) == 0
    text = capsys.readouterr().out
    assert "estimated run time" in text and "measured poses" in text
    program = (out / "measure.mod").read_text()
    assert "PulseDO \\PLength:=0.1, doMeas;" in program
    table = read_pose_table(out / "poses.csv")
    assert np.all(np.diff(table.times["t_trigger_s"]) > 0)
    assert main(["plan", str(out)]) == 1  # never overwrites without --force
    assert main(["plan", str(tmp_path / "p2"), "--box", "1,2,3"]) == 1
    assert "six numbers" in capsys.readouterr().err


def test_write_plan_round_trips_the_table(tmp_path):
    plan = make_plan(ROBOT, small(sweep_joints=(6,)))
    paths = write_plan(plan, tmp_path)
    table = read_pose_table(paths["poses"])
    assert list(table.point_id) == list(plan.table.point_id)
    assert np.allclose(table.q, plan.table.q, atol=1e-8)


def test_box_in_a_work_object_frame_and_the_cube_it_holds():
    from rapidfix.kinematics.frames import pose

    # a work object turned 30° about z, 700 mm in front of the robot
    c, s = np.cos(np.radians(15)), np.sin(np.radians(15))
    frame = pose([700.0, 100.0, 600.0], [c, 0.0, 0.0, s])
    box = Box(np.array([-200.0, -250.0, 0.0]), np.array([200.0, 250.0, 400.0]))
    env = Envelope(box=box, frame=frame)
    plan = make_plan(ROBOT, small(sweep_joints=(), envelope=env, iso=True, iso_cycles=2))
    t = plan.table
    pts = np.isin(t.set_name, ("calibration", "validation"))
    local = env.to_frame(ball_positions(ROBOT, t.q[pts], SMR))
    assert np.all(box.contains(local))
    assert np.ptp(local[:, 0]) > 250 and np.ptp(local[:, 1]) > 300  # they fill the box
    cube = plan.cube
    assert cube.side_mm <= 400.0 + 1e-9  # the box's smallest side, shrunk only if unreachable
    assert np.allclose(cube.centre_mm, frame[:3, :3] @ [0.0, 0.0, 200.0] + frame[:3, 3])
    corners_local = env.to_frame(cube.points_mm)
    assert np.all(box.contains(corners_local))


def test_simulate_needs_an_output_folder_without_a_program(capsys):
    assert main(["simulate"]) == 1
    assert "give OUT_DIR" in capsys.readouterr().err
