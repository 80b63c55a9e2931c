"""Tracker registration: rigid fit, outlier trimming and the joint-1 gauge."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rapidfix.exceptions import MeasurementError
from rapidfix.kinematics import load_robot
from rapidfix.measure.registration import move_joint1_offset, register, rigid_fit


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_rigid_fit_recovers_any_transform(seed):
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=seed).as_matrix()
    t = rng.uniform(-4000, 4000, 3)
    p = rng.uniform(-1000, 1000, (20, 3))
    R_fit, t_fit = rigid_fit(p, p @ R.T + t)
    assert np.allclose(R_fit, R, atol=1e-12) and np.allclose(t_fit, t, atol=1e-8)


def test_register_trims_and_reports_outliers():
    rng = np.random.default_rng(5)
    R = Rotation.from_euler("zyx", [130, 0.3, -0.2], degrees=True).as_matrix()
    t = np.array([2500.0, -1200.0, 300.0])
    p = rng.uniform(-1000, 1000, (60, 3))
    measured = p @ R.T + t + rng.normal(0, 0.01, p.shape)
    bad = [4, 17, 33]
    measured[bad] += [[2.0, 0, 0], [0, -1.0, 0.5], [0, 0, 3.0]]
    reg = register(p, measured, rows=np.arange(60) + 2)
    assert reg.outlier_rows.tolist() == [b + 2 for b in bad]
    angle = Rotation.from_matrix(reg.R @ R.T).magnitude()
    assert np.degrees(angle) < 1e-3 and np.linalg.norm(reg.t - t) < 0.05
    assert np.allclose(reg.to_robot(reg.to_tracker(p)), p)
    assert reg.rms_mm < 0.03


def test_register_refuses_points_on_a_line():
    p = np.outer(np.arange(10.0), [1.0, 2.0, 3.0])
    with pytest.raises(MeasurementError, match="line"):
        register(p, p)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(-0.01, 0.01))
def test_joint1_offset_moves_into_the_tracker_pose(seed, c):
    """R·FK(θ + c·e1) + t equals R'·FK(θ) + t' for every pose (forward kinematics as truth)."""
    robot = load_robot("IRB1600-10/1.45")
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.5, 1.5, (8, 6))
    R = Rotation.random(random_state=seed).as_matrix()
    t = rng.uniform(-3000, 3000, 3)
    ball = np.array([60.0, 80.0, 90.0])
    shifted = q.copy()
    shifted[:, 0] += c
    T1, T0 = robot.fk(shifted), robot.fk(q)
    p1 = T1[:, :3, :3] @ ball + T1[:, :3, 3]
    p0 = T0[:, :3, :3] @ ball + T0[:, :3, 3]
    R2, t2 = move_joint1_offset(R, t, c, robot.axis_dirs[0], robot.axis_points[0])
    assert np.allclose(p1 @ R.T + t, p0 @ R2.T + t2, atol=1e-9)
