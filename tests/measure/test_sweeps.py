"""Sweep analysis on virtual cells: tracker pose and actual joint angles against the truth."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rapidfix.exceptions import MeasurementError
from rapidfix.measure.files import Setup, SweepTable, round_joints_deg
from rapidfix.measure.sweeps import analyse_sweeps
from rapidfix.sim import VirtualRobot, simulate_set
from rapidfix.sim.plans import sweep_plan
from rapidfix.sim.tracker import VirtualTracker

Q_WIDE = np.radians(np.random.default_rng(2).uniform(-170, 170, (200, 6)))


def gauge_truth(vr):
    """The truth in the documented gauge, written out here independently of both sides:
    Δθ1(0) = 0; the constant goes into a tracker rotation about the base z axis."""
    c = float(vr.errors.joint(np.zeros((1, 6)))[0, 0])
    rot_z = Rotation.from_rotvec([0.0, 0.0, c]).as_matrix()  # joint 1 is the base z axis
    return c, vr.tracker.R @ rot_z, vr.tracker.t


def true_delta(vr, j, theta, c):
    q = np.zeros((len(theta), 6))
    q[:, j] = theta
    return vr.errors.joint(q)[:, j] - (c if j == 0 else 0.0)


def sweep_set(vr, *, noise, seed=1, **plan):
    p = sweep_plan(vr.robot, vr.smr_offset_mm, **plan)
    q = round_joints_deg(p.q)
    xyz = vr.measure(q, frame="tracker", noise=noise, seed=seed)
    table = SweepTable(p.sweep_joint, q, p.repeat, xyz, np.arange(len(q)) + 2)
    return Setup(vr.robot.name, vr.smr_offset_mm, 0.0125), table


def test_noise_free_sweeps_recover_the_truth_exactly():
    vr = VirtualRobot.create(seed=11)
    setup, table = sweep_set(vr, noise=False)
    an = analyse_sweeps(setup, table, vr.robot)
    c, R, t = gauge_truth(vr)
    assert np.degrees(Rotation.from_matrix(an.registration.R @ R.T).magnitude()) < 1e-6
    assert np.linalg.norm(an.registration.t - t) < 1e-5
    for j, js in enumerate(an.joints):
        assert len(js.theta_cmd) > 15
        err = np.degrees(js.delta - true_delta(vr, j, js.theta_cmd, c))
        assert np.abs(err).max() < 1e-5, j
    assert an.registration.outlier_rows.size == 0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_noisy_cell_registration_angles_and_outliers(seed):
    data = simulate_set(seed, n_outliers=3, n_calibration=5, n_validation=5)
    vr = data.robot
    an = analyse_sweeps(data.setup, data.sweeps, vr.robot)
    c, R, t = gauge_truth(vr)
    # the truth file states the same gauge
    assert np.allclose(data.truth["gauge"]["R"], R, atol=1e-12)
    assert np.degrees(Rotation.from_matrix(an.registration.R @ R.T).magnitude()) < 1e-3
    assert np.linalg.norm(an.registration.t - t) < 0.05
    assert an.registration.outlier_rows.tolist() == data.truth["outlier_rows"]["sweeps.csv"]
    for j, js in enumerate(an.joints):
        err = js.delta - true_delta(vr, j, js.theta_cmd, c)
        # every sample within 6 of its own stated standard errors ...
        assert np.all(np.abs(err) < 6 * js.delta_std + np.radians(2e-4)), j
        if j < 3:  # ... and the long-lever joints to 0.001° RMS
            assert np.degrees(np.sqrt(np.mean(err**2))) < 1e-3, j
        # the repeat spread sees the jitter and the tracker noise, not more
        assert 0.3 * 1e-5 < js.repeatability_rad < 3 * np.radians(0.01), j
    report = json.loads(json.dumps(an.report()))
    assert report["joints"][5]["samples"] == len(an.joints[5].theta_cmd)


def test_other_plans_step_fixed_pose_and_repeats():
    """Nothing assumes the simulator's own step, fixed pose or repeat count."""
    vr = VirtualRobot.create(seed=21)
    setup, table = sweep_set(vr, noise=False, step_deg=7.0, repeats=2,
                             fixed_deg=(10.0, 5.0, -10.0, 30.0, -60.0, 20.0), joints=(0, 2, 4, 5))
    an = analyse_sweeps(setup, table, vr.robot)
    c, R, _ = gauge_truth(vr)
    assert np.degrees(Rotation.from_matrix(an.registration.R @ R.T).magnitude()) < 1e-5
    assert len(an.joints[1].theta_cmd) == 0 and len(an.joints[3].theta_cmd) == 0
    for j in (0, 2, 4, 5):
        js = an.joints[j]
        err = np.degrees(js.delta - true_delta(vr, j, js.theta_cmd, c))
        assert np.abs(err).max() < 1e-4, j
        steps = np.diff(np.degrees(js.theta_cmd)) / 7.0
        assert np.allclose(steps, np.round(steps), atol=1e-6)


def test_ball_on_the_joint6_axis_draws_no_circle():
    vr = VirtualRobot.create(seed=1, smr_offset_mm=(0.0, 0.0, 120.0))
    setup, table = sweep_set(vr, noise=True, step_deg=20.0, repeats=1)
    with pytest.raises(MeasurementError) as info:
        analyse_sweeps(setup, table, vr.robot)
    err = info.value
    first_j6 = int(table.rows[np.flatnonzero(table.sweep_joint == 5)[0]])
    assert "joint 6" in err.message and "circle" in err.message
    assert (err.row, err.column) == (first_j6, "sweep_joint")


def test_sweep_with_too_few_angles_is_refused():
    vr = VirtualRobot.create(seed=1)
    setup, table = sweep_set(vr, noise=True, step_deg=20.0, repeats=1)
    q3 = np.degrees(table.q[:, 2])
    keep = (table.sweep_joint != 2) | ((q3 > -1.0) & (q3 < 25.0))  # joint 3 at 0° and 20° only
    short = SweepTable(table.sweep_joint[keep], table.q[keep], table.repeat[keep],
                       table.xyz[keep], table.rows[keep])
    with pytest.raises(MeasurementError, match=r"joint 3.*at least 3"):
        analyse_sweeps(setup, short, vr.robot)


def test_mislabelled_sweep_is_refused():
    vr = VirtualRobot.create(seed=1)
    setup, table = sweep_set(vr, noise=True, step_deg=20.0, repeats=1)
    wrong = table.sweep_joint.copy()
    wrong[wrong == 1] = 2  # the joint-2 sweep claims to move joint 3 ...
    q = table.q.copy()
    rows = wrong == 2
    q[rows, 1], q[rows, 2] = table.q[rows, 2], table.q[rows, 1]  # ... and says so in j3
    bad = SweepTable(wrong, q, table.repeat, table.xyz, table.rows)
    with pytest.raises(MeasurementError):
        analyse_sweeps(setup, bad, vr.robot)


def test_large_errors_and_any_tracker_orientation():
    """Other cells: joint errors near 1°, a tracker upside down in any orientation."""
    base = VirtualRobot.create(seed=31)
    errors = base.errors
    errors.joint.offset *= 25.0
    errors.joint.amps *= 25.0
    R = Rotation.random(random_state=4).as_matrix()
    tracker = VirtualTracker(R=R, t=np.array([-1500.0, 4200.0, 800.0]))
    vr = VirtualRobot(base.robot, errors, tracker, base.smr_offset_mm)
    assert np.degrees(np.abs(vr.true_joint_error(Q_WIDE)).max()) > 0.5
    setup, table = sweep_set(vr, noise=False, step_deg=10.0, repeats=1)
    an = analyse_sweeps(setup, table, vr.robot)
    c, R_true, _ = gauge_truth(vr)
    assert np.degrees(Rotation.from_matrix(an.registration.R @ R_true.T).magnitude()) < 1e-6
    for j, js in enumerate(an.joints):
        err = np.degrees(js.delta - true_delta(vr, j, js.theta_cmd, c))
        assert np.abs(err).max() < 1e-5, j
        assert np.all(np.isnan(js.repeat_std))  # one repeat: no spread to report


def test_written_set_round_trip_names_the_outlier_rows(tmp_path):
    """From the files on disk: the outliers are named by their line in sweeps.csv."""
    from rapidfix.measure.files import read_setup, read_sweeps
    from rapidfix.sim import simulate_cell

    out = simulate_cell(tmp_path / "set", seed=7, step_deg=10.0, repeats=2, n_outliers=3,
                        n_calibration=5, n_validation=5)
    truth = json.loads((out / "truth.json").read_text())
    setup, sweeps = read_setup(out / "setup.toml"), read_sweeps(out / "sweeps.csv")
    an = analyse_sweeps(setup, sweeps, VirtualRobot.from_truth(truth).robot)
    rows = truth["outlier_rows"]["sweeps.csv"]
    assert an.registration.outlier_rows.tolist() == rows
    lines = (out / "sweeps.csv").read_text().splitlines()
    clean = np.loadtxt(lines[1:], delimiter=",")
    measured = clean[np.array(rows) - 2, 8:11]  # file row r is line r (header = row 1)
    assert np.allclose(measured, sweeps.xyz[np.isin(sweeps.rows, rows)])
    assert np.allclose(truth["gauge"]["R"], an.registration.R, atol=2e-5)


def _shuffled_within_runs(table, seed):
    """The same sweeps with the samples of every run (one joint, one repeat) in random order."""
    run = np.flatnonzero(np.diff(table.sweep_joint) | np.diff(table.repeat)) + 1
    rng = np.random.default_rng(seed)
    order = np.concatenate([rng.permutation(r) for r in np.split(np.arange(len(table.q)), run)])
    return order


@pytest.mark.parametrize("shuffle", [False, True], ids=["plan-order", "any-order"])
def test_backlash_is_separated_from_the_joint_curves(shuffle):
    vr = VirtualRobot.create(seed=11, effects=("backlash",))
    p = sweep_plan(vr.robot, vr.smr_offset_mm)
    order = _shuffled_within_runs(p, 5) if shuffle else np.arange(len(p.q))
    q = round_joints_deg(p.q[order])
    # executed in row order: the simulator takes each joint's direction from the rows
    xyz = vr.measure(q, frame="tracker", noise=False)
    table = SweepTable(p.sweep_joint[order], q, p.repeat[order], xyz, np.arange(len(q)) + 2)
    an = analyse_sweeps(Setup(vr.robot.name, vr.smr_offset_mm, 0.0125), table, vr.robot)
    c, _, _ = gauge_truth(vr)
    for j, js in enumerate(an.joints):  # the curves midway between the two directions
        err = np.degrees(js.delta - true_delta(vr, j, js.theta_cmd, c))
        assert np.abs(err).max() < 1e-5, j
    # the play of joints 1-3 (the others have none), from below minus from above
    np.testing.assert_allclose(np.degrees(an.play_rad), np.degrees(vr.errors.backlash),
                               atol=1e-5)
    assert an.rms_mm < 1e-4
    report = json.loads(json.dumps(an.report()))
    assert report["backlash_play_deg"] == pytest.approx(np.degrees(an.play_rad).tolist())


def test_without_backlash_the_play_is_noise():
    data = simulate_set(4, n_calibration=5, n_validation=5)
    an = analyse_sweeps(data.setup, data.sweeps, data.robot.robot)
    seen = np.isfinite(an.play_std_rad)
    assert seen[:3].all()
    # within 4 of its standard errors of zero, and small against any real play (≥ 0.01°)
    assert np.all(np.abs(an.play_rad[seen]) < 4 * an.play_std_rad[seen])
    assert np.degrees(np.abs(an.play_rad[:3])).max() < 0.003
